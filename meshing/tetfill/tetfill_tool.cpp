// tetfill_tool IN [--size-factor X] [--no-optimize] [--threads N]
// Test/benchmark driver (benchmarks/run_tetfill.py): fills the inside of the surface IN, runs
// verify_tetfill again and prints one JSON line on stdout. Exit codes as DESIGN.md §3.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/tetfill/tetfill.hpp"

namespace tf = curvefem::meshing::tetfill;

namespace {

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\', out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

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
    std::printf(
        "{\"file\": %s, \"input_vertices\": %lld, \"input_faces\": %lld, \"vertices\": %lld, "
        "\"interior_vertices\": %lld, \"tets\": %lld, \"boundary_faces\": %lld, "
        "\"seconds\": %.4f, \"gmsh_seconds\": %.4f, \"verify_seconds\": %.4f, \"valid\": %s, "
        "\"non_positive_tets\": %d, \"missing_boundary_faces\": %d, "
        "\"extra_boundary_faces\": %d, \"moved_boundary_vertices\": %d, "
        "\"volume_error_rel\": %.3e, \"peak_rss_mb\": %.1f, \"error\": null}\n",
        json_string(input).c_str(), in_v, in_f, static_cast<long long>(r.V.rows()),
        static_cast<long long>(r.V.rows() - r.boundary_vertices),
        static_cast<long long>(r.T.rows()),
        in_f - v.missing_boundary_faces + v.extra_boundary_faces, r.seconds, r.gmsh_seconds,
        verify_seconds, v.valid() ? "true" : "false", v.non_positive_tets, v.missing_boundary_faces,
        v.extra_boundary_faces, v.moved_boundary_vertices, v.volume_error_rel,
        curvefem::peak_rss_mb());
    return v.valid() ? 0 : 3;
  } catch (const curvefem::Error& e) {
    std::printf(
        "{\"file\": %s, \"input_vertices\": %lld, \"input_faces\": %lld, \"valid\": false, "
        "\"peak_rss_mb\": %.1f, \"error\": %s}\n",
        json_string(input).c_str(), in_v, in_f, curvefem::peak_rss_mb(),
        json_string(e.what()).c_str());
    return e.exit_code();
  }
}
