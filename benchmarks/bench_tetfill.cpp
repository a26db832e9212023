// tetfill_tool IN [--size-factor X] [--no-optimize] [--threads N] [--flips]
// Benchmark driver (benchmarks/run_tetfill.py, run_curved.py): fills the inside of the surface IN,
// runs verify_tetfill again and prints one JSON line on stdout. Exit codes as DESIGN.md §3.
// --flips: then runs the curved mesher's interior quality flips (editing::flip_tets, on
// --threads threads) on the fill and reports their time, count and energies (flips_*).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>

#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/editing/algorithms/tet_flips.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/tetfill/tetfill.hpp"

namespace tf = curvefem::meshing::tetfill;

namespace {

int usage() {
  std::fprintf(
      stderr, "usage: tetfill_tool IN [--size-factor X] [--no-optimize] [--threads N] [--flips]\n");
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage();
  const std::string input = argv[1];
  tf::TetFillOptions options;
  bool flips = false;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--size-factor" && i + 1 < argc) {
      options.size_factor = std::atof(argv[++i]);
    } else if (a == "--threads" && i + 1 < argc) {
      options.threads = std::atoi(argv[++i]);
    } else if (a == "--flips") {
      flips = true;
    } else if (a == "--no-optimize") {
      options.optimize = false;
    } else {
      return usage();
    }
  }
  curvefem::log::set_level(curvefem::log::Level::warn);
  long long in_v = -1, in_f = -1;
  try {
    const curvefem::SurfaceMesh mesh = curvefem::io::read_surface(input);
    in_v = mesh.num_vertices(), in_f = mesh.num_faces();
    const tf::TetFillResult r = tf::fill_interior(mesh.V, mesh.F, options);
    curvefem::Stopwatch watch;
    const tf::TetFillVerification v = tf::verify_tetfill(mesh.V, mesh.F, r);
    const double verify_seconds = watch.seconds();
    nlohmann::ordered_json j = {
        {"file", input},
        {"input_vertices", in_v},
        {"input_faces", in_f},
        {"vertices", r.V.rows()},
        {"interior_vertices", r.V.rows() - r.boundary_vertices},
        {"tets", r.T.rows()},
        {"boundary_faces", in_f - v.missing_boundary_faces + v.extra_boundary_faces},
        {"seconds", r.seconds},
        {"gmsh_seconds", r.gmsh_seconds},
        {"verify_seconds", verify_seconds},
        {"valid", v.valid()},
        {"non_positive_tets", v.non_positive_tets},
        {"missing_boundary_faces", v.missing_boundary_faces},
        {"extra_boundary_faces", v.extra_boundary_faces},
        {"moved_boundary_vertices", v.moved_boundary_vertices},
        {"volume_error_rel", v.volume_error_rel},
        {"peak_rss_mb", curvefem::peak_rss_mb()},
        {"error", nullptr}};
    if (flips) {
      curvefem::meshing::editing::FlipOptions fo;
      fo.threads = std::max(options.threads, 1);
      watch = curvefem::Stopwatch();
      const auto f = curvefem::meshing::editing::flip_tets(r.V, r.T, fo);
      j["flips_seconds"] = watch.seconds();
      j["flips_succeeded"] = f.pass.succeeded;
      j["flips_attempted"] = f.pass.attempted;
      j["flips_tets_after"] = f.T.rows();
      j["flips_max_energy"] = {f.max_energy_before, f.max_energy_after};
      j["flips_mean_energy"] = {f.mean_energy_before, f.mean_energy_after};
      j["flips_pass"] = f.pass.summary();
      j["peak_rss_mb"] = curvefem::peak_rss_mb();
    }
    std::printf("%s\n", j.dump().c_str());
    return v.valid() ? 0 : 3;
  } catch (const curvefem::Error& e) {
    const nlohmann::ordered_json j = {{"file", input},
                                      {"input_vertices", in_v},
                                      {"input_faces", in_f},
                                      {"valid", false},
                                      {"peak_rss_mb", curvefem::peak_rss_mb()},
                                      {"error", e.what()}};
    std::printf("%s\n", j.dump().c_str());
    return e.exit_code();
  }
}
