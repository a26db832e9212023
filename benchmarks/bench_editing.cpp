// Surface editing benchmark shared with CGAL 5.5 (driven by benchmarks/run_editing.py): one
// algorithm, one engine, one run; the mesh is loaded before the clock starts. Prints ONE JSON line.
//
//   curvefem_bench_editing INPUT ALGORITHM [--target-faces N] [--target-edge R] [--threads T]
//                          [--engine curvefem|cgal] [--output OUT.obj]
//   ALGORITHM: shortest_collapse | qslim | isotropic | info (input statistics only)
//
// CGAL peers (always serial, whatever --threads says):
//   shortest_collapse  SMS::edge_collapse, Edge_length_cost + Midpoint_placement
//   qslim              SMS::edge_collapse, GarlandHeckbert_plane_policies (classic plane quadrics)
//   isotropic          PMP::isotropic_remeshing(faces, R, mesh, number_of_iterations(5))
// Both simplifications stop at or below N faces (a face-count stop predicate: CGAL 5.5 has no
// Face_count_stop_predicate, and its Count_stop_predicate counts edges).
// `seconds` is the wall time of the algorithm call: for CGAL without the conversion to and from
// Surface_mesh (reported as cgal_convert_s), for curvefem the whole remesh() call (which builds and
// exports its own TriMesh; remesh_internal_s is RemeshResult::seconds). Quality is curvefem's
// measure_quality(output, input) for both engines.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Edge_length_cost.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Midpoint_placement.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>
#include <tbb/global_control.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "meshing/core/log.hpp"
#include "meshing/core/surface_mesh.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/editing/algorithms/surface_remeshing.hpp"
#include "meshing/io/surface_io.hpp"

using namespace curvefem;
namespace editing = curvefem::meshing::editing;

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace SMS = CGAL::Surface_mesh_simplification;
namespace PMP = CGAL::Polygon_mesh_processing;

CgalMesh to_cgal(const SurfaceMesh& s) {
  CgalMesh m;
  m.reserve(s.num_vertices(), 3 * s.num_faces() / 2 + 16, s.num_faces());
  std::vector<CgalMesh::Vertex_index> v(s.num_vertices());
  for (int i = 0; i < s.num_vertices(); ++i)
    v[i] = m.add_vertex(Kernel::Point_3(s.V(i, 0), s.V(i, 1), s.V(i, 2)));
  for (int f = 0; f < s.num_faces(); ++f) {
    if (m.add_face(v[s.F(f, 0)], v[s.F(f, 1)], v[s.F(f, 2)]) == CgalMesh::null_face())
      throw std::runtime_error("CGAL Surface_mesh rejected face " + std::to_string(f) +
                               " (non-manifold input?)");
  }
  return m;
}

SurfaceMesh from_cgal(const CgalMesh& m) {
  SurfaceMesh s;
  s.V.resize(m.number_of_vertices(), 3);
  s.F.resize(m.number_of_faces(), 3);
  std::unordered_map<std::size_t, int> id;
  id.reserve(m.number_of_vertices());
  int n = 0;
  for (auto v : m.vertices()) {
    const auto& p = m.point(v);
    s.V.row(n) << p.x(), p.y(), p.z();
    id[std::size_t(v)] = n++;
  }
  int k = 0;
  for (auto f : m.faces()) {
    int c = 0;
    for (auto v : CGAL::vertices_around_face(m.halfedge(f), m)) {
      if (c == 3) throw std::runtime_error("CGAL output has a non-triangle face");
      s.F(k, c++) = id.at(std::size_t(v));
    }
    if (c != 3) throw std::runtime_error("CGAL output has a degenerate face");
    ++k;
  }
  return s;
}

// Stops once the live face count is at or below the target (Surface_mesh::number_of_faces()
// excludes removed faces and is O(1)).
struct FaceCountStop {
  const CgalMesh* mesh;
  std::size_t target;
  template <typename F, typename Profile>
  bool operator()(const F&, const Profile&, std::size_t, std::size_t) const {
    return mesh->number_of_faces() <= target;
  }
};

