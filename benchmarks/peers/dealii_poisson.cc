// Peer of benchmarks/bench_poisson.cpp in deal.II 9.4 (Debian libdeal.ii-dev).
//
// −Δu = f on the unit cube, u = cos πx cos πy cos πz, Dirichlet u on the whole boundary, P_p
// Lagrange (FE_SimplexP) on the same mesh as curvefem's make_cube_tets(n): n³ cubes, each split
// into 6 Kuhn tetrahedra with the same vertex numbering and orientation. deal.II 9.4 supports
// only p = 1, 2 on tetrahedra (FE_SimplexP(3) is broken in 9.4.1).
// Prints one JSON line with the same keys as curvefem_bench_poisson.
//   dealii_poisson N P direct|cg [threads]
//   direct = UMFPACK LU (dealii::SparseMatrix), cg = deal.II CG + Trilinos ML AMG (Epetra matrix),
//   stopping at ‖b − Ax‖ ≤ 1e-10 ‖b‖.
#include <deal.II/base/function.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_simplex_p.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_fe.h>
#include <deal.II/grid/tria.h>
#include <deal.II/lac/affine_constraints.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/solver_cg.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/sparse_direct.h>
#include <deal.II/lac/sparse_matrix.h>
#include <deal.II/lac/sparsity_pattern.h>
#include <deal.II/lac/vector.h>
#include <deal.II/numerics/vector_tools.h>
#include <sys/resource.h>

#ifdef DEAL_II_WITH_TRILINOS
#  include <deal.II/lac/trilinos_precondition.h>
#  include <deal.II/lac/trilinos_sparse_matrix.h>
#endif

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

using namespace dealii;

namespace {

constexpr double pi = M_PI;

class Exact : public Function<3> {
 public:
  double value(const Point<3>& x, const unsigned int = 0) const override {
    return std::cos(pi * x[0]) * std::cos(pi * x[1]) * std::cos(pi * x[2]);
  }
  Tensor<1, 3> gradient(const Point<3>& x, const unsigned int = 0) const override {
    const double c0 = std::cos(pi * x[0]), c1 = std::cos(pi * x[1]), c2 = std::cos(pi * x[2]);
    Tensor<1, 3> g;
    g[0] = -pi * std::sin(pi * x[0]) * c1 * c2;
    g[1] = -pi * c0 * std::sin(pi * x[1]) * c2;
    g[2] = -pi * c0 * c1 * std::sin(pi * x[2]);
    return g;
  }
};

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// curvefem's make_cube_tets(n) (meshing/core/primitives.cpp): node (i, j, k) has id
// (k·s + j)·s + i with s = n + 1; every cube is split into 6 tets along the paths
// (i,j,k) → +e_a → +e_b → +e_c over all permutations (a, b, c); negatively oriented tets get
// vertices 1 and 2 swapped, which is also deal.II's positive orientation of the reference tet.
void make_cube_tets(Triangulation<3>& tria, int n) {
  const int s = n + 1;
  auto id = [s](int i, int j, int k) { return static_cast<unsigned int>((k * s + j) * s + i); };
  std::vector<Point<3>> vertices(static_cast<std::size_t>(s) * s * s);
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) vertices[id(i, j, k)] = Point<3>(double(i) / n, double(j) / n,
                                                                   double(k) / n);
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  std::vector<CellData<3>> cells;
  cells.reserve(6 * static_cast<std::size_t>(n) * n * n);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (const auto& p : perms) {
          std::array<int, 3> g = {i, j, k};
          std::array<unsigned int, 4> v;
          v[0] = id(g[0], g[1], g[2]);
          for (int step = 0; step < 3; ++step) {
            g[p[step]] += 1;
            v[step + 1] = id(g[0], g[1], g[2]);
          }
          const Tensor<1, 3> a = vertices[v[1]] - vertices[v[0]];
          const Tensor<1, 3> b = vertices[v[2]] - vertices[v[0]];
          const Tensor<1, 3> d = vertices[v[3]] - vertices[v[0]];
          if (a * cross_product_3d(b, d) < 0) std::swap(v[1], v[2]);
          CellData<3> cell(4);
          for (unsigned int t = 0; t < 4; ++t) cell.vertices[t] = v[t];
          cell.material_id = 0;
          cells.push_back(cell);
        }
  tria.create_triangulation(vertices, cells, SubCellData());
}

