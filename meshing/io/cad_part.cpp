#include "meshing/io/cad_part.hpp"

#include <gmsh.h>

#include <map>
#include <unordered_map>

#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/io/gmsh_session.hpp"
#include "meshing/io/msh_io.hpp"

namespace curvefem::io {
namespace {

int build_model() {
  namespace occ = gmsh::model::occ;
  const int plate = occ::addBox(0, 0, 0, 2, 1, 0.5);
  const int hole = occ::addCylinder(0.6, 0.5, -0.1, 0, 0, 0.7, 0.25);
  const int boss = occ::addCylinder(1.5, 0.5, 0, 0, 0, 0.9, 0.3);
  std::vector<std::pair<int, int>> cut, fused;
  std::vector<std::vector<std::pair<int, int>>> map;
  occ::cut({{3, plate}}, {{3, hole}}, cut, map);
  occ::fuse(cut, {{3, boss}}, fused, map);
  occ::synchronize();
  CF_VERIFY(fused.size() == 1 && fused[0].first == 3, "CAD part is not a single solid");
  return fused[0].second;
}

// Node tag → row, filled from all nodes of the model.
void collect_nodes(Eigen::MatrixXd& X, std::unordered_map<std::size_t, int>& row) {
  std::vector<std::size_t> tags;
  std::vector<double> coord, param;
  gmsh::model::mesh::getNodes(tags, coord, param, -1, -1, true, false);
  X.resize(static_cast<Eigen::Index>(tags.size()), 3);
  row.clear();
  for (std::size_t i = 0; i < tags.size(); ++i) {
    row[tags[i]] = static_cast<int>(i);
    for (int d = 0; d < 3; ++d) X(static_cast<Eigen::Index>(i), d) = coord[3 * i + d];
  }
}

SurfaceMesh dense_surface(int volume) {
  Eigen::MatrixXd X;
  std::unordered_map<std::size_t, int> row;
  collect_nodes(X, row);
  std::vector<std::pair<int, int>> boundary;
  gmsh::model::getBoundary({{3, volume}}, boundary, true, true, false);  // oriented
  std::vector<Eigen::Vector3i> faces;
  std::vector<int> tags;
  std::unordered_map<int, int> used;  // old row → new vertex
  std::vector<int> order;
  for (const auto& [dim, signed_tag] : boundary) {
    const int tag = std::abs(signed_tag);
    std::vector<int> types;
    std::vector<std::vector<std::size_t>> elements, nodes;
    gmsh::model::mesh::getElements(types, elements, nodes, 2, tag);
    for (std::size_t b = 0; b < types.size(); ++b) {
      CF_VERIFY(types[b] == 2, "dense surface must be linear triangles");
      for (std::size_t e = 0; e < nodes[b].size() / 3; ++e) {
        Eigen::Vector3i f;
        for (int c = 0; c < 3; ++c) {
          const int r = row.at(nodes[b][3 * e + c]);
          auto [it, inserted] = used.try_emplace(r, static_cast<int>(order.size()));
          if (inserted) order.push_back(r);
          f[c] = it->second;
        }
        if (signed_tag < 0) std::swap(f[1], f[2]);
        faces.push_back(f);
        tags.push_back(tag);
      }
    }
  }
  SurfaceMesh m;
  m.V.resize(static_cast<Eigen::Index>(order.size()), 3);
  for (std::size_t i = 0; i < order.size(); ++i)
    m.V.row(static_cast<Eigen::Index>(i)) = X.row(order[i]);
  m.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  m.tags.resize(static_cast<Eigen::Index>(faces.size()));
  for (std::size_t i = 0; i < faces.size(); ++i) {
    m.F.row(static_cast<Eigen::Index>(i)) = faces[i].transpose();
    m.tags[static_cast<Eigen::Index>(i)] = tags[i];
  }
  for (int t : tags) m.tag_names[t] = "cad_surface_" + std::to_string(t);
  // Gmsh's surface orientation relative to the solid is already applied; make sure the solid is
  // outward (OCC solids are, but verify instead of assuming).
  if (signed_volume(m) < 0.0) m.F.col(1).swap(m.F.col(2));
  return m;
}

LagrangeMesh coarse_volume(int order) {
  Eigen::MatrixXd X;
  std::unordered_map<std::size_t, int> row;
  collect_nodes(X, row);
  const int type = gmsh::model::mesh::getElementType("Tetrahedron", order);
  std::vector<std::size_t> element_tags, node_tags;
  gmsh::model::mesh::getElementsByType(type, element_tags, node_tags);
  const auto perm =
      gmsh_node_permutation(CellKind::tetrahedron, order);  // gmsh i = canonical perm[i]
  const int n = num_lagrange_nodes(CellKind::tetrahedron, order);
  LagrangeMesh mesh;
  mesh.kind = CellKind::tetrahedron;
  mesh.order = order;
  const auto cells = static_cast<Eigen::Index>(element_tags.size());
  mesh.cells.resize(cells, n);
  std::unordered_map<int, int> used;
  std::vector<int> order_rows;
  for (Eigen::Index c = 0; c < cells; ++c)
    for (int i = 0; i < n; ++i) {
      const int r = row.at(node_tags[static_cast<std::size_t>(c) * n + i]);
      auto [it, inserted] = used.try_emplace(r, static_cast<int>(order_rows.size()));
      if (inserted) order_rows.push_back(r);
      mesh.cells(c, perm[i]) = it->second;
    }
  mesh.nodes.resize(static_cast<Eigen::Index>(order_rows.size()), 3);
  for (std::size_t i = 0; i < order_rows.size(); ++i)
    mesh.nodes.row(static_cast<Eigen::Index>(i)) = X.row(order_rows[i]);
  mesh.cell_tags = Eigen::VectorXi::Ones(cells);
  return mesh;
}

}  // namespace

CadPart make_cad_part(const CadPartOptions& options) {
  if (options.order < 1 || options.order > k_max_order)
    throw InputError("CAD part: order must be in 1..4");
  GmshSession session("cad_part");
  CadPart part;
  const int volume = build_model();
  gmsh::model::occ::getMass(3, volume, part.exact_volume);

  gmsh::option::setNumber("Mesh.MeshSizeMin", options.dense_size * 0.5);
  gmsh::option::setNumber("Mesh.MeshSizeMax", options.dense_size);
  gmsh::model::mesh::generate(2);
  part.dense_surface = dense_surface(volume);
  log::info("CAD part: dense surface with ", part.dense_surface.num_faces(), " faces");

  gmsh::model::mesh::clear();
  gmsh::option::setNumber("Mesh.MeshSizeMin", options.coarse_size * 0.5);
  gmsh::option::setNumber("Mesh.MeshSizeMax", options.coarse_size);
  gmsh::model::mesh::generate(3);
  if (options.order > 1) {
    gmsh::model::mesh::setOrder(options.order);
    if (options.optimize_high_order) {
      gmsh::option::setNumber("Mesh.HighOrderThresholdMin", 0.3);
      gmsh::model::mesh::optimize("HighOrder");
    }
  }
  part.coarse_volume = coarse_volume(options.order);
  log::info("CAD part: coarse order-", options.order, " mesh with ", part.coarse_volume.num_cells(),
            " tetrahedra");
  return part;
}

LagrangeMesh make_ball_mesh(double radius, double size, int order) {
  if (order < 1 || order > k_max_order) throw InputError("ball mesh: order must be in 1..4");
  GmshSession session("ball");
  gmsh::model::occ::addSphere(0, 0, 0, radius);
  gmsh::model::occ::synchronize();
  gmsh::option::setNumber("Mesh.MeshSizeMin", size * 0.5);
  gmsh::option::setNumber("Mesh.MeshSizeMax", size);
  gmsh::model::mesh::generate(3);
  if (order > 1) {
    gmsh::model::mesh::setOrder(order);
    gmsh::option::setNumber("Mesh.HighOrderThresholdMin", 0.3);
    gmsh::model::mesh::optimize("HighOrder");
  }
  return coarse_volume(order);
}

}  // namespace curvefem::io