double mean_edge_length(const SurfaceMesh& s) {
  // Each undirected edge once.
  std::unordered_map<long long, char> seen;
  seen.reserve(3 * s.num_faces());
  double sum = 0;
  std::size_t count = 0;
  for (int f = 0; f < s.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) {
      int a = s.F(f, c), b = s.F(f, (c + 1) % 3);
      if (a > b) std::swap(a, b);
      if (!seen.emplace((long long)a * s.num_vertices() + b, 1).second) continue;
      sum += (s.V.row(a) - s.V.row(b)).norm();
      ++count;
    }
  return count ? sum / count : 0;
}

nlohmann::json quality_json(const editing::SurfaceQuality& q, double bbox) {
  nlohmann::json j;
  j["vertices"] = q.vertices;
  j["faces"] = q.faces;
  j["min_angle_deg"] = q.min_angle_deg;
  j["max_angle_deg"] = q.max_angle_deg;
  j["min_edge"] = q.min_edge;
  j["mean_edge"] = q.mean_edge;
  j["max_edge"] = q.max_edge;
  j["max_deviation"] = q.max_deviation;
  j["max_deviation_from_reference"] = q.max_deviation_from_reference;
  j["max_deviation_rel"] = bbox > 0 ? q.max_deviation / bbox : 0;
  j["max_deviation_from_reference_rel"] = bbox > 0 ? q.max_deviation_from_reference / bbox : 0;
  std::size_t total = 0, six = 0, five_to_seven = 0;
  int vmin = 0, vmax = 0;
  nlohmann::json hist = nlohmann::json::object();
  for (const auto& [valence, n] : q.valence_histogram) {
    hist[std::to_string(valence)] = n;
    if (total == 0) vmin = valence;
    vmax = valence;
    total += n;
    if (valence == 6) six += n;
    if (valence >= 5 && valence <= 7) five_to_seven += n;
  }
  j["valence_histogram"] = hist;
  j["valence_min"] = vmin;
  j["valence_max"] = vmax;
  j["valence6_share"] = total ? double(six) / total : 0;
  j["valence5to7_share"] = total ? double(five_to_seven) / total : 0;
  return j;
}

