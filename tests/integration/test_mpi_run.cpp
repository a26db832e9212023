// `mpirun -n 2 curvefem run` against `mpirun -n 1` (fem/solvers/distributed.hpp): the same
// solution up to the solver tolerance, report.json's ranks and rows per rank; other commands are
// refused under two ranks (test_cli: Cli.SeveralMpiProcessesAreRefusedBeforeAnyOutput).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "meshing/io/vtu_io.hpp"
#include "tests/support/test_support.hpp"

using namespace curvefem;

namespace {

const std::string k_mpiexec = CURVEFEM_MPIEXEC;

/// `curvefem run` of `case_text` under the launcher with `ranks` processes, into dir/out<ranks>.
std::filesystem::path run_ranks(const std::filesystem::path& dir, const std::string& case_text,
                                int ranks, const std::string& extra = "") {
  const auto file = dir / "case.json";
  std::ofstream(file) << case_text;
  const auto out = dir / ("out" + std::to_string(ranks));
  std::string log;
  const int code =
      test::run_command(k_mpiexec + " --allow-run-as-root --oversubscribe -n " +
                            std::to_string(ranks) + " " + test::curvefem_executable().string() +
                            " run -q " + file.string() + " -o " + out.string() + extra,
                        &log);
  EXPECT_EQ(code, 0) << log;
  return out;
}

nlohmann::json report(const std::filesystem::path& dir) {
  std::ifstream in(dir / "report.json");
  return nlohmann::json::parse(in);
}

/// max |a - b| / max |a| over volume.vtu's first point field (u or displacement).
double relative_difference(const std::filesystem::path& a, const std::filesystem::path& b) {
  const auto va = io::read_vtu(a / "volume.vtu"), vb = io::read_vtu(b / "volume.vtu");
  const auto& x = va.fields.point_data.at(0).values;
  const auto& y = vb.fields.point_data.at(0).values;
  EXPECT_EQ(x.size(), y.size());
  double diff = 0, scale = 0;
  for (std::size_t i = 0; i < std::min(x.size(), y.size()); ++i) {
    diff = std::max(diff, std::abs(x[i] - y[i]));
    scale = std::max(scale, std::abs(x[i]));
  }
  EXPECT_GT(scale, 0.0);
  return diff / scale;
}

/// The distributed run's report: two ranks, each owning rows, as many as the one-rank solve.
void expect_two_rank_report(const nlohmann::json& one, const nlohmann::json& two,
                            const std::string& method) {
  EXPECT_EQ(one["ranks"], 1);
  EXPECT_FALSE(one["solver"].contains("rows_per_rank"));
  EXPECT_EQ(two["ranks"], 2);
  EXPECT_EQ(two["solver"]["method"], method);
  EXPECT_EQ(two["solver"]["ranks"], 2);
  EXPECT_EQ(two["solver"]["partitioner"], "ptscotch");
  const auto rows = two["solver"]["rows_per_rank"].get<std::vector<long long>>();
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_GT(rows[0], 0);
  EXPECT_GT(rows[1], 0);
  const auto rss = two["mpi"]["peak_rss_mb_per_rank"].get<std::vector<double>>();
  ASSERT_EQ(rss.size(), 2u);
  EXPECT_GT(rss[0], 0.0);
  EXPECT_GT(rss[1], 0.0);
  EXPECT_EQ(one["dofs"], two["dofs"]);
  // Measured on the distributed matrix (rank 0 no longer holds the whole matrix then).
  EXPECT_LT(two["solver"]["relative_residual"].get<double>(), 1e-8);
  EXPECT_GT(two["solver"]["relative_residual"].get<double>(), 0.0);
}

bool have_launcher(std::string& why) {
  if (k_mpiexec.empty() || test::run_command(k_mpiexec + " --version") != 0) {
    why = "no MPI launcher (MPIEXEC_EXECUTABLE '" + k_mpiexec + "')";
    return false;
  }
  return true;
}

}  // namespace

