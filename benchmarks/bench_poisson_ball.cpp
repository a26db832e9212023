// Curved-domain Poisson benchmark shared with benchmarks/peers/dolfinx_poisson_ball.py: the unit
// ball meshed by Gmsh at geometric order K (written to MESH.msh so the peer solves on the same
// mesh), −Δu = f with u = (1 − r²) cos(x + 2y + 3z), u = 0 on the mesh boundary, P_p elements.
// Prints one JSON line.   curvefem_bench_poisson_ball H P K direct|cg THREADS MESH.msh
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "fem/problems/error_norms.hpp"
#include "fem/problems/poisson.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/io/cad_part.hpp"
#include "meshing/io/msh_io.hpp"

using namespace curvefem;

int main(int argc, char** argv) {
  if (argc < 7) {
    std::fprintf(stderr, "usage: %s H P K direct|cg THREADS MESH.msh\n", argv[0]);
    return 1;
  }
  const double h = std::atof(argv[1]);
  const int p = std::atoi(argv[2]), k = std::atoi(argv[3]);
  const std::string solver = argv[4];
  const int threads = std::atoi(argv[5]);
  log::set_level(log::Level::warn);
  const LagrangeMesh generated = io::make_ball_mesh(1.0, h, k);
  io::write_msh(argv[6], generated);
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  Stopwatch total, w;
  const LagrangeMesh mesh = io::read_msh(argv[6]);  // exactly what the peer reads
  const fem::FunctionSpace space = fem::build_function_space(mesh, p);
  const double t_space = w.seconds();
  auto u = [](const Eigen::Vector3d& x) {
    return (1 - x.squaredNorm()) * std::cos(x[0] + 2 * x[1] + 3 * x[2]);
  };
  fem::PoissonProblem problem;
  problem.rhs = [](const Eigen::Vector3d& x) {
    const double s = x[0] + 2 * x[1] + 3 * x[2], r2 = x.squaredNorm();
    // −Δ[(1 − r²) cos s] = 6 cos s − 4 (x·(1,2,3)) sin s + 14 (1 − r²) cos s
    return 6 * std::cos(s) - 4 * s * std::sin(s) + 14 * (1 - r2) * std::cos(s);
  };
  problem.dirichlet.push_back({std::vector<char>(space.boundary_faces.size(), 1),
                               [](const Eigen::Vector3d&) { return 0.0; },
                               {}});
  fem::LinearSolverOptions options;
  options.type = curvefem::fem::solver_type_from(solver);
  const auto sol = fem::solve_poisson(mesh, space, problem, options);
  w.reset();
  const auto e = fem::compute_errors(
      mesh, space, sol.u, 1, [&](const Eigen::Vector3d& x, double* v) { *v = u(x); },
      [](const Eigen::Vector3d& x, double* g) {
        const double s = x[0] + 2 * x[1] + 3 * x[2], wgt = 1 - x.squaredNorm();
        for (int d = 0; d < 3; ++d) g[d] = -2 * x[d] * std::cos(s) - wgt * std::sin(s) * (d + 1);
      });
  nlohmann::json j;
  j["code"] = "curvefem";
  j["p"] = p;
  j["k"] = k;
  j["tets"] = mesh.num_cells();
  j["dofs"] = space.num_dofs;
  j["threads"] = threads;
  j["solver"] = sol.solve.method;
  j["iterations"] = sol.solve.iterations;
  j["dofmap_s"] = t_space;
  j["assembly_s"] = sol.timings.get("assembly");
  j["setup_s"] = sol.solve.setup_s;
  j["solve_s"] = sol.solve.solve_s;
  j["solve_total_s"] = sol.timings.get("solve");
  j["errors_s"] = w.seconds();
  j["total_s"] = total.seconds();
  j["l2_error"] = e.l2;
  j["h1_semi_error"] = e.h1_semi;
  j["peak_rss_mb"] = peak_rss_mb();
  std::printf("%s\n", j.dump().c_str());
  return 0;
}
