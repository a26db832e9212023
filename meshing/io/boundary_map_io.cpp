#include "meshing/io/boundary_map_io.hpp"

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"

namespace curvefem::io {

namespace {
nlohmann::ordered_json rows(const Eigen::MatrixXd& M) {
  auto out = nlohmann::ordered_json::array();
  for (int r = 0; r < M.rows(); ++r) {
    auto row = nlohmann::ordered_json::array();
    for (int c = 0; c < M.cols(); ++c) row.push_back(M(r, c));
    out.push_back(std::move(row));
  }
  return out;
}
Eigen::MatrixXd read_rows(const nlohmann::json& j, int cols = 3) {
  Eigen::MatrixXd M(Eigen::Index(j.size()), cols);
  for (std::size_t r = 0; r < j.size(); ++r)
    for (int c = 0; c < cols; ++c) M(Eigen::Index(r), c) = j[r].at(std::size_t(c)).get<double>();
  return M;
}
}  // namespace

void write_boundary_map(const std::filesystem::path& path, const BoundaryMap& map,
                        const std::string& input, const ShellFibers* fibers,
                        const std::string& input_checksum) {
  nlohmann::ordered_json j;
  j["format"] = "curvefem-boundary-map";
  j["version"] = k_boundary_map_version;
  j["input"] = input;
  if (!input_checksum.empty()) j["input_checksum"] = input_checksum;
  j["order"] = map.boundary.order;
  j["input_vertices"] = map.num_input_vertices();
  auto& nodes = j["boundary"]["nodes"] = nlohmann::ordered_json::array();
  for (int n = 0; n < map.boundary.num_nodes(); ++n)
    nodes.push_back({map.boundary.nodes(n, 0), map.boundary.nodes(n, 1), map.boundary.nodes(n, 2)});
  auto& tris = j["boundary"]["triangles"] = nlohmann::ordered_json::array();
  for (int f = 0; f < map.boundary.num_cells(); ++f) {
    auto row = nlohmann::ordered_json::array();
    for (int c = 0; c < map.boundary.cells.cols(); ++c) row.push_back(map.boundary.cells(f, c));
    tris.push_back(row);
  }
  auto& vol = j["boundary"]["volume_node"] = nlohmann::ordered_json::array();
  for (int n = 0; n < map.boundary_node_to_volume.size(); ++n)
    vol.push_back(map.boundary_node_to_volume[n]);
  // Filled apart, then moved in: a reference to one member of an ordered_json object does not
  // survive adding the next (members live in a vector).
  auto vf = nlohmann::ordered_json::array(), uv = nlohmann::ordered_json::array();
  for (int v = 0; v < map.num_input_vertices(); ++v) {
    vf.push_back(map.vertex_face[v]);
    uv.push_back({map.vertex_uv(v, 0), map.vertex_uv(v, 1)});
  }
  j["vertex_face"] = std::move(vf);
  j["vertex_uv"] = std::move(uv);
  if (!map.feature_edges.empty()) j["feature_edges"] = map.feature_edges;
  if (!map.eps_scale.empty()) j["eps_scale"] = map.eps_scale;
  if (map.num_points() > 0) {
    auto in_face = nlohmann::ordered_json::array(), bary = nlohmann::ordered_json::array(),
         face = nlohmann::ordered_json::array(), puv = nlohmann::ordered_json::array();
    for (int i = 0; i < map.num_points(); ++i) {
      in_face.push_back(map.point_input_face[i]);
      bary.push_back({map.point_bary(i, 0), map.point_bary(i, 1), map.point_bary(i, 2)});
      face.push_back(map.point_face[i]);
      puv.push_back({map.point_uv(i, 0), map.point_uv(i, 1)});
    }
    auto& pts = j["distance_points"];
    pts["input_face"] = std::move(in_face);
    pts["bary"] = std::move(bary);
    pts["face"] = std::move(face);
    pts["uv"] = std::move(puv);
  }
  if (fibers) {
    CF_VERIFY(fibers->num_prisms() == map.boundary.num_cells(),
              "write_boundary_map: the fibers have " + std::to_string(fibers->num_prisms()) +
                  " prisms for " + std::to_string(map.boundary.num_cells()) +
                  " boundary triangles");
    nlohmann::ordered_json s;
    s["base"] = rows(fibers->base);
    s["mid"] = rows(fibers->mid);
    s["top"] = rows(fibers->top);
    auto F = nlohmann::ordered_json::array();
    for (int f = 0; f < fibers->num_prisms(); ++f)
      F.push_back({fibers->faces(f, 0), fibers->faces(f, 1), fibers->faces(f, 2)});
    s["faces"] = std::move(F);
    if (!fibers->reference_vertices.empty()) {  // [input vertex, x, y, z] in the reference copy
      auto r = nlohmann::ordered_json::array();
      for (std::size_t i = 0; i < fibers->reference_vertices.size(); ++i) {
        const Eigen::Index k = Eigen::Index(i);
        r.push_back({fibers->reference_vertices[i], fibers->reference_positions(k, 0),
                     fibers->reference_positions(k, 1), fibers->reference_positions(k, 2)});
      }
      s["reference"] = std::move(r);
    }
    auto candidates = nlohmann::ordered_json::array();
    for (int f = 0; f < fibers->num_prisms(); ++f) {
      const auto c = fibers->candidates(f);
      candidates.push_back(std::vector<int>(c.begin(), c.end()));
    }
    s["candidates"] = std::move(candidates);
    if (fibers->refined()) {  // the refined surface the fibers cross (ShellFibers)
      nlohmann::ordered_json r;
      r["points"] = rows(fibers->surface_points);
      auto RF = nlohmann::ordered_json::array();
      for (Eigen::Index f = 0; f < fibers->surface_faces.rows(); ++f)
        RF.push_back({fibers->surface_faces(f, 0), fibers->surface_faces(f, 1),
                      fibers->surface_faces(f, 2)});
      r["faces"] = std::move(RF);
      r["parent"] = fibers->surface_parent;
      r["bary"] = rows(fibers->surface_bary);
      s["surface"] = std::move(r);
    }
    j["fibers"] = std::move(s);
  }
  write_text_file_atomic(path, j.dump() + "\n");
}

SavedBoundaryMap read_boundary_map(const std::filesystem::path& path) {
  std::ifstream f(path);
  if (!f) throw IoError(path.string() + ": cannot open");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(f);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path.string() + ": not valid JSON: " + e.what());
  }
  SavedBoundaryMap saved;
  BoundaryMap& map = saved.map;
  try {
    saved.input = j.value("input", std::string());
    saved.input_checksum = j.value("input_checksum", std::string());
    if (j.at("format") != "curvefem-boundary-map")
      throw InputError(path.string() + ": not a curvefem boundary map");
    const int version = j.at("version").get<int>();
    if (version == 1 && j.contains("shell"))
      throw InputError(path.string() +
                       ": boundary map version 1 stores the coarse shell, which φ⁻¹ no longer "
                       "reads; re-run `curvefem mesh` to write version " +
                       std::to_string(k_boundary_map_version) + " (with the shell's fibers)");
    if (version < 1 || version > k_boundary_map_version)
      throw InputError(path.string() + ": boundary map version " + std::to_string(version) +
                       " is not supported (this build reads 1 without a shell, and 2 to " +
                       std::to_string(k_boundary_map_version) + ")");
    map.boundary.kind = CellKind::triangle;
    map.boundary.order = j.at("order").get<int>();
    if (map.boundary.order < 1 || map.boundary.order > k_max_order)
      throw InputError(path.string() + ": order out of range");
    const auto& nodes = j.at("boundary").at("nodes");
    map.boundary.nodes.resize(Eigen::Index(nodes.size()), 3);
    for (std::size_t n = 0; n < nodes.size(); ++n)
      for (int d = 0; d < 3; ++d) map.boundary.nodes(Eigen::Index(n), d) = nodes[n].at(d);
    const auto& tris = j.at("boundary").at("triangles");
    const int per = num_lagrange_nodes(CellKind::triangle, map.boundary.order);
    map.boundary.cells.resize(Eigen::Index(tris.size()), per);
    for (std::size_t f = 0; f < tris.size(); ++f) {
      if (int(tris[f].size()) != per)
        throw InputError(path.string() + ": triangle " + std::to_string(f) + " has " +
                         std::to_string(tris[f].size()) + " nodes, expected " +
                         std::to_string(per));
      for (int c = 0; c < per; ++c) map.boundary.cells(Eigen::Index(f), c) = tris[f][c];
    }
    const auto& vol = j.at("boundary").at("volume_node");
    map.boundary_node_to_volume.resize(Eigen::Index(vol.size()));
    for (std::size_t n = 0; n < vol.size(); ++n)
      map.boundary_node_to_volume[Eigen::Index(n)] = vol[n];
    const auto& vf = j.at("vertex_face");
    const auto& uv = j.at("vertex_uv");
    if (vf.size() != uv.size())
      throw InputError(path.string() + ": vertex_face and vertex_uv differ in length");
    map.vertex_face.resize(Eigen::Index(vf.size()));
    map.vertex_uv.resize(Eigen::Index(vf.size()), 2);
    for (std::size_t v = 0; v < vf.size(); ++v) {
      map.vertex_face[Eigen::Index(v)] = vf[v];
      map.vertex_uv(Eigen::Index(v), 0) = uv[v].at(0);
      map.vertex_uv(Eigen::Index(v), 1) = uv[v].at(1);
    }
    if (j.contains("feature_edges"))
      map.feature_edges = j.at("feature_edges").get<std::vector<std::array<int, 2>>>();
    if (j.contains("eps_scale")) {
      map.eps_scale = j.at("eps_scale").get<std::vector<double>>();
      if (map.eps_scale.size() != vf.size())
        throw InputError(path.string() + ": eps_scale has " + std::to_string(map.eps_scale.size()) +
                         " entries for " + std::to_string(vf.size()) + " input vertices");
      for (std::size_t v = 0; v < map.eps_scale.size(); ++v)
        if (!(map.eps_scale[v] > 0 && map.eps_scale[v] <= 1))
          throw InputError(path.string() + ": eps_scale of input vertex " + std::to_string(v) +
                           " is not in (0, 1]");
    }
    if (j.contains("distance_points")) {
      const auto& pts = j.at("distance_points");
      const auto& in_face = pts.at("input_face");
      const auto& bary = pts.at("bary");
      const auto& face = pts.at("face");
      const auto& puv = pts.at("uv");
      const std::size_t n = face.size();
      if (in_face.size() != n || bary.size() != n || puv.size() != n)
        throw InputError(path.string() + ": distance_points arrays differ in length");
      map.point_input_face.resize(Eigen::Index(n));
      map.point_bary.resize(Eigen::Index(n), 3);
      map.point_face.resize(Eigen::Index(n));
      map.point_uv.resize(Eigen::Index(n), 2);
      for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Index r = Eigen::Index(i);
        map.point_input_face[r] = in_face[i];
        map.point_face[r] = face[i];
        for (int c = 0; c < 3; ++c) map.point_bary(r, c) = bary[i].at(c);
        for (int c = 0; c < 2; ++c) map.point_uv(r, c) = puv[i].at(c);
      }
    }
    if (j.contains("fibers")) {
      const auto& s = j.at("fibers");
      ShellFibers fibers;
      fibers.base = read_rows(s.at("base"));
      fibers.mid = read_rows(s.at("mid"));
      fibers.top = read_rows(s.at("top"));
      const auto& F = s.at("faces");
      fibers.faces.resize(Eigen::Index(F.size()), 3);
      for (std::size_t f = 0; f < F.size(); ++f)
        for (int c = 0; c < 3; ++c) fibers.faces(Eigen::Index(f), c) = F[f].at(c).get<int>();
      if (s.contains("reference")) {
        const auto& r = s.at("reference");
        fibers.reference_positions.resize(Eigen::Index(r.size()), 3);
        for (std::size_t i = 0; i < r.size(); ++i) {
          fibers.reference_vertices.push_back(r[i].at(0).get<int>());
          for (int c = 0; c < 3; ++c)
            fibers.reference_positions(Eigen::Index(i), c) = r[i].at(c + 1).get<double>();
        }
      }
      const auto& candidates = s.at("candidates");
      fibers.candidate_offsets.push_back(0);
      for (const auto& c : candidates) {
        for (const auto& t : c) fibers.candidate_faces.push_back(t.get<int>());
        fibers.candidate_offsets.push_back(int(fibers.candidate_faces.size()));
      }
      if (fibers.num_prisms() == 0 && candidates.empty()) fibers.candidate_offsets.clear();
      if (s.contains("surface")) {
        const auto& r = s.at("surface");
        fibers.surface_points = read_rows(r.at("points"));
        const auto& RF = r.at("faces");
        fibers.surface_faces.resize(Eigen::Index(RF.size()), 3);
        for (std::size_t f = 0; f < RF.size(); ++f)
          for (int c = 0; c < 3; ++c)
            fibers.surface_faces(Eigen::Index(f), c) = RF[f].at(c).get<int>();
        fibers.surface_parent = r.at("parent").get<std::vector<int>>();
        fibers.surface_bary = read_rows(r.at("bary"), 9);
        if (fibers.surface_points.rows() == 0) fibers.surface_points.resize(0, 3);
      }
      try {
        validate_structure(fibers);
      } catch (const InputError& e) {
        throw InputError(path.string() + ": " + e.what());
      }
      if (fibers.num_prisms() != map.boundary.num_cells())
        throw InputError(path.string() + ": " + std::to_string(fibers.num_prisms()) +
                         " shell prisms for " + std::to_string(map.boundary.num_cells()) +
                         " boundary triangles");
      saved.fibers = std::move(fibers);
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path.string() + ": malformed boundary map: " + e.what());
  }
  validate_structure(map);
  return saved;
}

}  // namespace curvefem::io