TEST(MpiRun, PoissonP2OneAndTwoRanksAgree) {
  std::string why;
  if (!have_launcher(why)) GTEST_SKIP() << why;
  const auto dir = test::scratch_dir("mpi_poisson");
  const std::string text = R"json({
    "geometry": {"builtin": {"shape": "cube", "divisions": 4, "order": 1}},
    "physics": {"type": "poisson"},
    "discretization": {"degree": 2},
    "rhs": "-2*exp(x)*sin(y)",
    "exact": "exp(x)*sin(y)*x + z",
    "boundary_conditions": [
      {"type": "dirichlet", "select": {"all": true}, "value": "exp(x)*sin(y)*x + z"}],
    "solver": {"type": "cg", "rtol": 1e-12}
  })json";
  const auto one = run_ranks(dir, text, 1), two = run_ranks(dir, text, 2, " --threads 2");
  const double d = relative_difference(one, two);
  EXPECT_LT(d, 1e-8);  // measured 2026-12-03: see fem/README.md
  std::printf("Poisson P2: 1 vs 2 ranks, relative max difference %.3e\n", d);
  const auto r1 = report(one), r2 = report(two);
  expect_two_rank_report(r1, r2, "petsc-cg-gamg");
  // The matrix was assembled by rows, one rank's at a time (distributed::solve_by_rows).
  EXPECT_TRUE(r2["solver"]["assembled_by_rows"].get<bool>());
  EXPECT_GT(r2["solver"]["rows_assembly_s"].get<double>(), 0.0);
  // "auto": PETSc's own Galerkin products for a scalar problem (allatonce with elasticity's modes).
  EXPECT_EQ(r2["solver"]["parallel_ptap"], "scalable");
  EXPECT_NEAR(r2["l2_error"].get<double>(), r1["l2_error"].get<double>(),
              1e-8 * r1["l2_error"].get<double>());
  EXPECT_GT(r1["l2_error"].get<double>(), 1e-8);  // not in the space: the test can fail
}

// solver.rank_balance: by default rank 0, which also holds the mesh and the space, is asked for
// fewer rows (shares from the ranks' heaps); "rows" splits them evenly. Same solution either way.
TEST(MpiRun, RankZeroGetsFewerRowsWhenTheRanksMemoryIsBalanced) {
  std::string why;
  if (!have_launcher(why)) GTEST_SKIP() << why;
  std::string text = R"json({
    "geometry": {"builtin": {"shape": "cube", "divisions": 6, "order": 1}},
    "physics": {"type": "poisson"},
    "discretization": {"degree": 2},
    "rhs": "-2*exp(x)*sin(y)",
    "boundary_conditions": [
      {"type": "dirichlet", "select": {"all": true}, "value": "exp(x)*sin(y)*x + z"}],
    "solver": {"type": "cg", "rtol": 1e-12}
  })json";
  const auto memory = run_ranks(test::scratch_dir("mpi_balance_memory"), text, 2);
  text.replace(text.find("\"rtol\""), 0, "\"rank_balance\": \"rows\", ");
  const auto rows = run_ranks(test::scratch_dir("mpi_balance_rows"), text, 2);
  EXPECT_LT(relative_difference(memory, rows), 1e-8);
  const auto m = report(memory)["solver"], r = report(rows)["solver"];
  const auto shares = m["rank_shares"].get<std::vector<double>>();
  const auto heap = m["rank_heap_mb"].get<std::vector<double>>();
  ASSERT_EQ(shares.size(), 2u);
  ASSERT_EQ(heap.size(), 2u);
  EXPECT_NEAR(shares[0] + shares[1], 1.0, 1e-12);
  EXPECT_GT(heap[0], heap[1]);  // rank 0 holds the mesh, the space, the boundary data
  EXPECT_LT(shares[0], 0.5);
  EXPECT_GE(shares[0], 0.1 - 1e-12);  // the floor: 0.2 / ranks
  const auto asked = m["rows_per_rank"].get<std::vector<long long>>();
  const auto even = r["rows_per_rank"].get<std::vector<long long>>();
  ASSERT_EQ(asked.size(), 2u);
  ASSERT_EQ(even.size(), 2u);
  EXPECT_LT(asked[0], asked[1]);
  // PT-Scotch follows the weights to within a few per cent of the rows.
  EXPECT_NEAR(double(asked[0]) / double(asked[0] + asked[1]), shares[0], 0.05);
  EXPECT_FALSE(r.contains("rank_shares"));
  EXPECT_NEAR(double(even[0]) / double(even[0] + even[1]), 0.5, 0.05);
}

