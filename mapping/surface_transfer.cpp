#include "mapping/surface_transfer.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/core/lagrange_nodes.hpp"

namespace curvefem::mapping {
namespace {
const double k_nan = std::numeric_limits<double>::quiet_NaN();

Eigen::Vector3d reference_vertex(int i) {
  return i == 0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(Eigen::Vector3d::Unit(i - 1));
}
}  // namespace

SurfaceSamples locate_input_vertices(const LagrangeMesh& mesh, const BoundaryMap& map) {
  CF_VERIFY(mesh.kind == CellKind::tetrahedron, "surface transfer: a tet mesh is expected");
  CF_VERIFY(map.boundary_node_to_volume.size() == map.boundary.num_nodes(),
            "surface transfer: the boundary map is not tied to a volume mesh");
  // The tet under each boundary triangle: the boundary triangles by their sorted corner node
  // ids, then one sweep over the faces of every tet, looking each up there (a map of every tet
  // face was 56 s of the surface transfer on a 5.7M-tet mesh). A boundary triangle must be the
  // face of one tet (a boundary face) or of two (an interface, e.g. the curved surface of an
  // exterior mesh solved on both sides: the first tet is used, the field being continuous).
  struct KeyHash {
    std::size_t operator()(const std::array<int, 3>& k) const {
      std::size_t h = std::size_t(k[0]);
      h = h * 0x9E3779B97F4A7C15ull + std::size_t(k[1]);
      h = h * 0x9E3779B97F4A7C15ull + std::size_t(k[2]);
      return h ^ (h >> 29);
    }
  };
  const int nb = map.boundary.num_cells();
  std::vector<std::array<int, 3>> ids(nb);
  std::unordered_map<std::array<int, 3>, int, KeyHash> triangle_of;
  triangle_of.reserve(std::size_t(nb));
  for (int f = 0; f < nb; ++f) {
    for (int j = 0; j < 3; ++j) ids[f][j] = map.boundary_node_to_volume[map.boundary.cells(f, j)];
    std::array<int, 3> key = ids[f];
    std::sort(key.begin(), key.end());
    triangle_of.emplace(key, f);
  }
  std::vector<int> cell_of(nb, -1), count(nb, 0);
  for (int c = 0; c < mesh.num_cells(); ++c)
    for (int j = 0; j < 4; ++j) {
      std::array<int, 3> k;
      int n = 0;
      for (int i = 0; i < 4; ++i)
        if (i != j) k[n++] = mesh.cells(c, i);
      std::sort(k.begin(), k.end());
      const auto it = triangle_of.find(k);
      if (it == triangle_of.end()) continue;
      if (count[it->second]++ == 0) cell_of[it->second] = c;
    }
  std::vector<std::pair<int, std::array<int, 3>>> tet_of(nb);  // cell, local corner per tri corner
  for (int f = 0; f < nb; ++f) {
    if (count[f] < 1 || count[f] > 2)
      throw MeshingError("surface transfer: boundary triangle " + std::to_string(f) +
                         " is a face of " + std::to_string(count[f]) +
                         " tets of the mesh (1 or 2 expected)");
    const int c = cell_of[f];
    std::array<int, 3> local;
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 4; ++i)
        if (mesh.cells(c, i) == ids[f][j]) local[j] = i;
    tet_of[f] = {c, local};
  }
  const int nv = map.num_input_vertices();
  SurfaceSamples s;
  s.cell = Eigen::VectorXi::Constant(nv, -1);
  s.xi = Eigen::MatrixXd::Constant(nv, 3, k_nan);
  for (int v = 0; v < nv; ++v) {
    const int f = map.vertex_face[v];
    if (f < 0) continue;
    const double a = map.vertex_uv(v, 0), b = map.vertex_uv(v, 1);
    const auto& [c, local] = tet_of[f];
    s.cell[v] = c;
    s.xi.row(v) = ((1 - a - b) * reference_vertex(local[0]) + a * reference_vertex(local[1]) +
                   b * reference_vertex(local[2]))
                      .transpose();
  }
  return s;
}

Eigen::MatrixXd sample_positions(const LagrangeMesh& mesh, const SurfaceSamples& samples) {
  Eigen::MatrixXd X = Eigen::MatrixXd::Constant(samples.cell.size(), 3, k_nan);
  for (Eigen::Index v = 0; v < samples.cell.size(); ++v)
    if (samples.cell[v] >= 0)
      X.row(v) = mesh.map(samples.cell[v], samples.xi.row(v).transpose()).transpose();
  return X;
}