// Matrix + right-hand side with the Dirichlet values eliminated through AffineConstraints
// (symmetric; constrained rows keep a diagonal entry), as in deal.II's tutorials.
template <typename Matrix>
void assemble(const Mapping<3>& mapping, const DoFHandler<3>& dof,
              const AffineConstraints<double>& constraints, const Quadrature<3>& quad,
              Matrix& A, Vector<double>& b) {
  const FiniteElement<3>& fe = dof.get_fe();
  FEValues<3> fv(mapping, fe, quad,
                 update_values | update_gradients | update_quadrature_points | update_JxW_values);
  const unsigned int nd = fe.n_dofs_per_cell(), nq = quad.size();
  FullMatrix<double> Ke(nd, nd);
  Vector<double> Fe(nd);
  std::vector<types::global_dof_index> ids(nd);
  for (const auto& cell : dof.active_cell_iterators()) {
    fv.reinit(cell);
    Ke = 0;
    Fe = 0;
    for (unsigned int q = 0; q < nq; ++q) {
      const Point<3>& x = fv.quadrature_point(q);
      const double jxw = fv.JxW(q);
      const double f = 3 * pi * pi * std::cos(pi * x[0]) * std::cos(pi * x[1]) *
                       std::cos(pi * x[2]);
      for (unsigned int i = 0; i < nd; ++i) {
        const Tensor<1, 3>& gi = fv.shape_grad(i, q);
        for (unsigned int j = i; j < nd; ++j) Ke(i, j) += gi * fv.shape_grad(j, q) * jxw;
        Fe(i) += f * fv.shape_value(i, q) * jxw;
      }
    }
    for (unsigned int i = 0; i < nd; ++i)
      for (unsigned int j = 0; j < i; ++j) Ke(i, j) = Ke(j, i);
    cell->get_dof_indices(ids);
    constraints.distribute_local_to_global(Ke, Fe, ids, A, b);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s N P direct|cg [threads]\n", argv[0]);
    return 1;
  }
  const int n = std::atoi(argv[1]), p = std::atoi(argv[2]);
  const std::string solver = argv[3];
  const unsigned int threads = argc > 4 ? static_cast<unsigned int>(std::atoi(argv[4])) : 1;
  if (n < 1 || p < 1 || p > 2 || (solver != "direct" && solver != "cg")) {
    std::fprintf(stderr, "need N ≥ 1, P in {1, 2} (deal.II 9.4 simplices), direct|cg\n");
    return 1;
  }
  // MPI is needed by Trilinos (Epetra); the thread limit caps deal.II's TBB use.
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, threads);
  const Exact exact;
  const auto t_total = std::chrono::steady_clock::now();

  auto t = std::chrono::steady_clock::now();
  Triangulation<3> tria;
  make_cube_tets(tria, n);
  const double t_mesh = seconds_since(t);

  t = std::chrono::steady_clock::now();
  const FE_SimplexP<3> fe(p);
  const MappingFE<3> mapping(FE_SimplexP<3>(1));
  DoFHandler<3> dof(tria);
  dof.distribute_dofs(fe);
  const double t_space = seconds_since(t);

  const QGaussSimplex<3> quad(p + 1);  // 14 points for p = 2, exact to degree 5
  // Errors: Witherden–Vincent, even order 2n = 10 (81 points), curvefem uses degree 10 too.
  // (QGaussSimplex<3> exists only for n ≤ 4 in 9.4; bigger n gives an empty rule.)
  const QWitherdenVincentSimplex<3> error_quad(5, false);
  double wsum = 0;
  for (unsigned int q = 0; q < error_quad.size(); ++q) wsum += error_quad.weight(q);
  if (error_quad.size() == 0 || std::abs(wsum - 1.0 / 6.0) > 1e-13) {
    std::fprintf(stderr, "error quadrature is broken (%u points, weight sum %g)\n",
                 error_quad.size(), wsum);
    return 1;
  }

  Vector<double> u(dof.n_dofs()), b(dof.n_dofs());
  AffineConstraints<double> constraints;
  std::string method;
  unsigned int iterations = 0;
  double t_asm = 0, t_setup = 0, t_solve = 0;

  // Timed assembly = boundary interpolation + sparsity pattern + matrix and vector, as the
  // DOLFINx peer (whose assemble_matrix builds the pattern and applies the conditions).
  auto setup_constraints_and_pattern = [&](SparsityPattern& sp) {
    VectorTools::interpolate_boundary_values(mapping, dof, types::boundary_id(0), exact,
                                             constraints);
    constraints.close();
    DynamicSparsityPattern dsp(dof.n_dofs());
    DoFTools::make_sparsity_pattern(dof, dsp, constraints, /*keep_constrained_dofs=*/false);
    sp.copy_from(dsp);
  };

  SparsityPattern sp;
  if (solver == "direct") {
    method = "umfpack";
    SparseMatrix<double> A;
    t = std::chrono::steady_clock::now();
    setup_constraints_and_pattern(sp);
    A.reinit(sp);
    assemble(mapping, dof, constraints, quad, A, b);
    t_asm = seconds_since(t);
    t = std::chrono::steady_clock::now();
    SparseDirectUMFPACK lu;
    lu.initialize(A);  // symbolic + numeric LU
    t_setup = seconds_since(t);
    t = std::chrono::steady_clock::now();
    lu.vmult(u, b);
    constraints.distribute(u);
    t_solve = seconds_since(t);
    iterations = 0;
  } else {
#ifdef DEAL_II_WITH_TRILINOS
    method = "cg-ml";
    TrilinosWrappers::SparseMatrix A;
    t = std::chrono::steady_clock::now();
    setup_constraints_and_pattern(sp);
    A.reinit(sp);
    assemble(mapping, dof, constraints, quad, A, b);
    A.compress(VectorOperation::add);
    t_asm = seconds_since(t);
    t = std::chrono::steady_clock::now();
    TrilinosWrappers::PreconditionAMG amg;
    TrilinosWrappers::PreconditionAMG::AdditionalData data;
    data.elliptic = true;
    data.higher_order_elements = p > 1;
    amg.initialize(A, data);
    t_setup = seconds_since(t);
    t = std::chrono::steady_clock::now();
    SolverControl control(10000, 1e-10 * b.l2_norm());
    SolverCG<Vector<double>> cg(control);
    cg.solve(A, u, b, amg);
    constraints.distribute(u);
    t_solve = seconds_since(t);
    iterations = control.last_step();
#else
    std::fprintf(stderr, "deal.II was built without Trilinos: no AMG\n");
    return 1;
#endif
  }

  t = std::chrono::steady_clock::now();
  Vector<double> cellwise(tria.n_active_cells());
  VectorTools::integrate_difference(mapping, dof, u, exact, cellwise, error_quad,
                                    VectorTools::L2_norm);
  const double l2 = VectorTools::compute_global_error(tria, cellwise, VectorTools::L2_norm);
  VectorTools::integrate_difference(mapping, dof, u, exact, cellwise, error_quad,
                                    VectorTools::H1_seminorm);
  const double h1 = VectorTools::compute_global_error(tria, cellwise, VectorTools::H1_seminorm);
  const double t_err = seconds_since(t);

  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  std::printf(
      "{\"code\": \"deal.II\", \"n\": %d, \"p\": %d, \"tets\": %u, \"dofs\": %u, "
      "\"threads\": %u, \"solver\": \"%s\", \"iterations\": %u, \"mesh_s\": %.6f, "
      "\"dofmap_s\": %.6f, \"assembly_s\": %.6f, \"setup_s\": %.6f, \"solve_s\": %.6f, "
      "\"solve_total_s\": %.6f, \"errors_s\": %.6f, \"total_s\": %.6f, \"l2_error\": %.17g, "
      "\"h1_semi_error\": %.17g, \"peak_rss_mb\": %.1f}\n",
      n, p, tria.n_active_cells(), static_cast<unsigned int>(dof.n_dofs()), threads,
      method.c_str(), iterations, t_mesh, t_space, t_asm, t_setup, t_solve, t_setup + t_solve,
      t_err, seconds_since(t_total), l2, h1, ru.ru_maxrss / 1024.0);
  return 0;
}
