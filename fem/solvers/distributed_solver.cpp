// Distributed solves over MPI ranks (distributed.hpp): rank 0 partitions, renumbers and sends each
// rank its rows; every rank holds its part of a MATMPIAIJ and of the KSP; rank 0 gets the
// solution back.
// <mpi.h> through petscsys.h, which skips the MPI C++ bindings (OMPI_SKIP_MPICXX).
#include <malloc.h>
#include <petscksp.h>
#include <sys/resource.h>

#include <Eigen/QR>
#include <algorithm>
#include <chrono>
#include <climits>
#include <numeric>
#include <sstream>
#include <thread>

#include "fem/solvers/distributed.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/timer.hpp"

namespace curvefem::fem::distributed {
namespace {

enum Command : int { k_stop = 0, k_solve = 1, k_memory = 2 };

bool g_started = false;
int g_rank = 0, g_size = 1;

MPI_Comm comm() { return PETSC_COMM_WORLD; }

void check(PetscErrorCode code, const char* what) {
  if (code != 0)
    throw SolverError(std::string("PETSc error in ") + what + " (code " +
                      std::to_string(static_cast<int>(code)) + ", rank " + std::to_string(g_rank) +
                      ")");
}

/// Completes a request by polling: a blocking MPI call spins on its core (OpenMPI), which the
/// threads of rank 0 on the same machine need.
void wait(MPI_Request& request) {
  int done = 0;
  for (;;) {
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (done) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

/// Rank 0's command to every rank (non-blocking on both sides: a non-blocking collective only
/// matches a non-blocking one).
int broadcast_command(int command) {
  MPI_Request request;
  MPI_Ibcast(&command, 1, MPI_INT, 0, comm(), &request);
  wait(request);
  return command;
}

template <class T>
void send_vector(const std::vector<T>& v, int to) {
  const long long count = static_cast<long long>(v.size());
  if (count * static_cast<long long>(sizeof(T)) > INT_MAX)
    throw SolverError("distributed solve: a message of " + std::to_string(count * sizeof(T)) +
                      " bytes to rank " + std::to_string(to) + " (at most 2 GiB)");
  MPI_Send(&count, 1, MPI_LONG_LONG, to, 0, comm());
  MPI_Send(v.data(), static_cast<int>(count * sizeof(T)), MPI_BYTE, to, 0, comm());
}

template <class T>
std::vector<T> receive_vector() {
  long long count = 0;
  MPI_Request request;
  MPI_Irecv(&count, 1, MPI_LONG_LONG, 0, 0, comm(), &request);
  wait(request);
  std::vector<T> v(static_cast<std::size_t>(count));
  MPI_Irecv(v.data(), static_cast<int>(count * sizeof(T)), MPI_BYTE, 0, 0, comm(), &request);
  wait(request);
  return v;
}

/// Frees v's storage (`v = {}` keeps the capacity).
template <class T>
void release(std::vector<T>& v) {
  std::vector<T>().swap(v);
}

/// What every rank needs to know about a solve (rank 0 broadcasts it).
struct Header {
  long long n = 0;            // global rows
  long long graph_nodes = 0;  // vertices of the graph partitioned (groups of nodes)
  int block_size = 1;
  int kernel_columns = 0;  // exact null space (singular A)
  int vector_columns = 0;  // explicit near-nullspace vectors
  int coordinates = 0;     // 1: rigid-body modes from the owned nodes' coordinates
  int direct = 0;          // 1: MUMPS Cholesky
  int preconditioner = 0;  // Preconditioner as an int: 0 gamg, 1 hypre, 2 ml
  int parallel_ptap = 0;   // ParallelPtap as an int: 0 automatic, 1 allatonce, 2 scalable
  int max_iterations = 0;
  double rtol = 0;
  // RankBalance::memory: the solver's estimated memory over all ranks (MiB), and the part of
  // rank 0's heap that the solve frees before its set-up (the whole matrix handed over).
  int balance_memory = 0;
  double solve_mb = 0, rank0_transient_mb = 0;
};

/// The parallel Galerkin product the header asks for: allatonce, or scalable (ParallelPtap).
bool wants_allatonce(const Header& h) {
  const bool with_modes = h.coordinates || h.vector_columns > 0;
  return h.parallel_ptap == static_cast<int>(ParallelPtap::allatonce) ||
         (h.parallel_ptap == static_cast<int>(ParallelPtap::automatic) && with_modes);
}

/// Bytes of a distributed CG + GAMG solve's memory per nonzero of its matrix, over all ranks: the
/// matrix's CSR (12 bytes an entry) and what GAMG builds on it (the graph, the prolongators, the
/// coarse operators, the Galerkin products' buffers). Measured on 2 ranks with equal rows, from
/// the peak resident set of rank 1 (which holds nothing else) less its resident set before the
/// solve (benchmarks/results/mpi.md, 2026-12-06): P2 Poisson, 1.03M rows, 25.8M nonzeros: 54
/// (allatonce), 59 (scalable); P2 elasticity with the rigid-body modes, 1.07M rows, 87.8M
/// nonzeros: 30 (allatonce), 61 (scalable). hypre and ML are not measured (the scalable figure).
double solve_bytes_per_nonzero(const Header& h) {
  const bool gamg = h.preconditioner == static_cast<int>(Preconditioner::gamg);
  if (!gamg || !wants_allatonce(h)) return 60;
  return h.block_size > 1 ? 30 : 54;
}

/// The heap this process is using (MiB): glibc's allocated chunks and its mmapped blocks, not
/// what it freed and keeps for later allocations (which the resident set still counts).
double heap_in_use_mb() {
  const struct mallinfo2 m = mallinfo2();
  return static_cast<double>(m.uordblks + m.hblkhd) / (1024.0 * 1024.0);
}

/// One rank's rows in the new numbering: CSR (global column indices), and its slices of the
/// right-hand side, the coordinates (3 per node), the kernel and the vectors (column-major,
/// #local rows per column).
struct LocalPart {
  std::vector<PetscInt> row_ptr, cols;
  std::vector<PetscScalar> values;
  std::vector<double> b, coordinates, kernel, vectors;
};

void send_part(const LocalPart& p, int to) {
  send_vector(p.row_ptr, to);
  send_vector(p.cols, to);
  send_vector(p.values, to);
  send_vector(p.b, to);
  send_vector(p.coordinates, to);
  send_vector(p.kernel, to);
  send_vector(p.vectors, to);
}

LocalPart receive_part() {
  LocalPart p;
  p.row_ptr = receive_vector<PetscInt>();
  p.cols = receive_vector<PetscInt>();
  p.values = receive_vector<PetscScalar>();
  p.b = receive_vector<double>();
  p.coordinates = receive_vector<double>();
  p.kernel = receive_vector<double>();
  p.vectors = receive_vector<double>();
  return p;
}

/// Collective: the owner of every node of the graph held by rank 0 (CSR without the diagonal;
/// empty on the other ranks). Only rank 0's result is filled. With h.balance_memory the ranks'
/// shares of the nodes follow memory_balanced_shares (PT-Scotch's partition weights), from every
/// rank's heap in use now; `shares` and `heap_mb` then say what was asked (else empty).
std::vector<int> partition(const std::vector<int>& ptr, const std::vector<int>& adj,
                           const Header& h, std::string& partitioner, std::vector<double>& shares,
                           std::vector<double>& heap_mb) {
  const long long nodes = h.graph_nodes;
  shares.clear();
  heap_mb.clear();
  if (h.balance_memory && g_size > 1) {
    double mine = heap_in_use_mb();
    if (g_rank == 0) mine = std::max(0.0, mine - h.rank0_transient_mb);
    heap_mb.assign(std::size_t(g_size), 0.0);
    MPI_Allgather(&mine, 1, MPI_DOUBLE, heap_mb.data(), 1, MPI_DOUBLE, comm());
    shares = memory_balanced_shares(heap_mb, h.solve_mb, 0.2 / g_size);
  }
  const PetscInt local = g_rank == 0 ? static_cast<PetscInt>(nodes) : 0;
  const std::size_t nnz = g_rank == 0 ? adj.size() : 0;
  PetscInt *ia = nullptr, *ja = nullptr;  // owned by the MPIAdj matrix
  check(PetscMalloc1(local + 1, &ia), "PetscMalloc1");
  check(PetscMalloc1(std::max<std::size_t>(nnz, 1), &ja), "PetscMalloc1");
  ia[0] = 0;
  for (PetscInt i = 0; i < local; ++i) ia[i + 1] = ptr[std::size_t(i) + 1];
  for (std::size_t k = 0; k < nnz; ++k) ja[k] = adj[k];
  Mat graph;
  check(MatCreateMPIAdj(comm(), local, static_cast<PetscInt>(nodes), ia, ja, nullptr, &graph),
        "MatCreateMPIAdj");
  MatPartitioning part;
  check(MatPartitioningCreate(comm(), &part), "MatPartitioningCreate");
  check(MatPartitioningSetAdjacency(part, graph), "MatPartitioningSetAdjacency");
  check(MatPartitioningSetNParts(part, g_size), "MatPartitioningSetNParts");
  std::vector<int> owner;
  IS is = nullptr;
  PetscErrorCode err = MatPartitioningSetType(part, MATPARTITIONINGPTSCOTCH);
  if (!err && !shares.empty()) {
    PetscReal* weights = nullptr;  // freed by PETSc
    err = PetscMalloc1(g_size, &weights);
    if (!err) {
      for (int p = 0; p < g_size; ++p) weights[p] = shares[std::size_t(p)];
      err = MatPartitioningSetPartitionWeights(part, weights);
    }
  }
  if (!err) err = MatPartitioningApply(part, &is);
  if (!err) {
    partitioner = "ptscotch";
    if (g_rank == 0) {
      const PetscInt* idx;
      check(ISGetIndices(is, &idx), "ISGetIndices");
      owner.assign(idx, idx + local);
      check(ISRestoreIndices(is, &idx), "ISRestoreIndices");
    }
    ISDestroy(&is);
  } else {
    partitioner = "contiguous";
    if (g_rank == 0) {
      log::warn("distributed solve: PT-Scotch partitioning failed (PETSc code ", int(err),
                "); the nodes are split into contiguous ranges");
      owner.resize(std::size_t(nodes));
      for (long long i = 0; i < nodes; ++i) owner[std::size_t(i)] = int(i * g_size / nodes);
      if (!shares.empty()) {  // the same shares, as consecutive ranges
        double end = 0;
        long long i = 0;
        for (int p = 0; p < g_size; ++p) {
          end += shares[std::size_t(p)];
          const long long last = p + 1 == g_size ? nodes : std::llround(end * double(nodes));
          for (; i < last; ++i) owner[std::size_t(i)] = p;
        }
      }
    }
  }
  MatPartitioningDestroy(&part);
  MatDestroy(&graph);
  return owner;
}

/// A PETSc null space from the columns of the local slices (orthonormal globally).
MatNullSpace null_space_from(const std::vector<double>& slices, int columns, PetscInt m) {
  std::vector<Vec> vecs(static_cast<std::size_t>(columns));
  for (int k = 0; k < columns; ++k) {
    check(VecCreateMPI(comm(), m, PETSC_DETERMINE, &vecs[std::size_t(k)]), "VecCreateMPI");
    PetscScalar* v;
    check(VecGetArray(vecs[std::size_t(k)], &v), "VecGetArray");
    for (PetscInt i = 0; i < m; ++i)
      v[i] = slices[std::size_t(k) * std::size_t(m) + std::size_t(i)];
    check(VecRestoreArray(vecs[std::size_t(k)], &v), "VecRestoreArray");
  }
  MatNullSpace space;
  check(MatNullSpaceCreate(comm(), PETSC_FALSE, columns, vecs.data(), &space),
        "MatNullSpaceCreate");
  for (Vec& v : vecs) VecDestroy(&v);
  return space;
}

PetscErrorCode record_residual(KSP, PetscInt, PetscReal norm, void* ctx) {
  static_cast<std::vector<double>*>(ctx)->push_back(static_cast<double>(norm));
  return 0;
}

struct SolveOutcome {
  std::vector<double> x;         // rank 0: the whole solution in the new numbering
  double relative_residual = 0;  // ‖b − M x‖ / ‖b‖ on the distributed matrix
  int iterations = 0, reason = 0;
  std::vector<double> history;
  double setup_s = 0, solve_s = 0;
  std::string near_nullspace = "default";
  std::string parallel_ptap;  // GAMG: the -matptap_via of its set-up
};

/// Collective: every rank solves with its part (its CSR is released once PETSc has copied it).
SolveOutcome solve_part(const Header& h, LocalPart& part) {
  SolveOutcome out;
  if (h.direct) out.near_nullspace = "";
  Stopwatch watch;
  const PetscInt m = static_cast<PetscInt>(part.b.size());
  const PetscInt n = static_cast<PetscInt>(h.n);
  Mat M;
  check(MatCreate(comm(), &M), "MatCreate");
  check(MatSetSizes(M, m, m, n, n), "MatSetSizes");
  check(MatSetBlockSize(M, h.block_size), "MatSetBlockSize");
  check(MatSetType(M, MATMPIAIJ), "MatSetType");
  check(MatMPIAIJSetPreallocationCSR(M, part.row_ptr.data(), part.cols.data(), part.values.data()),
        "MatMPIAIJSetPreallocationCSR");
  release(part.row_ptr);
  release(part.cols);
  release(part.values);
  check(MatSetOption(M, MAT_SYMMETRIC, PETSC_TRUE), "MatSetOption");
  if (h.kernel_columns == 0) check(MatSetOption(M, MAT_SPD, PETSC_TRUE), "MatSetOption");
  if (h.coordinates) {
    Vec xyz;
    check(VecCreateMPI(comm(), m, n, &xyz), "VecCreateMPI");
    check(VecSetBlockSize(xyz, 3), "VecSetBlockSize");
    PetscScalar* v;
    check(VecGetArray(xyz, &v), "VecGetArray");
    std::copy(part.coordinates.begin(), part.coordinates.end(), v);
    check(VecRestoreArray(xyz, &v), "VecRestoreArray");
    MatNullSpace near;
    check(MatNullSpaceCreateRigidBody(xyz, &near), "MatNullSpaceCreateRigidBody");
    check(MatSetNearNullSpace(M, near), "MatSetNearNullSpace");
    MatNullSpaceDestroy(&near);
    VecDestroy(&xyz);
    out.near_nullspace = "rigid-body modes";
  } else if (h.vector_columns > 0) {
    MatNullSpace near = null_space_from(part.vectors, h.vector_columns, m);
    check(MatSetNearNullSpace(M, near), "MatSetNearNullSpace");
    MatNullSpaceDestroy(&near);
    out.near_nullspace = "vectors";
  }
  if (h.kernel_columns > 0) {
    MatNullSpace kernel = null_space_from(part.kernel, h.kernel_columns, m);
    check(MatSetNullSpace(M, kernel), "MatSetNullSpace");
    MatNullSpaceDestroy(&kernel);
  }
  KSP ksp;
  PC pc;
  check(KSPCreate(comm(), &ksp), "KSPCreate");
  check(KSPSetOperators(ksp, M, M), "KSPSetOperators");
  check(KSPGetPC(ksp, &pc), "KSPGetPC");
  if (h.direct) {
    check(KSPSetType(ksp, KSPPREONLY), "KSPSetType");
    check(PCSetType(pc, PCCHOLESKY), "PCSetType");
    check(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS), "PCFactorSetMatSolverType");
  } else {
    check(KSPSetType(ksp, KSPCG), "KSPSetType");
    if (h.preconditioner == static_cast<int>(Preconditioner::hypre)) {
      check(PCSetType(pc, PCHYPRE), "PCSetType");
      check(PCHYPRESetType(pc, "boomeramg"), "PCHYPRESetType");
    } else if (h.preconditioner == static_cast<int>(Preconditioner::ml)) {
      check(PCSetType(pc, PCML), "PCSetType");
    } else {
      check(PCSetType(pc, PCGAMG), "PCSetType");
    }
    check(KSPSetTolerances(ksp, h.rtol, PETSC_DEFAULT, PETSC_DEFAULT, h.max_iterations),
          "KSPSetTolerances");
  }
  check(KSPSetFromOptions(ksp), "KSPSetFromOptions");
  // GAMG's parallel Galerkin products (PtAP, in its coarsening and its coarse operators):
  // "scalable" is PETSc's default; "allatonce" holds far less memory per rank
  // (benchmarks/results/mpi.md). Set for this set-up only, unless $PETSC_OPTIONS chose already.
  PetscBool user_ptap = PETSC_FALSE;
  check(PetscOptionsHasName(nullptr, nullptr, "-matptap_via", &user_ptap), "PetscOptionsHasName");
  const bool set_ptap = !h.direct && !user_ptap;
  const bool allatonce = wants_allatonce(h);
  if (set_ptap)
    check(PetscOptionsSetValue(nullptr, "-matptap_via", allatonce ? "allatonce" : "scalable"),
          "PetscOptionsSetValue");
  if (set_ptap && g_rank == 0 && h.preconditioner == static_cast<int>(Preconditioner::gamg))
    log::info("GAMG over ", g_size, " ranks: parallel Galerkin products '",
              allatonce ? "allatonce" : "scalable", "' (",
              allatonce ? "the least memory per rank; \"solver\": {\"parallel_ptap\": "
                          "\"scalable\"} sets up faster"
                        : "PETSc's default; \"allatonce\" holds less memory per rank",
              ")");
  if (!h.direct && h.preconditioner == static_cast<int>(Preconditioner::gamg)) {
    char via[64] = "";
    PetscBool found = PETSC_FALSE;
    check(PetscOptionsGetString(nullptr, nullptr, "-matptap_via", via, sizeof via, &found),
          "PetscOptionsGetString");
    out.parallel_ptap = found ? via : "scalable";
  }
  const PetscErrorCode setup = KSPSetUp(ksp);
  if (set_ptap) PetscOptionsClearValue(nullptr, "-matptap_via");
  check(setup, "KSPSetUp");
  out.setup_s = watch.seconds();
  watch.reset();
  Vec x, b;
  check(MatCreateVecs(M, &x, &b), "MatCreateVecs");
  PetscScalar* bv;
  check(VecGetArray(b, &bv), "VecGetArray");
  std::copy(part.b.begin(), part.b.end(), bv);
  check(VecRestoreArray(b, &bv), "VecRestoreArray");
  check(KSPMonitorSet(ksp, record_residual, &out.history, nullptr), "KSPMonitorSet");
  check(KSPSolve(ksp, b, x), "KSPSolve");
  out.solve_s = watch.seconds();
  KSPConvergedReason reason;
  PetscInt its;
  check(KSPGetConvergedReason(ksp, &reason), "KSPGetConvergedReason");
  check(KSPGetIterationNumber(ksp, &its), "KSPGetIterationNumber");
  out.reason = static_cast<int>(reason);
  out.iterations = static_cast<int>(its);
  {  // the true residual, on every rank's rows (collective)
    Vec r;
    check(VecDuplicate(b, &r), "VecDuplicate");
    check(MatMult(M, x, r), "MatMult");
    check(VecAYPX(r, -1.0, b), "VecAYPX");  // r = b − M x
    PetscReal rn = 0, bn = 0;
    check(VecNorm(r, NORM_2, &rn), "VecNorm");
    check(VecNorm(b, NORM_2, &bn), "VecNorm");
    out.relative_residual = static_cast<double>(rn / (bn > 0 ? bn : 1.0));
    VecDestroy(&r);
  }
  VecScatter to_zero;
  Vec all;
  check(VecScatterCreateToZero(x, &to_zero, &all), "VecScatterCreateToZero");
  check(VecScatterBegin(to_zero, x, all, INSERT_VALUES, SCATTER_FORWARD), "VecScatterBegin");
  check(VecScatterEnd(to_zero, x, all, INSERT_VALUES, SCATTER_FORWARD), "VecScatterEnd");
  if (g_rank == 0) {
    const PetscScalar* xs;
    check(VecGetArrayRead(all, &xs), "VecGetArrayRead");
    out.x.assign(xs, xs + n);
    check(VecRestoreArrayRead(all, &xs), "VecRestoreArrayRead");
  }
  VecScatterDestroy(&to_zero);
  VecDestroy(&all);
  VecDestroy(&x);
  VecDestroy(&b);
  KSPDestroy(&ksp);
  MatDestroy(&M);
  return out;
}

/// Rank != 0's side of solve().
void serve_solve() {
  Header h;
  MPI_Request request;
  MPI_Ibcast(&h, sizeof(Header), MPI_BYTE, 0, comm(), &request);
  wait(request);
  std::string partitioner;
  std::vector<double> shares, heap_mb;
  partition({}, {}, h, partitioner, shares, heap_mb);
  LocalPart part = receive_part();
  solve_part(h, part);
}

void serve_memory() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  double mb = static_cast<double>(usage.ru_maxrss) / 1024.0;  // kB on Linux
  MPI_Gather(&mb, 1, MPI_DOUBLE, nullptr, 1, MPI_DOUBLE, 0, comm());
}

}  // namespace

int start() {
  check(PetscInitializeNoArguments(), "PetscInitialize");
  MPI_Comm_rank(PETSC_COMM_WORLD, &g_rank);
  MPI_Comm_size(PETSC_COMM_WORLD, &g_size);
  g_started = true;
  return g_rank;
}

void finish() {
  if (!g_started) return;
  g_started = false;
  PetscFinalize();
}

bool active() { return g_started && g_size > 1; }
int rank() { return g_rank; }
int size() { return g_size; }

void serve() {
  for (;;) {
    const int command = broadcast_command(k_stop);
    if (command == k_stop) return;
    try {
      if (command == k_solve) serve_solve();
      if (command == k_memory) serve_memory();
    } catch (const std::exception& e) {
      log::error("rank ", g_rank, ": ", e.what());
      MPI_Abort(comm(), 3);
    }
  }
}

void release_workers() {
  if (active() && g_rank == 0) broadcast_command(k_stop);
}

void abort(int code) {
  MPI_Abort(comm(), code);
  std::abort();  // not reached
}

std::vector<double> peak_rss_mb_per_rank() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  double mb = static_cast<double>(usage.ru_maxrss) / 1024.0;
  if (!active()) return {mb};
  broadcast_command(k_memory);
  std::vector<double> all(std::size_t(g_size), 0.0);
  MPI_Gather(&mb, 1, MPI_DOUBLE, all.data(), 1, MPI_DOUBLE, 0, comm());
  return all;
}