Eigen::MatrixXd evaluate_on_surface(const fem::FunctionSpace& space, const Eigen::VectorXd& u,
                                    int components, const SurfaceSamples& samples) {
  CF_VERIFY(u.size() == Eigen::Index(space.num_dofs) * components,
            "surface transfer: field size does not match the space");
  Eigen::MatrixXd out = Eigen::MatrixXd::Constant(samples.cell.size(), components, k_nan);
  for (Eigen::Index v = 0; v < samples.cell.size(); ++v) {
    const int c = samples.cell[v];
    if (c < 0) continue;
    const Eigen::VectorXd phi =
        lagrange_shape_values(CellKind::tetrahedron, space.degree, samples.xi.row(v).transpose());
    for (int i = 0; i < components; ++i) {
      double s = 0;
      for (Eigen::Index a = 0; a < phi.size(); ++a)
        s += phi[a] * u[Eigen::Index(space.cell_dofs(c, a)) * components + i];
      out(v, i) = s;
    }
  }
  return out;
}

Eigen::MatrixXd evaluate_on_surface_extended(const LagrangeMesh& mesh,
                                             const fem::FunctionSpace& space,
                                             const Eigen::VectorXd& u, int components,
                                             const SurfaceSamples& samples,
                                             const Eigen::MatrixXd& targets) {
  CF_VERIFY(u.size() == Eigen::Index(space.num_dofs) * components,
            "surface transfer: field size does not match the space");
  CF_VERIFY(targets.rows() == samples.cell.size() && targets.cols() == 3,
            "surface transfer: one target point per sample expected");
  CF_VERIFY(mesh.kind == CellKind::tetrahedron && mesh.num_cells() == space.cell_dofs.rows(),
            "surface transfer: the mesh is not the space's");
  Eigen::MatrixXd out = Eigen::MatrixXd::Constant(samples.cell.size(), components, k_nan);
  for (Eigen::Index v = 0; v < samples.cell.size(); ++v) {
    const int c = samples.cell[v];
    if (c < 0) continue;
    const Eigen::Vector3d xi = samples.xi.row(v).transpose();
    const Eigen::VectorXd phi = lagrange_shape_values(CellKind::tetrahedron, space.degree, xi);
    const Eigen::MatrixXd dphi = lagrange_shape_gradients(CellKind::tetrahedron, space.degree, xi);
    const Eigen::Matrix3d J = mesh.jacobian(c, xi);
    const double det = J.determinant();
    if (!(std::abs(det) > 0)) continue;
    // x_v − φ(v) in reference coordinates: J⁻¹ d, so ∇u_h · d = (∂u/∂ξ) · J⁻¹ d.
    const Eigen::Vector3d d = targets.row(v).transpose() - mesh.map(c, xi);
    const Eigen::Vector3d dxi = J.inverse() * d;
    for (int i = 0; i < components; ++i) {
      double value = 0, slope = 0;
      for (Eigen::Index a = 0; a < phi.size(); ++a) {
        const double ua = u[Eigen::Index(space.cell_dofs(c, a)) * components + i];
        value += phi[a] * ua;
        slope += dphi.row(a).dot(dxi) * ua;
      }
      out(v, i) = value + slope;
    }
  }
  return out;
}

SurfaceErrors surface_errors(const SurfaceMesh& input, const Eigen::MatrixXd& values,
                             const ExactFn& exact) {
  const int nv = input.num_vertices(), c = int(values.cols());
  CF_VERIFY(values.rows() == nv, "surface errors: one row of values per input vertex expected");
  Eigen::VectorXd area = Eigen::VectorXd::Zero(nv);
  for (int f = 0; f < input.num_faces(); ++f) {
    const Eigen::Vector3d a = input.V.row(input.F(f, 0)).transpose();
    const Eigen::Vector3d b = input.V.row(input.F(f, 1)).transpose();
    const Eigen::Vector3d d = input.V.row(input.F(f, 2)).transpose();
    const double A = 0.5 * (b - a).cross(d - a).norm();
    for (int j = 0; j < 3; ++j) area[input.F(f, j)] += A / 3;
  }
  SurfaceErrors e;
  e.exact = Eigen::MatrixXd::Constant(nv, c, k_nan);
  e.error = Eigen::MatrixXd::Constant(nv, c, k_nan);
  std::vector<double> buffer(c);
  double l2 = 0, l2x = 0;
  for (int v = 0; v < nv; ++v) {
    exact(input.V.row(v).transpose(), buffer.data());
    for (int i = 0; i < c; ++i) e.exact(v, i) = buffer[i];
    if (!values.row(v).allFinite()) continue;
    ++e.vertices;
    e.error.row(v) = values.row(v) - e.exact.row(v);
    const double n2 = e.error.row(v).squaredNorm();
    l2 += area[v] * n2;
    l2x += area[v] * e.exact.row(v).squaredNorm();
    e.max = std::max(e.max, std::sqrt(n2));
  }
  e.l2 = std::sqrt(l2);
  e.l2_exact = std::sqrt(l2x);
  return e;
}

}  // namespace curvefem::mapping
