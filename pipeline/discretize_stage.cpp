// Stage discretize (stages.hpp): the solve geometry, the function space, the boundary face tags of
// a given mesh and φ⁻¹ on the solve geometry's boundary.
#include <algorithm>
#include <map>
#include <unordered_map>

#include "meshing/core/error.hpp"
#include "meshing/core/geometry_degree.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/position_key.hpp"
#include "meshing/curved/jacobian_certificate.hpp"
#include "meshing/io/msh_io.hpp"
#include "pipeline/stages.hpp"

namespace curvefem::pipeline {
namespace {
using json = nlohmann::json;

/// Physical tag of every boundary face, from the triangles stored in the mesh file (-1 if none).
std::vector<int> boundary_face_tags(const std::filesystem::path& path, const LagrangeMesh& mesh,
                                    const fem::FunctionSpace& space) {
  std::vector<int> tags(space.boundary_faces.size(), -1);
  if (path.extension() != ".msh") return tags;
  SurfaceMesh triangles;
  try {
    triangles = io::read_msh_boundary_triangles(path);  // any order; corners + physical tags
  } catch (const InputError&) {
    return tags;  // no triangles in the file
  }
  if (!triangles.has_tags()) return tags;
  std::unordered_map<PositionKey, int, PositionHash> node_of;
  for (int n = 0; n < mesh.num_nodes(); ++n) node_of.emplace(position_key(mesh.nodes.row(n)), n);
  std::map<std::array<int, 3>, int> tag_of;
  for (int f = 0; f < triangles.num_faces(); ++f) {
    std::array<int, 3> ids;
    bool found = true;
    for (int c = 0; c < 3; ++c) {
      auto it = node_of.find(position_key(triangles.V.row(triangles.F(f, c))));
      if (it == node_of.end())
        found = false;
      else
        ids[c] = it->second;
    }
    if (!found) continue;
    std::sort(ids.begin(), ids.end());
    tag_of[ids] = triangles.tags[f];
  }
  for (std::size_t f = 0; f < space.boundary_faces.size(); ++f) {
    const auto [cell, j] = space.boundary_faces[f];
    std::array<int, 3> ids;
    int k = 0;
    for (int i = 0; i < 4; ++i)
      if (i != j) ids[k++] = mesh.cells(cell, i);
    std::sort(ids.begin(), ids.end());
    auto it = tag_of.find(ids);
    if (it != tag_of.end()) tags[f] = it->second;
  }
  return tags;
}

/// Sides of the built-in unit cube: 1..6 = x=0, x=1, y=0, y=1, z=0, z=1 (as make_box).
std::vector<int> cube_face_tags(const LagrangeMesh& mesh, const fem::FunctionSpace& space) {
  std::vector<int> tags(space.boundary_faces.size(), -1);
  for (std::size_t f = 0; f < tags.size(); ++f) {
    const auto [cell, j] = space.boundary_faces[f];
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(2), hi = Eigen::Vector3d::Constant(-1);
    for (int i = 0; i < 4; ++i)
      if (i != j) {
        lo = lo.cwiseMin(mesh.nodes.row(mesh.cells(cell, i)).transpose());
        hi = hi.cwiseMax(mesh.nodes.row(mesh.cells(cell, i)).transpose());
      }
    for (int axis = 0; axis < 3; ++axis) {
      if (hi[axis] < 1e-12) tags[f] = 1 + 2 * axis;
      if (lo[axis] > 1 - 1e-12) tags[f] = 2 + 2 * axis;
    }
  }
  return tags;
}

json lower_geometry_for_solve(const CaseSpec& spec, LagrangeMesh& mesh) {
  json r = {{"mode", spec.geometry}, {"mesh_order", mesh.order}, {"degree", mesh.order}};
  if (spec.geometry != SolveGeometry::iso || spec.degree >= mesh.order) return r;
  int kept = 0;
  mesh = lower_geometry_degree(
      mesh, spec.degree,
      [order = mesh.order](int, const Eigen::MatrixXd& X) {
        return meshing::curved::certify_tet_jacobian(order, X).verdict ==
               meshing::curved::JacobianVerdict::positive;
      },
      &kept);
  r["degree"] = spec.degree;
  r["tets"] = mesh.num_cells();
  r["tets_kept_at_mesh_order"] = kept;  // their degree-p interpolant was not certified positive
  if (kept > 0)
    log::info("run: " + std::to_string(kept) + " of " + std::to_string(mesh.num_cells()) +
              " tets keep their order-" + std::to_string(mesh.order) + " map (the degree-" +
              std::to_string(spec.degree) + " interpolant was not certified positive)");
  return r;
}

}  // namespace

Discretization discretize(const CaseSpec& spec, const Domain& domain, const StageContext& ctx) {
  std::optional<ScopedTimer> t;
  if (ctx.timings) t.emplace(*ctx.timings, "build_space");
  ctx.update("build space", 0.0);
  Discretization disc;
  disc.components = spec.components();
  disc.mesh = domain.mesh;
  disc.solve_geometry = lower_geometry_for_solve(spec, disc.mesh);
  disc.space = fem::build_function_space(disc.mesh, spec.degree);
  if (!domain.on_input()) {
    disc.face_tags = spec.builtin == BuiltinVolume::cube
                         ? cube_face_tags(disc.mesh, disc.space)
                         : boundary_face_tags(spec.mesh, disc.mesh, disc.space);
  } else if (domain.curved_map) {
    const BoundaryMap* map = &*domain.curved_map;
    if (disc.solve_geometry["degree"] != disc.solve_geometry["mesh_order"]) {
      // Boundary data are read at the solver's points, on the lowered boundary: locate them on
      // the boundary triangles moved with it (same faces, same (u, v)).
      auto lowered = std::make_shared<BoundaryMap>(*domain.curved_map);
      const Eigen::VectorXi& to_volume = lowered->boundary_node_to_volume;
      for (Eigen::Index i = 0; i < to_volume.size(); ++i)
        if (to_volume[i] >= 0) lowered->boundary.nodes.row(i) = disc.mesh.nodes.row(to_volume[i]);
      disc.solve_map = lowered;
      map = lowered.get();
    }
    disc.inverse =
        std::make_shared<const mapping::BoundaryInverse>(*map, *domain.fibers, domain.input);
  } else {
    disc.inverse = std::make_shared<const mapping::BoundaryInverse>(
        mapping::BoundaryInverse::identity(domain.input));
  }
  log::info("mesh: ", disc.mesh.num_cells(), " tetrahedra of order ", disc.mesh.order, "; degree ",
            spec.degree, ": ", disc.space.num_dofs, " nodes, ", disc.space.boundary_faces.size(),
            " boundary faces");
  ctx.update("build space", 1.0);
  return disc;
}

}  // namespace curvefem::pipeline