TEST(MpiRun, ElasticityP2OneAndTwoRanksAgreeWithRigidBodyModes) {
  std::string why;
  if (!have_launcher(why)) GTEST_SKIP() << why;
  const auto dir = test::scratch_dir("mpi_elasticity");
  const std::string text = R"json({
    "geometry": {"builtin": {"shape": "cube", "divisions": 4, "order": 1}},
    "physics": {"type": "linear_elasticity", "E": 210e3, "nu": 0.3},
    "discretization": {"degree": 2},
    "boundary_conditions": [
      {"type": "dirichlet", "select": {"tag": 1}, "value": [0, 0, 0]},
      {"type": "neumann", "select": {"tag": 2}, "value": [0, "10*y", "-100"]}],
    "solver": {"type": "cg", "rtol": 1e-12}
  })json";
  const auto one = run_ranks(dir, text, 1), two = run_ranks(dir, text, 2);
  const double d = relative_difference(one, two);
  EXPECT_LT(d, 1e-8);
  std::printf("elasticity P2: 1 vs 2 ranks, relative max difference %.3e\n", d);
  const auto r1 = report(one), r2 = report(two);
  expect_two_rank_report(r1, r2, "petsc-cg-gamg");
  EXPECT_EQ(r2["solver"]["near_nullspace"], "rigid-body modes");
  EXPECT_EQ(r2["solver"]["rows_per_rank"][0].get<long long>() % 3, 0);
  EXPECT_TRUE(r2["solver"]["assembled_by_rows"].get<bool>());
  // GAMG's parallel Galerkin products: "auto" is the lean allatonce with the rigid-body modes, and
  // PETSc's own on request (the same solution to the solver tolerance).
  EXPECT_EQ(r2["solver"]["parallel_ptap"], "allatonce");
  std::string scalable = text;
  scalable.replace(scalable.find("\"rtol\""), 0, "\"parallel_ptap\": \"scalable\", ");
  const auto three = run_ranks(test::scratch_dir("mpi_elasticity_scalable"), scalable, 2);
  EXPECT_LT(relative_difference(one, three), 1e-8);
  EXPECT_EQ(report(three)["solver"]["parallel_ptap"], "scalable");
}

// The boundary terms of a matrix assembled by rows: Robin's ∫ h u v and the Nitsche terms of a
// Dirichlet selection that cuts boundary faces (Poisson; elasticity's Nitsche terms with
// "partial_dirichlet": "nitsche"), each rank's rows from the same face points as one rank's.
TEST(MpiRun, RobinAndNitscheTermsAssembledByRowsAgree) {
  std::string why;
  if (!have_launcher(why)) GTEST_SKIP() << why;
  const std::string poisson = R"json({
    "geometry": {"builtin": {"shape": "cube", "divisions": 4, "order": 1}},
    "physics": {"type": "poisson", "kappa": "1 + x*y"},
    "discretization": {"degree": 2},
    "rhs": "1 + z",
    "boundary_conditions": [
      {"type": "robin", "select": {"tag": 2}, "h": "2 + x", "u_inf": "y"},
      {"type": "dirichlet", "select": {"box": [[-1, -1, -1], [0.3, 2, 0.55]]}, "value": "x*z"}],
    "solver": {"type": "cg", "rtol": 1e-12}
  })json";
  const std::string elasticity = R"json({
    "geometry": {"builtin": {"shape": "cube", "divisions": 4, "order": 1}},
    "physics": {"type": "linear_elasticity", "E": 1000, "nu": 0.3},
    "discretization": {"degree": 2, "partial_dirichlet": "nitsche"},
    "boundary_conditions": [
      {"type": "dirichlet", "select": {"box": [[-1, -1, -1], [0.3, 2, 0.55]]}, "value": [0, 0, 0]},
      {"type": "neumann", "select": {"tag": 2}, "value": [1, 0, "-1"]}],
    "solver": {"type": "cg", "rtol": 1e-12}
  })json";
  for (const auto& [name, text] : {std::pair{"poisson", poisson}, {"elasticity", elasticity}}) {
    const auto dir = test::scratch_dir(std::string("mpi_boundary_terms_") + name);
    const auto one = run_ranks(dir, text, 1), two = run_ranks(dir, text, 2);
    EXPECT_LT(relative_difference(one, two), 1e-8) << name;
    const auto r1 = report(one), r2 = report(two);
    expect_two_rank_report(r1, r2, "petsc-cg-gamg");
    EXPECT_TRUE(r2["solver"]["assembled_by_rows"].get<bool>()) << name;
    // The selection cuts faces: Nitsche terms were assembled (the test covers them).
    EXPECT_GT(r1["physics_details"]["nitsche_faces"].get<int>(), 0) << name;
    EXPECT_EQ(r1["physics_details"]["nitsche_faces"], r2["physics_details"]["nitsche_faces"]);
  }
}