std::vector<double> memory_balanced_shares(const std::vector<double>& heap_mb, double solve_mb,
                                           double min_share) {
  const std::size_t n = heap_mb.size();
  if (n == 0) return {};
  std::vector<double> share(n, 1.0 / double(n));
  if (!(solve_mb > 0) || n == 1) return share;
  min_share = std::clamp(min_share, 0.0, 1.0 / double(n));
  // Every rank gets at least min_share; the rest fills the ranks from the lowest heap up to a
  // common level L: share_p = min_share + max(0, L − heap_p − min_share·solve) / solve.
  std::vector<double> base(n);
  for (std::size_t p = 0; p < n; ++p) base[p] = heap_mb[p] + min_share * solve_mb;
  const double rest = solve_mb * (1.0 - min_share * double(n));
  std::vector<double> sorted = base;
  std::sort(sorted.begin(), sorted.end());
  // The level: the first k lowest ranks are filled when L ≥ sorted[k-1].
  double level = sorted.back() + rest / double(n);
  double sum = 0;
  for (std::size_t k = 1; k <= n; ++k) {
    sum += sorted[k - 1];
    const double L = (rest + sum) / double(k);
    if (k == n || L <= sorted[k]) {
      level = L;
      break;
    }
  }
  for (std::size_t p = 0; p < n; ++p)
    share[p] = min_share + std::max(0.0, level - base[p]) / solve_mb;
  const double total = std::accumulate(share.begin(), share.end(), 0.0);
  for (double& x : share) x /= total;
  return share;
}

