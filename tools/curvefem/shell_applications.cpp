// The shell's applications behind `curvefem shell` options (shell_applications.hpp).
#include "tools/curvefem/shell_applications.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "meshing/check/check_surface.hpp"
#include "meshing/check/self_intersections.hpp"
#include "meshing/check/surface_distance.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/io/vtu_io.hpp"
#include "meshing/shell/displacement_map.hpp"
#include "meshing/shell/geometric_texture.hpp"
#include "meshing/shell/projection.hpp"
#include "meshing/shell/section.hpp"
#include "meshing/shell/section_transfer.hpp"

namespace curvefem::cli {
namespace {

namespace sh = meshing::shell;

// cage.obj: the shell's base, middle and top vertices (in that order, #V each) and the middle
// surface's faces: with displacement_map.txt all the rebuilt surface needs.
void write_cage(const std::filesystem::path& path, const sh::Shell& shell) {
  SurfaceMesh cage;
  const Eigen::Index n = shell.mid.rows();
  cage.V.resize(3 * n, 3);
  cage.V << shell.base, shell.mid, shell.top;
  cage.F = shell.F.array() + int(n);
  io::write_surface(path, cage, io::SurfaceFormat::obj);
}

}  // namespace

// --displacement-map L: bakes the heights through P (meshing/shell/displacement_map.hpp), writes
// displacement_map.txt, cage.obj (base, middle and top vertices in this order, the middle faces)
// and displaced.obj (the rebuilt surface), and checks the rebuilt surface with code independent
// of P: distance of its vertices to the input and a sampled Hausdorff distance (CGAL AABB),
// self-intersections (exact), and is_section (exact). The same subdivision displaced along the
// interpolated normals of the middle surface is measured beside it.
nlohmann::ordered_json run_displacement_map(const sh::Shell& shell, const SurfaceMesh& input,
                                            int level, const StagedOutputDir& out) {
  const double unit = bbox_longest_edge(input.V);
  Stopwatch clock;
  const sh::ShellProjection onto_input(shell, input);
  const sh::DisplacementMap map = sh::bake_displacement_map(onto_input, level);
  const double bake_s = clock.seconds();
  sh::write_displacement_map(out.path("displacement_map.txt").string(), map);
  // What a user stores and reads back: the map from its file, the cage from cage.obj's numbers.
  const sh::DisplacementMap stored =
      sh::read_displacement_map(out.path("displacement_map.txt").string());
  const sh::Reconstruction rebuilt = sh::reconstruct(shell, stored);
  io::write_surface(out.path("displaced.obj"), rebuilt.mesh, io::SurfaceFormat::obj);
  write_cage(out.path("cage.obj"), shell);
  const double rebuild_s = clock.seconds() - bake_s;
  auto measure = [&](const SurfaceMesh& m) {
    const Eigen::VectorXd on = check::distances_to_surface(m.V, input.V, input.F);
    const check::HausdorffEstimate h = check::sampled_hausdorff(m.V, m.F, input.V, input.F);
    const auto degenerate = check::exactly_degenerate_faces(m.V, m.F);
    const int pairs = int(check::find_self_intersections(m.V, m.F, degenerate, true).pairs.size());
    int degenerate_faces = 0;
    for (char d : degenerate) degenerate_faces += d;
    const sh::SectionCheck section = sh::check_section(onto_input, m);
    return nlohmann::ordered_json{{"is_section", section.is_section()},
                                  {"section_check",
                                   {{"manifold", section.manifold},
                                    {"vertices_outside", section.vertices_outside},
                                    {"faces_crossing_cage", section.faces_crossing_cage},
                                    {"faces_not_transversal", section.faces_not_transversal},
                                    {"degree_failures", section.degree_failures}}},
                                  {"self_intersecting_pairs", pairs},
                                  {"degenerate_faces", degenerate_faces},
                                  {"max_vertex_distance_rel", on.maxCoeff() / unit},
                                  {"hausdorff_rel", h.symmetric() / unit},
                                  {"to_input_max_rel", h.a_to_b / unit},
                                  {"from_input_max_rel", h.b_to_a / unit},
                                  {"to_input_mean_rel", h.mean_a_to_b / unit}};
  };
  nlohmann::ordered_json j = {{"level", level},
                              {"coarse_faces", int(shell.F.rows())},
                              {"samples", int(map.h.size())},
                              {"failures", map.failures},
                              {"rebuilt_vertices", rebuilt.mesh.num_vertices()},
                              {"rebuilt_faces", rebuilt.mesh.num_faces()}};
  j["rebuilt"] = measure(rebuilt.mesh);
  const sh::FiberCheck fibers = sh::check_on_fibers(onto_input, stored, rebuilt);
  j["rebuilt"]["vertices_not_located"] = fibers.not_located;
  j["rebuilt"]["fiber_offset_max_rel"] = fibers.max_offset / unit;
  const double check_s = clock.seconds() - bake_s - rebuild_s;
  int missed = 0;
  double reach = 0;
  for (Eigen::Index v = 0; v < shell.mid.rows(); ++v)
    reach = std::max({reach, (shell.top.row(v) - shell.mid.row(v)).norm(),
                      (shell.base.row(v) - shell.mid.row(v)).norm()});
  const sh::Reconstruction normals =
      sh::reconstruct_along_normals(shell, input, level, 2 * reach, &missed);
  j["along_normals"] = measure(normals.mesh);
  j["along_normals"]["reach_rel"] = 2 * reach / unit;
  j["along_normals"]["missed"] = missed;
  j["time_s"] = {
      {"bake", bake_s}, {"rebuild", rebuild_s}, {"checks", check_s}, {"total", clock.seconds()}};
  return j;
}

bool displacement_map_ok(const nlohmann::ordered_json& d) {
  return d["failures"].get<int>() == 0 && d["rebuilt"]["vertices_not_located"].get<int>() == 0 &&
         d["rebuilt"]["fiber_offset_max_rel"].get<double>() <= 1e-9 &&
         d["rebuilt"]["max_vertex_distance_rel"].get<double>() <= 1e-12;
}

namespace {

int pairs_between(const SurfaceMesh& a, const SurfaceMesh& b) {
  return check::intersecting_pairs_between(a.V, a.F, b.V, b.F);
}

}  // namespace

nlohmann::ordered_json run_nested_cages(const SurfaceMesh& input,
                                        const sh::NestedCageOptions& options,
                                        const StagedOutputDir& out) {
  Stopwatch clock;
  const sh::NestedCages cages = sh::build_nested_cages(input, options);
  const double build_s = clock.seconds();
  const double unit = bbox_longest_edge(input.V);
  std::vector<const SurfaceMesh*> layers{&input};
  for (const auto& layer : cages.layers) layers.push_back(&layer.cage);
  nlohmann::ordered_json j = {{"layers", int(cages.layers.size())}};
  nlohmann::ordered_json per_layer = nlohmann::ordered_json::array();
  for (std::size_t k = 0; k < cages.layers.size(); ++k) {
    const sh::CageLayer& layer = cages.layers[k];
    const std::string name = "cage_" + std::to_string(k + 1) + ".obj";
    io::write_surface(out.path(name), layer.cage, io::SurfaceFormat::obj);
    // The map down to the input at every face's centroid and first corner, and back up.
    std::vector<sh::MeshPoint> points;
    for (int f = 0; f < layer.cage.num_faces(); ++f) {
      points.push_back({f, Eigen::Vector3d::Constant(1.0 / 3)});
      points.push_back({f, Eigen::Vector3d(1, 0, 0)});
    }
    Eigen::MatrixXd start(Eigen::Index(points.size()), 3);
    for (std::size_t i = 0; i < points.size(); ++i) {
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      for (int c = 0; c < 3; ++c)
        x += points[i].bary[c] * Eigen::Vector3d(layer.cage.V.row(layer.cage.F(points[i].face, c)));
      start.row(Eigen::Index(i)) = x.transpose();
    }
    int down_failures = 0, up_failures = 0;
    std::vector<char> on_fill;
    const Eigen::MatrixXd down = sh::cage_to_input(cages, int(k), points, &down_failures, &on_fill);
    // Samples whose way down meets a fill map to the filled point and are not one to one
    // (nested_cages.hpp): the round trip is taken on the others.
    std::vector<Eigen::Index> mapped;
    for (std::size_t i = 0; i < points.size(); ++i)
      if (!on_fill[i]) mapped.push_back(Eigen::Index(i));
    double on_input = 0, roundtrip = 0;
    if (down_failures == 0) {
      on_input = check::distances_to_surface(down, input.V, input.F).maxCoeff() / unit;
      const Eigen::MatrixXd up =
          sh::input_to_cage(cages, int(k), down(mapped, Eigen::all), &up_failures);
      if (up_failures == 0 && !mapped.empty())
        roundtrip = (up - start(mapped, Eigen::all)).rowwise().norm().maxCoeff() / unit;
    }
    int fill_faces = 0;
    for (char c : layer.cage_face_on_fill) fill_faces += c;
    // The share of the cage's area whose way down meets a fill, by the faces' centroids.
    double area = 0, area_on_fills = 0;
    for (int f = 0; f < layer.cage.num_faces(); ++f) {
      const Eigen::Vector3d a = layer.cage.V.row(layer.cage.F(f, 0)),
                            b = layer.cage.V.row(layer.cage.F(f, 1)),
                            c = layer.cage.V.row(layer.cage.F(f, 2));
      const double af = (b - a).cross(c - a).norm();
      area += af;
      if (on_fill[2 * std::size_t(f)]) area_on_fills += af;
    }
    const Eigen::VectorXd gap = check::distances_to_surface(
        check::surface_samples(layer.cage.V, layer.cage.F, 3), layers[k]->V, layers[k]->F);
    per_layer.push_back(
        {{"file", name},
         {"faces", layer.cage.num_faces()},
         {"vertices", layer.cage.num_vertices()},
         {"shell", layer.attempt},
         {"singular_vertices", layer.singular_vertices},
         {"self_intersecting_pairs_before_shrinking", layer.self_intersecting_pairs_before},
         {"shrink_rounds", layer.shrink_rounds},
         {"shrunk_pillars", layer.shrunk_pillars},
         {"top_pinch_points_before_unpinching", layer.top_pinch_points_before},
         {"top_pinch_points", layer.top_pinch_points},
         {"unpinch_rounds", layer.unpinch_rounds},
         {"filled_points", layer.filled_points},
         {"unfilled_points", layer.unfilled_points},
         {"fill_faces", fill_faces},
         {"fill_size_rel", layer.fill_size / unit},
         {"shell_verified", layer.verification.valid()},
         {"self_intersecting_pairs",
          check::count_self_intersecting_pairs(layer.cage.V, layer.cage.F)},
         {"winding_number_of_layer_inside",
          check::winding_number(layer.cage.V, layer.cage.F, layers[k]->V.row(0).transpose())},
         {"min_gap_to_layer_inside_rel", gap.minCoeff() / unit},
         {"max_gap_to_layer_inside_rel", gap.maxCoeff() / unit},
         {"map_samples", int(points.size())},
         {"map_samples_on_fills", int(points.size() - mapped.size())},
         {"map_area_share_on_fills", area > 0 ? area_on_fills / area : 0.0},
         {"map_failures", down_failures + up_failures},
         {"map_to_input_max_distance_rel", on_input},
         {"map_roundtrip_max_rel", roundtrip},
         {"seconds", layer.seconds}});
  }
  j["per_layer"] = per_layer;
  // Every two layers, the input included: no intersecting pair.
  nlohmann::ordered_json between = nlohmann::ordered_json::array();
  int total = 0;
  for (std::size_t a = 0; a < layers.size(); ++a)
    for (std::size_t b = a + 1; b < layers.size(); ++b) {
      const int n = pairs_between(*layers[a], *layers[b]);
      total += n;
      between.push_back({{"layers", {int(a), int(b)}}, {"intersecting_pairs", n}});
    }
  j["between_layers"] = between;
  j["intersecting_pairs_between_layers"] = total;
  j["time_s"] = {{"build", build_s}, {"checks", clock.seconds() - build_s}};
  return j;
}

bool nested_cages_ok(const nlohmann::ordered_json& j) {
  if (j["intersecting_pairs_between_layers"].get<int>() != 0) return false;
  for (const auto& l : j["per_layer"])
    if (!l["shell_verified"].get<bool>() || l["self_intersecting_pairs"].get<int>() != 0 ||
        std::abs(l["winding_number_of_layer_inside"].get<double>() - 1) > 1e-6 ||
        l["map_failures"].get<int>() != 0 ||
        l["map_to_input_max_distance_rel"].get<double>() > 1e-12 ||
        l["map_roundtrip_max_rel"].get<double>() > 1e-9)
      return false;
  return true;
}

SurfaceMesh load_tile(const std::string& spec) {
  const bool from_file = spec.size() > 4 && spec.substr(spec.size() - 4) == ".obj";
  const SurfaceMesh tile = from_file ? io::read_surface(spec) : sh::builtin_tile(spec);
  sh::check_tile(tile, spec);
  return tile;
}

nlohmann::ordered_json run_geometric_texture(const sh::Shell& shell, const SurfaceMesh& surface,
                                             const SurfaceMesh& tile, const std::string& tile_spec,
                                             const StagedOutputDir& out) {
  Stopwatch clock;
  sh::Shell separated = shell;
  const sh::TileSeparation sep = sh::separate_for_tile(separated, surface, tile);
  nlohmann::ordered_json separation = nlohmann::ordered_json::object();
  auto side = [](const sh::SeparationStats& st, const std::string& why) {
    return nlohmann::ordered_json{{"self_intersecting_pairs_before", st.pairs_before},
                                  {"shrink_rounds", st.rounds},
                                  {"shortened_pillars", st.shortened_pillars},
                                  {"failure", why}};
  };
  if (sep.top) separation["top"] = side(sep.top_stats, sep.top_failure);
  if (sep.base) separation["base"] = side(sep.base_stats, sep.base_failure);
  const double separate_s = clock.seconds();
  const sh::ShellProjection onto_input(separated, surface);
  const sh::TexturedSurface textured = sh::apply_geometric_texture(onto_input, tile);
  const double map_s = clock.seconds() - separate_s;
  io::write_surface(out.path("textured.obj"), textured.mesh, io::SurfaceFormat::obj);
  nlohmann::ordered_json j = {{"tile", tile_spec},
                              {"tile_faces", tile.num_faces()},
                              {"copies", int(shell.F.rows()) - textured.skipped_pinched},
                              {"prisms", int(shell.F.rows())},
                              {"prisms_pinched_skipped", textured.skipped_pinched},
                              {"faces", textured.mesh.num_faces()},
                              {"shell_separation", separation}};
  {
    const SurfaceMesh& m = textured.mesh;
    const auto degenerate = check::exactly_degenerate_faces(m.V, m.F);
    int degenerate_faces = 0;
    for (char d : degenerate) degenerate_faces += d;
    j["degenerate_faces"] = degenerate_faces;
    j["self_intersecting_pairs"] =
        int(check::find_self_intersections(m.V, m.F, degenerate, false).pairs.size());
    j["pairs_with_input"] = pairs_between(m, surface);
    const double unit = bbox_longest_edge(surface.V);
    j["min_distance_to_input_rel"] =
        check::distances_to_surface(m.V, surface.V, surface.F).minCoeff() / unit;
  }
  j["time_s"] = {
      {"separate", separate_s}, {"map", map_s}, {"checks", clock.seconds() - separate_s - map_s}};
  return j;
}

bool geometric_texture_ok(const nlohmann::ordered_json& j) {
  return j["self_intersecting_pairs"].get<int>() == 0 && j["degenerate_faces"].get<int>() == 0;
}

BooleanInput prepare_boolean(const SurfaceMesh& a, const std::string& b_path,
                             const std::string& operation) {
  Stopwatch clock;
  BooleanInput in;
  in.a = a;
  in.b = io::read_surface(b_path);
  in.operation = operation;
  // CGAL's corefinement needs two closed, embedded, outward surfaces: say which one is not.
  for (const auto& [m, name] :
       {std::pair<const SurfaceMesh*, std::string>{&in.a, "the input"}, {&in.b, b_path}}) {
    const check::CheckReport c = check::check_surface(*m);
    if (!c.acceptable)
      throw InputError("boolean " + operation + ": " + name +
                       " is not a closed, embedded surface: " +
                       (c.defects.empty() ? std::string("empty") : c.defects.front().message));
  }
  in.result = sh::corefine_boolean(in.a, in.b, sh::parse_boolean_operation(operation));
  const SurfaceMesh& r = in.result.mesh;
  const auto degenerate = check::exactly_degenerate_faces(r.V, r.F);
  in.self_intersecting_pairs =
      int(check::find_self_intersections(r.V, r.F, degenerate, true).pairs.size());
  int degenerate_faces = 0;
  for (char d : degenerate) degenerate_faces += d;
  if (in.self_intersecting_pairs > 0 || degenerate_faces > 0)
    throw MeshingError("boolean " + operation + ": the result rounded to double has " +
                       std::to_string(in.self_intersecting_pairs) +
                       " self-intersecting face pairs and " + std::to_string(degenerate_faces) +
                       " degenerate faces; no shell can be built on it");
  in.seconds = clock.seconds();
  return in;
}

namespace {

/// The two operands' test fields: the smooth field of section_transfer.hpp on A, another on B
/// (shifted and scaled), so that the result shows where each part came from.
double operand_field(int operand, const Eigen::Vector3d& x, const Eigen::Vector3d& center,
                     double scale) {
  const Eigen::Vector3d p = (x - center) / scale;
  return operand == 0 ? std::sin(3 * p.x()) * std::cos(2 * p.y()) + p.z() * p.z()
                      : 2 + std::cos(2 * p.x() + p.z()) * std::sin(3 * p.y());
}

}  // namespace

nlohmann::ordered_json run_boolean_transfer(const BooleanInput& in, const sh::Shell& shell,
                                            const sh::BeveledSurface& surface,
                                            const StagedOutputDir& out) {
  Stopwatch clock;
  const SurfaceMesh& r = in.result.mesh;
  const double unit = bbox_longest_edge(r.V);
  const Eigen::Vector3d center =
      0.5 * (r.V.colwise().minCoeff() + r.V.colwise().maxCoeff()).transpose();
  const double scale = 0.5 * unit;
  // Operand fields at the operands' vertices, interpolated linearly in their faces.
  auto field_on = [&](int operand, int face, const Eigen::Vector3d& bary) {
    const SurfaceMesh& m = operand == 0 ? in.a : in.b;
    double v = 0;
    for (int k = 0; k < 3; ++k)
      v += bary[k] * operand_field(operand, m.V.row(m.F(face, k)).transpose(), center, scale);
    return v;
  };
  // The result's vertices: through the first face holding each.
  std::vector<int> first_face(std::size_t(r.num_vertices()), -1);
  for (int f = 0; f < r.num_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      if (first_face[std::size_t(r.F(f, k))] < 0) first_face[std::size_t(r.F(f, k))] = f;
  const auto at_result = sh::locate_in_operands(in.a, in.b, in.result, r.V, first_face);
  Eigen::VectorXd result_field(r.num_vertices()), result_operand_cells(r.num_faces());
  for (int v = 0; v < r.num_vertices(); ++v)
    result_field[v] = field_on(at_result[std::size_t(v)].operand, at_result[std::size_t(v)].face,
                               at_result[std::size_t(v)].bary);
  for (int f = 0; f < r.num_faces(); ++f)
    result_operand_cells[f] = in.result.operand[std::size_t(f)];
  MeshFields rf;
  rf.point_data.push_back(
      {"field", 1,
       std::vector<double>(result_field.data(), result_field.data() + result_field.size())});
  rf.cell_data.push_back(
      {"operand", 1,
       std::vector<double>(result_operand_cells.data(),
                           result_operand_cells.data() + result_operand_cells.size())});
  io::write_vtu(out.path("result.vtu"), as_triangle_mesh(r), rf);
  // The coarse middle surface: each vertex through P to the result (the beveled refinement's
  // point, then its place in the result face), then to its operand.
  const sh::ShellProjection onto(shell, surface.mesh);
  const int n = int(shell.mid.rows());
  Eigen::MatrixXd image(n, 3);
  std::vector<int> image_face(std::size_t(n), -1);
  int failures = 0;
  for (int v = 0; v < n; ++v) {
    const auto s = onto.project(Eigen::Vector3d(shell.mid.row(v)));
    if (!s) {
      ++failures;
      image.row(v) = shell.mid.row(v);
      image_face[std::size_t(v)] = 0;
      continue;
    }
    const auto [face, bary] = surface.refined() ? surface.to_input(s->face, s->bary)
                                                : std::pair<int, Eigen::Vector3d>{s->face, s->bary};
    image_face[std::size_t(v)] = face;
    image.row(v) = s->position.transpose();
  }
  const auto at_coarse = sh::locate_in_operands(in.a, in.b, in.result, image, image_face);
  Eigen::VectorXd coarse_field(n), coarse_operand(n);
  double field_error = 0, on_operand = 0;
  Eigen::MatrixXd on_a(0, 3), on_b(0, 3);
  std::vector<Eigen::Vector3d> pa, pb;
  for (int v = 0; v < n; ++v) {
    const auto& o = at_coarse[std::size_t(v)];
    coarse_field[v] = field_on(o.operand, o.face, o.bary);
    coarse_operand[v] = o.operand;
    field_error = std::max(
        field_error, std::abs(coarse_field[v] -
                              operand_field(o.operand, image.row(v).transpose(), center, scale)));
    (o.operand == 0 ? pa : pb).push_back(image.row(v).transpose());
  }
  auto max_distance = [&](const std::vector<Eigen::Vector3d>& pts, const SurfaceMesh& m) {
    if (pts.empty()) return 0.0;
    Eigen::MatrixXd P(Eigen::Index(pts.size()), 3);
    for (std::size_t i = 0; i < pts.size(); ++i) P.row(Eigen::Index(i)) = pts[i].transpose();
    return check::distances_to_surface(P, m.V, m.F).maxCoeff();
  };
  on_operand = std::max(max_distance(pa, in.a), max_distance(pb, in.b)) / unit;
  SurfaceMesh middle;
  middle.V = shell.mid;
  middle.F = shell.F;
  MeshFields cf;
  cf.point_data.push_back(
      {"field", 1, std::vector<double>(coarse_field.data(), coarse_field.data() + n)});
  cf.point_data.push_back(
      {"operand", 1, std::vector<double>(coarse_operand.data(), coarse_operand.data() + n)});
  io::write_vtu(out.path("remeshed.vtu"), as_triangle_mesh(middle), cf);
  int from_a = 0;
  for (int o : in.result.operand) from_a += o == 0;
  return {{"operation", in.operation},
          {"operand_faces", {in.a.num_faces(), in.b.num_faces()}},
          {"result_faces", r.num_faces()},
          {"result_faces_from_a", from_a},
          {"result_faces_from_b", r.num_faces() - from_a},
          {"result_self_intersecting_pairs", in.self_intersecting_pairs},
          {"origin_max_distance_rel", in.result.max_origin_distance / unit},
          {"remeshed_vertices", n},
          {"remeshed_faces", int(shell.F.rows())},
          {"map_failures", failures},
          {"map_to_operand_max_distance_rel", on_operand},
          {"field_max_error", field_error},
          {"field",
           "A: sin(3x) cos(2y) + z^2, B: 2 + cos(2x + z) sin(3y), at (p - bbox center) / (longest "
           "bbox edge / 2), interpolated linearly in the operand's faces"},
          {"time_s", {{"corefine", in.seconds}, {"transfer", clock.seconds()}}}};
}

bool boolean_ok(const nlohmann::ordered_json& j) {
  return j["map_failures"].get<int>() == 0 &&
         j["map_to_operand_max_distance_rel"].get<double>() <= 1e-12 &&
         j["result_self_intersecting_pairs"].get<int>() == 0;
}

}  // namespace curvefem::cli