// Load cases (the solves of a run sharing a factorization cache, as the shifted passes of a curved
// run do): on several ranks each case's matrix is assembled by rows too — the cache is not used
// across ranks, and keeping the stiffness would keep the whole matrix on rank 0.
TEST(MpiRun, LoadCasesAreAssembledByRowsToo) {
  std::string why;
  if (!have_launcher(why)) GTEST_SKIP() << why;
  const auto dir = test::scratch_dir("mpi_load_cases");
  const std::string text = R"json({
    "geometry": {"builtin": {"shape": "cube", "divisions": 4, "order": 1}},
    "physics": {"type": "linear_elasticity", "E": 1000, "nu": 0.3},
    "discretization": {"degree": 2},
    "solver": {"type": "cg", "rtol": 1e-12},
    "load_cases": [
      {"name": "down", "boundary_conditions": [
         {"type": "dirichlet", "select": {"tag": 1}, "value": [0, 0, 0]},
         {"type": "neumann", "select": {"tag": 2}, "value": [0, 0, -1]}]},
      {"name": "side", "rhs": [0, "0.5", 0], "boundary_conditions": [
         {"type": "dirichlet", "select": {"tag": 1}, "value": [0, 0, 0]}]}]
  })json";
  const auto one = run_ranks(dir, text, 1), two = run_ranks(dir, text, 2);
  EXPECT_LT(relative_difference(one, two), 1e-8);
  const auto r1 = report(one), r2 = report(two);
  ASSERT_EQ(r2["load_cases"].size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const auto& s1 = r1["load_cases"][i]["solver"];
    const auto& s2 = r2["load_cases"][i]["solver"];
    EXPECT_FALSE(s1.contains("assembled_by_rows"));
    EXPECT_EQ(s2["ranks"], 2);
    EXPECT_TRUE(s2["assembled_by_rows"].get<bool>()) << i;
    EXPECT_LT(s2["relative_residual"].get<double>(), 1e-8);
  }
}

// Neo-Hookean: every Newton step's tangent is assembled by rows on several ranks; the Newton
// iterations and the solution match one rank's.
TEST(MpiRun, NeoHookeanNewtonTangentsAssembledByRows) {
  std::string why;
  if (!have_launcher(why)) GTEST_SKIP() << why;
  const auto dir = test::scratch_dir("mpi_neo_hookean");
  const std::string text = R"json({
    "geometry": {"builtin": {"shape": "cube", "divisions": 3, "order": 1}},
    "physics": {"type": "neo_hookean", "E": 1000, "nu": 0.3, "load_steps": 2},
    "discretization": {"degree": 2},
    "boundary_conditions": [
      {"type": "dirichlet", "select": {"tag": 1}, "value": [0, 0, 0]},
      {"type": "neumann", "select": {"tag": 2}, "value": [0, 0, -80]}],
    "solver": {"type": "cg", "rtol": 1e-12}
  })json";
  const auto one = run_ranks(dir, text, 1), two = run_ranks(dir, text, 2);
  EXPECT_LT(relative_difference(one, two), 1e-8);
  const auto r1 = report(one), r2 = report(two);
  EXPECT_EQ(r2["solver"]["ranks"], 2);
  EXPECT_TRUE(r2["solver"]["assembled_by_rows"].get<bool>());
  EXPECT_EQ(r1["physics_details"]["newton"].size(), r2["physics_details"]["newton"].size());
  EXPECT_GT(r2["physics_details"]["newton"].size(), 2u);
}

TEST(MpiRun, DirectIsMumpsOnTwoRanks) {
  std::string why;
  if (!have_launcher(why)) GTEST_SKIP() << why;
  const auto dir = test::scratch_dir("mpi_direct");
  const std::string text = R"json({
    "geometry": {"builtin": {"shape": "cube", "divisions": 3, "order": 1}},
    "physics": {"type": "poisson"},
    "discretization": {"degree": 2},
    "rhs": "1",
    "boundary_conditions": [{"type": "dirichlet", "select": {"tag": 1}, "value": "0"}],
    "solver": {"type": "direct"}
  })json";
  const auto one = run_ranks(dir, text, 1), two = run_ranks(dir, text, 2);
  const double d = relative_difference(one, two);
  EXPECT_LT(d, 1e-10);
  const auto r1 = report(one), r2 = report(two);
  EXPECT_EQ(r1["solver"]["method"], "cholmod-supernodal");
  expect_two_rank_report(r1, r2, "petsc-mumps-cholesky");
  EXPECT_TRUE(r2["solver"]["assembled_by_rows"].get<bool>());
}

