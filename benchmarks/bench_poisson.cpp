// Poisson benchmark shared with the peers (benchmarks/peers/*): −Δu = f on the unit cube,
// u = cos πx cos πy cos πz, Dirichlet u on the whole boundary, P_p Lagrange on 6n³ tetrahedra.
// Prints one JSON line: DOFs, stage times (s), L2 / H1-semi errors, peak RSS.
//   curvefem_bench_poisson N P direct|cg [threads]
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <numbers>

#include "fem/problems/error_norms.hpp"
#include "fem/problems/poisson.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/core/timer.hpp"

using namespace curvefem;

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s N P direct|cg [threads]\n", argv[0]);
    return 1;
  }
  const int n = std::atoi(argv[1]), p = std::atoi(argv[2]);
  const std::string solver = argv[3];
  const int threads = argc > 4 ? std::atoi(argv[4]) : 1;
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  log::set_level(log::Level::warn);
  const double pi = std::numbers::pi;
  auto u = [pi](const Eigen::Vector3d& x) {
    return std::cos(pi * x[0]) * std::cos(pi * x[1]) * std::cos(pi * x[2]);
  };
  Stopwatch total, w;
  const LagrangeMesh mesh = make_cube_tets(n);
  const double t_mesh = w.seconds();
  w.reset();
  const fem::FunctionSpace space = fem::build_function_space(mesh, p);
  const double t_space = w.seconds();
  fem::PoissonProblem problem;
  problem.rhs = [&](const Eigen::Vector3d& x) { return 3 * pi * pi * u(x); };
  problem.dirichlet.push_back({std::vector<char>(space.boundary_faces.size(), 1), u, {}});
  fem::LinearSolverOptions options;
  options.type = curvefem::fem::solver_type_from(solver);
  options.rtol = 1e-10;
  const auto sol = fem::solve_poisson(mesh, space, problem, options);
  w.reset();
  const auto e = fem::compute_errors(
      mesh, space, sol.u, 1, [&](const Eigen::Vector3d& x, double* v) { *v = u(x); },
      [&](const Eigen::Vector3d& x, double* g) {
        g[0] = -pi * std::sin(pi * x[0]) * std::cos(pi * x[1]) * std::cos(pi * x[2]);
        g[1] = -pi * std::cos(pi * x[0]) * std::sin(pi * x[1]) * std::cos(pi * x[2]);
        g[2] = -pi * std::cos(pi * x[0]) * std::cos(pi * x[1]) * std::sin(pi * x[2]);
      });
  const double t_errors = w.seconds();
  nlohmann::json j;
  j["code"] = "curvefem";
  j["n"] = n;
  j["p"] = p;
  j["tets"] = mesh.num_cells();
  j["dofs"] = space.num_dofs;
  j["threads"] = threads;
  j["solver"] = sol.solve.method;
  j["iterations"] = sol.solve.iterations;
  j["mesh_s"] = t_mesh;
  j["dofmap_s"] = t_space;
  j["assembly_s"] = sol.timings.get("assembly");
  j["setup_s"] = sol.solve.setup_s;
  j["solve_s"] = sol.solve.solve_s;
  j["solve_total_s"] = sol.timings.get("solve");
  j["errors_s"] = t_errors;
  j["total_s"] = total.seconds();
  j["l2_error"] = e.l2;
  j["h1_semi_error"] = e.h1_semi;
  j["peak_rss_mb"] = peak_rss_mb();
  std::printf("%s\n", j.dump().c_str());
  return 0;
}