Renumbering renumber_by_owner(const std::vector<int>& owner, int ranks) {
  Renumbering r;
  r.offsets.assign(std::size_t(ranks) + 1, 0);
  for (int o : owner) {
    if (o < 0 || o >= ranks)
      throw SolverError("distributed solve: a node owned by rank " + std::to_string(o) + " of " +
                        std::to_string(ranks));
    ++r.offsets[std::size_t(o) + 1];
  }
  std::partial_sum(r.offsets.begin(), r.offsets.end(), r.offsets.begin());
  std::vector<int> next(r.offsets.begin(), r.offsets.end() - 1);
  r.new_of.resize(owner.size());
  r.old_of.resize(owner.size());
  for (std::size_t i = 0; i < owner.size(); ++i) {
    const int k = next[std::size_t(owner[i])]++;
    r.new_of[i] = k;
    r.old_of[std::size_t(k)] = static_cast<int>(i);
  }
  return r;
}

Eigen::VectorXd solve(const SparseMatrix& A, const Eigen::VectorXd& b,
                      const LinearSolverOptions& options, bool direct,
                      const Eigen::MatrixXd& null_space, LinearSolveInfo& info) {
  return solve(A, b, options, direct, null_space, info, nullptr);
}

namespace {

/// The near-nullspace of a system of n rows as options give it: rigid-body modes from
/// coordinates (blocks of 3), or explicit vectors (orthonormalized here); InputError on sizes.
struct NearNullspace {
  bool coordinates = false, vectors = false;
  Eigen::MatrixXd basis;  // the orthonormalized vectors
};
NearNullspace near_nullspace_of(const LinearSolverOptions& options, long long n, bool direct) {
  NearNullspace out;
  const Eigen::MatrixXd& coordinates = options.near_nullspace_coordinates;
  out.coordinates = !direct && options.use_near_nullspace && coordinates.size() > 0;
  if (out.coordinates &&
      (options.block_size != 3 || coordinates.cols() != 3 || 3 * coordinates.rows() != n))
    throw InputError("near-nullspace: " + std::to_string(coordinates.rows()) + "x" +
                     std::to_string(coordinates.cols()) + " coordinates for " + std::to_string(n) +
                     " unknowns in blocks of " + std::to_string(options.block_size));
  out.vectors = !direct && options.use_near_nullspace && !out.coordinates &&
                options.near_nullspace_vectors.size() > 0;
  if (out.vectors && options.near_nullspace_vectors.rows() != n)
    throw InputError("near-nullspace: " + std::to_string(options.near_nullspace_vectors.rows()) +
                     " rows of vectors for " + std::to_string(n) + " unknowns");
  if (out.vectors) {
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(options.near_nullspace_vectors);
    out.basis =
        qr.householderQ() * Eigen::MatrixXd::Identity(n, options.near_nullspace_vectors.cols());
  }
  return out;
}

/// options.block_size (at least 1), which must divide the n unknowns (InputError otherwise).
int block_size_of(const LinearSolverOptions& options, long long n) {
  const int bs = std::max(1, options.block_size);
  if (n % bs != 0)
    throw InputError("distributed solve: " + std::to_string(n) + " unknowns in blocks of " +
                     std::to_string(bs));
  return bs;
}

Header header_of(long long n, long long groups, int bs, int kernel_columns,
                 const NearNullspace& near, const LinearSolverOptions& options, bool direct) {
  Header h;
  h.n = n;
  h.graph_nodes = groups;
  h.block_size = bs;
  h.kernel_columns = kernel_columns;
  h.vector_columns = near.vectors ? int(near.basis.cols()) : 0;
  h.coordinates = near.coordinates;
  h.direct = direct;
  h.preconditioner = static_cast<int>(options.preconditioner);
  h.parallel_ptap = static_cast<int>(options.parallel_ptap);
  h.max_iterations = options.max_iterations;
  h.rtol = options.rtol;
  // Not for MUMPS (its factor's memory is not modelled): equal rows there.
  h.balance_memory = options.rank_balance == RankBalance::memory && !direct;
  return h;
}

/// Rank 0: broadcasts the solve and its header, and partitions the graph (collective).
/// `nonzeros`: the matrix's (estimated where it is not assembled yet), for the memory balance.
std::vector<int> start_solve(Header& h, const std::vector<int>& ptr, const std::vector<int>& adj,
                             double nonzeros, std::string& partitioner, LinearSolveInfo& info) {
  h.solve_mb = nonzeros * solve_bytes_per_nonzero(h) / (1024.0 * 1024.0);
  broadcast_command(k_solve);
  MPI_Request request;
  MPI_Ibcast(&h, sizeof(Header), MPI_BYTE, 0, comm(), &request);
  wait(request);
  std::vector<int> owner = partition(ptr, adj, h, partitioner, info.rank_shares, info.rank_heap_mb);
  if (!info.rank_shares.empty()) {
    std::ostringstream s;
    for (int p = 0; p < g_size; ++p)
      s << (p ? ", " : "") << "rank " << p << ": heap "
        << std::llround(info.rank_heap_mb[std::size_t(p)]) << " MiB, share "
        << info.rank_shares[std::size_t(p)];
    log::debug("distributed solve: ", nonzeros, " nonzeros, solver memory about ",
               std::llround(h.solve_mb), " MiB over all ranks; ", s.str());
  }
  return owner;
}

void fill_info(LinearSolveInfo& info, SolveOutcome& out, bool direct,
               const LinearSolverOptions& options, const std::string& partitioner,
               double partition_s, double distribute_s) {
  info.method = direct ? "petsc-mumps-cholesky" : "petsc-cg-" + to_string(options.preconditioner);
  info.iterations = out.iterations;
  info.relative_residual = out.relative_residual;
  info.residual_history = std::move(out.history);
  info.near_nullspace = out.near_nullspace;
  info.setup_s = partition_s + distribute_s + out.setup_s;
  info.solve_s = out.solve_s;
  info.ranks = g_size;
  info.partitioner = partitioner;
  info.parallel_ptap = out.parallel_ptap;
  info.partition_s = partition_s;
  info.distribute_s = distribute_s;
}

void throw_if_failed(const SolveOutcome& out, const LinearSolveInfo& info, bool direct) {
  if (out.reason >= 0) return;
  std::ostringstream s;
  s << (direct ? "MUMPS Cholesky failed" : "distributed CG did not converge") << " (PETSc reason "
    << out.reason << ") after " << out.iterations << " iterations on " << g_size
    << " ranks; residual history:";
  const auto& hist = info.residual_history;
  for (std::size_t i = 0; i < hist.size(); i += std::max<std::size_t>(1, hist.size() / 10))
    s << ' ' << hist[i];
  throw SolverError(s.str());
}

/// At most this many vertices in the graph PT-Scotch partitions on rank 0: nodes are grouped in
/// runs of consecutive ones. The DOFs are numbered in spatial order (fem/space), so consecutive
/// nodes are near each other; grouping keeps the partitioning's memory on rank 0 (it holds the
/// whole graph) a fraction of the matrix's instead of several times the pattern's.
constexpr long long k_graph_target = 1 << 17;

long long group_size(long long nodes) {
  return std::max(1LL, (nodes + k_graph_target - 1) / k_graph_target);
}

// The graph PT-Scotch partitions: `nodes` in groups of `group` consecutive ones (group_size),
// in CSR form (ptr, adj); two groups are neighbours when a node of one has a neighbour in the
// other. neighbours(i, emit) calls emit(j) for the neighbours j of node i (repeats allowed).
struct GroupGraph {
  long long group = 1, groups = 0;
  std::vector<int> ptr, adj;
};
template <class Neighbours>
GroupGraph group_graph(long long nodes, Neighbours&& neighbours) {
  GroupGraph g;
  g.group = group_size(nodes);
  g.groups = (nodes + g.group - 1) / g.group;
  g.ptr.assign(std::size_t(g.groups) + 1, 0);
  std::vector<int> seen(std::size_t(g.groups), -1);
  for (long long G = 0; G < g.groups; ++G) {
    for (long long i = G * g.group; i < std::min(nodes, (G + 1) * g.group); ++i)
      neighbours(i, [&](long long j) {
        const int J = int(j / g.group);
        if (J != G && seen[std::size_t(J)] != int(G)) {
          seen[std::size_t(J)] = int(G);
          g.adj.push_back(J);
        }
      });
    g.ptr[std::size_t(G) + 1] = int(g.adj.size());
  }
  g.adj.shrink_to_fit();
  return g;
}

}  // namespace

