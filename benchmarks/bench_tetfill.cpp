// tetfill_tool IN [--size-factor X] [--no-optimize] [--threads N]
// Benchmark driver (benchmarks/run_tetfill.py, run_curved.py): fills the inside of the surface IN,
// runs verify_tetfill again and prints one JSON line on stdout. Exit codes as DESIGN.md §3.
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>

#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/tetfill/tetfill.hpp"

namespace tf = curvefem::meshing::tetfill;

namespace {

int usage() {
  std::fprintf(stderr, "usage: tetfill_tool IN [--size-factor X] [--no-optimize] [--threads N]\n");
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage();
  const std::string input = argv[1];
  tf::TetFillOptions options;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--size-factor" && i + 1 < argc) {
      options.size_factor = std::atof(argv[++i]);
    } else if (a == "--threads" && i + 1 < argc) {
      options.threads = std::atoi(argv[++i]);
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
    const nlohmann::ordered_json j = {
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