[[noreturn]] void usage(const char* argv0) {
  std::fprintf(stderr,
               "usage: %s INPUT shortest_collapse|qslim|isotropic|info [--target-faces N] "
               "[--target-edge R] [--threads T] [--engine curvefem|cgal] [--output OUT.obj]\n",
               argv0);
  std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) usage(argv[0]);
  const std::string input_path = argv[1], algorithm = argv[2];
  std::size_t target_faces = 0;
  double target_edge = 0;
  int threads = 1;
  std::string engine = "curvefem", output_path;
  for (int i = 3; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc) usage(argv[0]);
    const char* v = argv[++i];
    if (a == "--target-faces")
      target_faces = std::strtoull(v, nullptr, 10);
    else if (a == "--target-edge")
      target_edge = std::atof(v);
    else if (a == "--threads")
      threads = std::atoi(v);
    else if (a == "--engine")
      engine = v;
    else if (a == "--output")
      output_path = v;
    else
      usage(argv[0]);
  }
  if (algorithm != "shortest_collapse" && algorithm != "qslim" && algorithm != "isotropic" &&
      algorithm != "info")
    usage(argv[0]);
  if (engine != "curvefem" && engine != "cgal") usage(argv[0]);
  if (engine == "cgal") threads = 1;  // CGAL's SMS and isotropic remeshing are serial
  if (threads < 1) threads = 1;
  log::set_level(log::Level::warn);

  try {
    const SurfaceMesh input = io::read_surface(input_path);
    const double bbox = bbox_longest_edge(input.V);
    const double input_mean_edge = mean_edge_length(input);
    nlohmann::json j;
    j["input"] = input_path;
    j["input_faces"] = input.num_faces();
    j["input_vertices"] = input.num_vertices();
    j["input_mean_edge"] = input_mean_edge;
    j["bbox_longest_edge"] = bbox;
    if (algorithm == "info") {
      std::printf("%s\n", j.dump().c_str());
      return 0;
    }
    if (algorithm == "isotropic" && target_edge <= 0) target_edge = 2 * input_mean_edge;
    if (algorithm != "isotropic" && target_faces == 0) target_faces = input.num_faces() / 10;
    j["engine"] = engine;
    j["algorithm"] = algorithm;
    j["threads"] = threads;
    if (algorithm == "isotropic")
      j["target_edge"] = target_edge;
    else
      j["target_faces"] = target_faces;

    SurfaceMesh output;
    double seconds = 0;
    if (engine == "cgal") {
      Stopwatch convert;
      CgalMesh mesh = to_cgal(input);
      double convert_s = convert.seconds();
      Stopwatch w;
      if (algorithm == "shortest_collapse") {
        SMS::edge_collapse(mesh, FaceCountStop{&mesh, target_faces},
                           CGAL::parameters::get_cost(SMS::Edge_length_cost<CgalMesh>())
                               .get_placement(SMS::Midpoint_placement<CgalMesh>()));
      } else if (algorithm == "qslim") {
        SMS::GarlandHeckbert_plane_policies<CgalMesh, Kernel> gh(mesh);
        SMS::edge_collapse(
            mesh, FaceCountStop{&mesh, target_faces},
            CGAL::parameters::get_cost(gh.get_cost()).get_placement(gh.get_placement()));
      } else {
        PMP::isotropic_remeshing(faces(mesh), target_edge, mesh,
                                 CGAL::parameters::number_of_iterations(5));
        j["iterations"] = 5;
      }
      seconds = w.seconds();
      convert.reset();
      mesh.collect_garbage();
      output = from_cgal(mesh);
      j["cgal_convert_s"] = convert_s + convert.seconds();
    } else {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
      editing::RemeshOptions options;
      using editing::RemeshAlgorithm;
      options.algorithm = algorithm == "shortest_collapse" ? RemeshAlgorithm::shortest_collapse
                          : algorithm == "qslim"           ? RemeshAlgorithm::qslim
                                                           : RemeshAlgorithm::isotropic;
      options.target_faces = target_faces;
      options.target_edge = target_edge;
      options.threads = threads;
      if (algorithm == "isotropic") j["iterations"] = options.iterations;
      Stopwatch w;
      editing::RemeshResult result = editing::remesh(input, options);
      seconds = w.seconds();
      j["remesh_internal_s"] = result.seconds;
      nlohmann::json passes = nlohmann::json::array();
      for (const auto& [name, p] : result.passes)
        passes.push_back({{"name", name},
                          {"attempted", p.attempted},
                          {"succeeded", p.succeeded},
                          {"rejected_before", p.rejected_before},
                          {"rejected_topology", p.rejected_topology},
                          {"rejected_after", p.rejected_after},
                          {"rejected_invariant", p.rejected_invariant},
                          {"stale_tuple", p.stale_tuple},
                          {"stale_priority", p.stale_priority},
                          {"lock_failures", p.lock_failures},
                          {"serial_tail", p.serial_tail},
                          {"threads", p.threads},
                          {"seconds", p.seconds}});
      j["passes"] = passes;
      output = std::move(result.mesh);
    }
    j["seconds"] = seconds;
    j["output_faces"] = output.num_faces();
    j["output_vertices"] = output.num_vertices();
    j["peak_rss_mb"] = peak_rss_mb();
    Stopwatch wq;
    j["quality"] = quality_json(editing::measure_quality(output, input), bbox);
    j["quality_s"] = wq.seconds();
    if (!output_path.empty())
      io::write_surface(output_path, output, io::surface_format_from_extension(output_path));
    std::printf("%s\n", j.dump().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