Eigen::VectorXd solve(const SparseMatrix& A, const Eigen::VectorXd& b,
                      const LinearSolverOptions& options, bool direct,
                      const Eigen::MatrixXd& null_space, LinearSolveInfo& info,
                      SparseMatrix* owned) {
  if (!active() || g_rank != 0) throw Error("distributed::solve: only on rank 0 of several");
  CF_VERIFY(owned == nullptr || owned == &A, "distributed::solve: owned must be A");
  const long long n = A.rows();
  const NearNullspace near = near_nullspace_of(options, n, direct);
  const Eigen::MatrixXd& coordinates = options.near_nullspace_coordinates;
  const int bs = block_size_of(options, n);
  Stopwatch watch;
  SparseMatrix copy;  // only when A is not compressed (the assemblies' matrices are)
  if (!A.isCompressed()) {
    copy = A;
    copy.makeCompressed();
  }
  const SparseMatrix& C = A.isCompressed() ? A : copy;
  // Nodes are blocks of bs rows; their neighbours come from the (symmetric) pattern.
  const long long nodes = n / bs;
  GroupGraph graph = group_graph(nodes, [&](long long i, auto&& emit) {
    for (int c = 0; c < bs; ++c)
      for (SparseMatrix::InnerIterator it(C, int(i * bs + c)); it; ++it) emit(it.row() / bs);
  });
  const long long group = graph.group, groups = graph.groups;
  Header h = header_of(n, groups, bs, int(null_space.cols()), near, options, direct);
  // A handed over is freed once the parts are sent, before the solver's set-up.
  if (owned)
    h.rank0_transient_mb = (double(C.nonZeros()) * (sizeof(double) + sizeof(int)) +
                            double(C.outerSize() + 1) * sizeof(int)) /
                           (1024.0 * 1024.0);
  SolveOutcome out;
  Eigen::VectorXd x(n);
  try {
    std::string partitioner;
    const std::vector<int> group_owner =
        start_solve(h, graph.ptr, graph.adj, double(C.nonZeros()), partitioner, info);
    release(graph.ptr);
    release(graph.adj);
    std::vector<int> owner(static_cast<std::size_t>(nodes));
    for (long long i = 0; i < nodes; ++i)
      owner[std::size_t(i)] = group_owner[std::size_t(i / group)];
    log::debug("distributed solve: ", nodes, " nodes partitioned in ", groups, " groups of ",
               group);
    const Renumbering r = renumber_by_owner(owner, g_size);
    auto new_row = [&](int old) { return r.new_of[std::size_t(old / bs)] * bs + old % bs; };
    const double partition_s = watch.seconds();
    // Each rank's rows, built and sent one rank at a time (rank 0's last, kept).
    LocalPart own;
    for (int p = g_size - 1; p >= 0; --p) {
      LocalPart part;
      const int first = r.offsets[std::size_t(p)] * bs, last = r.offsets[std::size_t(p) + 1] * bs;
      const std::size_t m = std::size_t(last - first);
      part.row_ptr.reserve(m + 1);
      part.row_ptr.push_back(0);
      part.b.resize(m);
      // Exact sizes: grown by push_back, the part's arrays kept up to twice their entries.
      std::size_t entries = 0;
      for (int k = first; k < last; ++k) {
        const int old = r.old_of[std::size_t(k / bs)] * bs + k % bs;
        entries += std::size_t(C.outerIndexPtr()[old + 1] - C.outerIndexPtr()[old]);
      }
      part.cols.reserve(entries);
      part.values.reserve(entries);
      std::vector<std::pair<PetscInt, double>> row;
      for (int k = first; k < last; ++k) {
        const int old = r.old_of[std::size_t(k / bs)] * bs + k % bs;
        row.clear();
        for (SparseMatrix::InnerIterator it(C, old); it; ++it)  // column old = row old
          row.emplace_back(new_row(it.row()), it.value());
        std::sort(row.begin(), row.end());
        for (const auto& [c, v] : row) {
          part.cols.push_back(c);
          part.values.push_back(v);
        }
        part.row_ptr.push_back(static_cast<PetscInt>(part.cols.size()));
        part.b[std::size_t(k - first)] = b[old];
      }
      if (near.coordinates) {
        part.coordinates.reserve(m);
        for (int k = first / 3; k < last / 3; ++k)
          for (int c = 0; c < 3; ++c)
            part.coordinates.push_back(coordinates(r.old_of[std::size_t(k)], c));
      }
      auto slice = [&](const Eigen::MatrixXd& V, std::vector<double>& out) {
        out.reserve(m * std::size_t(V.cols()));
        for (Eigen::Index j = 0; j < V.cols(); ++j)
          for (int k = first; k < last; ++k)
            out.push_back(V(r.old_of[std::size_t(k / bs)] * bs + k % bs, j));
      };
      slice(null_space, part.kernel);
      if (near.vectors) slice(near.basis, part.vectors);
      info.rows_per_rank.insert(info.rows_per_rank.begin(), static_cast<long long>(m));
      if (p == 0)
        own = std::move(part);
      else
        send_part(part, p);
    }
    fem::release(copy);
    if (owned) fem::release(*owned);  // rank 0 keeps its own rows only, like the others
    const double distribute_s = watch.seconds() - partition_s;
    out = solve_part(h, own);
    fill_info(info, out, direct, options, partitioner, partition_s, distribute_s);
    for (long long i = 0; i < n; ++i) x[i] = out.x[std::size_t(new_row(int(i)))];
  } catch (const std::exception& e) {
    // The other ranks are somewhere in the protocol: nothing brings them back to serve().
    log::error("distributed solve: ", e.what());
    abort(3);
  }
  throw_if_failed(out, info, direct);
  return x;
}