// Pure Neumann Poisson (CG on the singular system with its kernel, and MUMPS after pinning) and
// elasticity with a component fixed alone (block size 1, the six modes as explicit vectors).
TEST(MpiRun, SingularSystemsAndExplicitNearNullspaceVectors) {
  std::string why;
  if (!have_launcher(why)) GTEST_SKIP() << why;
  const std::string neumann = R"json(
    "geometry": {"builtin": {"shape": "cube", "divisions": 3, "order": 1}},
    "physics": {"type": "poisson"}, "discretization": {"degree": 2}, "rhs": "0",
    "boundary_conditions": [{"type": "neumann", "select": {"tag": 1}, "value": "1"},
                            {"type": "neumann", "select": {"tag": 2}, "value": "-1"}],)json";
  for (const std::string solver : {"cg", "direct"}) {
    const auto dir = test::scratch_dir("mpi_singular_" + solver);
    const std::string text = "{" + neumann + R"json("solver": {"type": ")json" + solver +
                             R"json(", "rtol": 1e-12}})json";
    const auto one = run_ranks(dir, text, 1), two = run_ranks(dir, text, 2);
    EXPECT_LT(relative_difference(one, two), 1e-8) << solver;
    const auto r2 = report(two);
    EXPECT_EQ(r2["solver"]["null_space_dim"], 1) << solver;
    EXPECT_EQ(r2["solver"]["ranks"], 2) << solver;
    // Singular: solved on the whole matrix (its kernel), not assembled by rows.
    EXPECT_FALSE(r2["solver"]["assembled_by_rows"].get<bool>()) << solver;
  }
  const auto dir = test::scratch_dir("mpi_vectors");
  const std::string text = R"json({
    "geometry": {"builtin": {"shape": "cube", "divisions": 4, "order": 1}},
    "physics": {"type": "linear_elasticity", "E": 1000, "nu": 0.3},
    "discretization": {"degree": 2},
    "boundary_conditions": [
      {"type": "dirichlet", "select": {"tag": 1}, "value": [0, 0, 0],
       "components": [true, false, false]},
      {"type": "dirichlet", "select": {"box": [[-1, -1, -1], [0.01, 0.01, 2]]}, "value": [0, 0, 0]},
      {"type": "neumann", "select": {"tag": 2}, "value": [1, 0, "-1"]}],
    "solver": {"type": "cg", "rtol": 1e-12}
  })json";
  const auto one = run_ranks(dir, text, 1), two = run_ranks(dir, text, 2);
  EXPECT_LT(relative_difference(one, two), 1e-8);
  const auto r1 = report(one), r2 = report(two);
  EXPECT_EQ(r1["solver"]["near_nullspace"], "vectors");
  expect_two_rank_report(r1, r2, "petsc-cg-gamg");
  EXPECT_EQ(r2["solver"]["near_nullspace"], "vectors");
  EXPECT_TRUE(r2["solver"]["assembled_by_rows"].get<bool>());
}

// Failures on rank 0 end every rank: a bad case file (exit 2) and a CG that does not converge in
// its iteration limit (a SolverError after the collective solve, exit 3); no rank hangs, nothing is
// written.
TEST(MpiRun, ErrorsOnRankZeroEndEveryRank) {
  std::string why;
  if (!have_launcher(why)) GTEST_SKIP() << why;
  const auto dir = test::scratch_dir("mpi_errors");
  auto run = [&](const std::string& text, std::string& log) {
    std::ofstream(dir / "case.json") << text;
    return test::run_command("timeout 60 " + k_mpiexec +
                                 " --allow-run-as-root --oversubscribe -n 2 " +
                                 test::curvefem_executable().string() + " run -q " +
                                 (dir / "case.json").string() + " -o " + (dir / "out").string(),
                             &log);
  };
  std::string log;
  EXPECT_EQ(run(R"json({"physics": {"type": "poisson"}})json", log), 2) << log;
  EXPECT_NE(log.find("/geometry: missing"), std::string::npos) << log;
  EXPECT_EQ(run(R"json({
    "geometry": {"builtin": {"shape": "cube", "divisions": 3, "order": 1}},
    "discretization": {"degree": 2}, "rhs": "1",
    "boundary_conditions": [{"type": "dirichlet", "select": {"tag": 1}, "value": "0"}],
    "solver": {"type": "cg", "rtol": 1e-14, "max_iterations": 2}
  })json",
                log),
            3)
      << log;
  EXPECT_NE(log.find("did not converge"), std::string::npos) << log;
  EXPECT_NE(log.find("on 2 ranks"), std::string::npos) << log;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}