Eigen::VectorXd solve_by_rows(const RowAssembly& system, const Eigen::VectorXd& F,
                              const Eigen::VectorXd& values, const std::vector<int>& reduced, int m,
                              const LinearSolverOptions& options, bool direct,
                              LinearSolveInfo& info) {
  if (!active() || g_rank != 0)
    throw Error("distributed::solve_by_rows: only on rank 0 of several");
  CF_VERIFY(system.cell_dofs && system.rows && system.block_size >= 1,
            "distributed::solve_by_rows: incomplete system");
  const int fb = system.block_size;  // unknowns per node of the full system
  const long long full = static_cast<long long>(system.nodes) * fb;
  CF_VERIFY(
      F.size() == full && values.size() == full && static_cast<long long>(reduced.size()) == full,
      "distributed::solve_by_rows: sizes do not match the system");
  const NearNullspace near = near_nullspace_of(options, m, direct);
  const Eigen::MatrixXd& coordinates = options.near_nullspace_coordinates;
  const int bs = block_size_of(options, m);
  Stopwatch watch;
  // The full system's nodes; their neighbours come through the cells (the node -> cells
  // incidence, then those cells' nodes).
  const Eigen::MatrixXi& cells = *system.cell_dofs;
  const long long nodes = system.nodes;
  const int nc = static_cast<int>(cells.rows()), nl = static_cast<int>(cells.cols());
  GroupGraph graph;
  double node_pairs = 0;
  {
    std::vector<int> start(std::size_t(nodes) + 1, 0);
    for (int c = 0; c < nc; ++c)
      for (int l = 0; l < nl; ++l) ++start[std::size_t(cells(c, l)) + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    std::vector<int> incident(std::size_t(start.back())), fill(start.begin(), start.end() - 1);
    for (int c = 0; c < nc; ++c)
      for (int l = 0; l < nl; ++l) incident[std::size_t(fill[std::size_t(cells(c, l))]++)] = c;
    release(fill);
    // The pattern's size on the way (distinct neighbours per node), for the memory balance.
    std::vector<long long> stamp(std::size_t(nodes), -1);
    graph = group_graph(nodes, [&](long long i, auto&& emit) {
      for (int k = start[std::size_t(i)]; k < start[std::size_t(i) + 1]; ++k)
        for (int l = 0; l < nl; ++l) {
          const int j = cells(incident[std::size_t(k)], l);
          if (stamp[std::size_t(j)] != i) {
            stamp[std::size_t(j)] = i;
            ++node_pairs;
          }
          emit(j);
        }
    });
  }
  const long long group = graph.group, groups = graph.groups;
  Header h = header_of(m, groups, bs, 0, near, options, direct);
  SolveOutcome out;
  Eigen::VectorXd x(m);
  try {
    std::string partitioner;
    // Nonzeros of the reduced matrix: fb² per pair of neighbouring nodes, the fixed unknowns'
    // rows and columns left out.
    const double free_share = double(m) / double(std::max(1LL, full));
    const double nonzeros = node_pairs * fb * fb * free_share * free_share;
    const std::vector<int> group_owner =
        start_solve(h, graph.ptr, graph.adj, nonzeros, partitioner, info);
    release(graph.ptr);
    release(graph.adj);
    // Owners: of every node, then of every free unknown (its node's); new numbers by owner,
    // keeping the order within a rank, so blocks of free nodes stay aligned.
    std::vector<int> full_of(std::size_t(m), -1), row_owner(std::size_t(m), 0);
    for (long long u = 0; u < full; ++u) {
      const int k = reduced[std::size_t(u)];
      if (k < 0) continue;
      CF_VERIFY(k < m, "distributed::solve_by_rows: a reduced index beyond m");
      full_of[std::size_t(k)] = int(u);
      row_owner[std::size_t(k)] = group_owner[std::size_t(u / fb / group)];
    }
    const Renumbering r = renumber_by_owner(row_owner, g_size);
    release(row_owner);
    const double partition_s = watch.seconds();
    double assemble_s = 0;
    LocalPart own;
    for (int p = g_size - 1; p >= 0; --p) {
      const int first = r.offsets[std::size_t(p)], last = r.offsets[std::size_t(p) + 1];
      CF_VERIFY(first % bs == 0 && last % bs == 0,
                "distributed::solve_by_rows: a block split between ranks");
      // The rank's nodes with a free unknown (a fixed row is not in the reduced system; the
      // fixed columns come with the free rows).
      std::vector<char> mine(std::size_t(nodes), 0);
      for (long long i = 0; i < nodes; ++i) {
        bool free = false;
        for (int c = 0; c < fb && !free; ++c) free = reduced[std::size_t(i * fb + c)] >= 0;
        mine[std::size_t(i)] = free && group_owner[std::size_t(i / group)] == p;
      }
      Stopwatch assembly;
      SparseMatrix A = system.rows(mine);
      assemble_s += assembly.seconds();
      release(mine);
      CF_VERIFY(A.isCompressed() && A.rows() == full && A.cols() == full,
                "distributed::solve_by_rows: the rows assembled do not match the system");
      LocalPart part;
      const std::size_t rows = std::size_t(last - first);
      part.row_ptr.reserve(rows + 1);
      part.row_ptr.push_back(0);
      part.b.resize(rows);
      std::size_t entries = 0;
      for (int k = first; k < last; ++k) {
        const int u = full_of[std::size_t(r.old_of[std::size_t(k)])];
        entries += std::size_t(A.outerIndexPtr()[u + 1] - A.outerIndexPtr()[u]);
      }
      part.cols.reserve(entries);
      part.values.reserve(entries);
      std::vector<std::pair<PetscInt, double>> row;
      for (int k = first; k < last; ++k) {
        const int u = full_of[std::size_t(r.old_of[std::size_t(k)])];
        CF_VERIFY(A.outerIndexPtr()[u + 1] > A.outerIndexPtr()[u],
                  "distributed::solve_by_rows: an owned row was not assembled");
        double b = F[u];
        row.clear();
        for (SparseMatrix::InnerIterator it(A, u); it; ++it) {  // column u = row u
          const int j = reduced[std::size_t(it.row())];
          if (j >= 0)
            row.emplace_back(r.new_of[std::size_t(j)], it.value());
          else
            b -= it.value() * values[it.row()];
        }
        std::sort(row.begin(), row.end());
        for (const auto& [c, v] : row) {
          part.cols.push_back(c);
          part.values.push_back(v);
        }
        part.row_ptr.push_back(static_cast<PetscInt>(part.cols.size()));
        part.b[std::size_t(k - first)] = b;
      }
      fem::release(A);
      if (near.coordinates) {
        part.coordinates.reserve(rows);
        for (int k = first; k < last; k += 3)
          for (int c = 0; c < 3; ++c)
            part.coordinates.push_back(coordinates(r.old_of[std::size_t(k)] / 3, c));
      }
      if (near.vectors) {
        part.vectors.reserve(rows * std::size_t(near.basis.cols()));
        for (Eigen::Index j = 0; j < near.basis.cols(); ++j)
          for (int k = first; k < last; ++k)
            part.vectors.push_back(near.basis(r.old_of[std::size_t(k)], j));
      }
      info.rows_per_rank.insert(info.rows_per_rank.begin(), static_cast<long long>(rows));
      if (p == 0)
        own = std::move(part);
      else
        send_part(part, p);
    }
    const double distribute_s = watch.seconds() - partition_s;
    out = solve_part(h, own);
    fill_info(info, out, direct, options, partitioner, partition_s, distribute_s);
    info.assembly_s = assemble_s;
    info.assembled_by_rows = true;
    for (int k = 0; k < m; ++k) x[k] = out.x[std::size_t(r.new_of[std::size_t(k)])];
  } catch (const std::exception& e) {
    log::error("distributed solve: ", e.what());
    abort(3);
  }
  throw_if_failed(out, info, direct);
  return x;
}

}  // namespace curvefem::fem::distributed
