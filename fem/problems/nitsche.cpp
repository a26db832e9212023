#include "fem/problems/nitsche.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "fem/quadrature/simplex_quadrature.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/lagrange_nodes.hpp"

namespace curvefem::fem {

double nitsche_length(const LagrangeMesh& mesh, int cell, int j) {
  Eigen::Vector3d v[4];
  for (int i = 0; i < 4; ++i) v[i] = mesh.nodes.row(mesh.cells(cell, i)).transpose();
  const double volume = std::abs((v[1] - v[0]).dot((v[2] - v[0]).cross(v[3] - v[0]))) / 6;
  Eigen::Vector3d f[3];
  int n = 0;
  for (int i = 0; i < 4; ++i)
    if (i != j) f[n++] = v[i];
  const double area = 0.5 * (f[1] - f[0]).cross(f[2] - f[0]).norm();
  // A curved cell's corners alone can be nearly flat: the height is kept above 1e-3 √|F|.
  return std::max(area > 0 ? 3 * volume / area : 0.0, 1e-3 * std::sqrt(area));
}

double nitsche_penalty(int degree, double h) {
  CF_VERIFY(h > 0, "Nitsche penalty: a boundary face of zero area");
  return 4.0 * (degree + 1) * (degree + 3) / h;
}

DirichletFaceSplit split_dirichlet_faces(const LagrangeMesh& mesh, const FunctionSpace& space,
                                         const std::vector<char>& faces, const PointFilter& where,
                                         PartialDirichlet mode) {
  CF_VERIFY(faces.size() == space.boundary_faces.size(), "boundary face flags do not match");
  DirichletFaceSplit out;
  out.strong = faces;
  if (!where || mode == PartialDirichlet::nodal) return out;
  const int face_degree = default_quadrature_degree(space.degree, mesh.order, QuadratureUse::mass);
  const FacePoints all = face_points(mesh, space, faces, face_degree);
  const std::vector<char> used =
      evaluate_at_face_points(all, where, [](int, const Eigen::Vector3d&) {});
  // Per face: how many of its quadrature points pass, and whether all of its DOFs pass.
  const std::size_t nf = faces.size();
  std::vector<int> points(nf, 0), passing(nf, 0), first(nf, -1);
  for (int k = 0; k < all.size(); ++k) {
    const std::size_t f = std::size_t(all.face[k]);
    if (points[f]++ == 0) first[f] = k;
    passing[f] += used[std::size_t(k)];
  }
  const auto& lattice = lagrange_lattice(CellKind::tetrahedron, space.degree);
  const int n = static_cast<int>(space.cell_dofs.cols());
  std::vector<char> partial(nf, 0);
  for (std::size_t f = 0; f < nf; ++f) {
    if (!faces[f] || passing[f] == 0) continue;  // none: its passing DOFs stay fixed
    bool all_dofs = true;
    const auto [cell, j] = space.boundary_faces[f];
    for (int l = 0; l < n && all_dofs; ++l)
      if (lattice[l][j] == 0)
        all_dofs = where(space.dof_points.row(space.cell_dofs(cell, l)).transpose());
    if (all_dofs && passing[f] == points[f]) continue;  // every point passes: strong
    partial[f] = 1;
    out.strong[f] = 0;
    ++out.partial_faces;
  }
  if (out.partial_faces == 0) return out;
  // The same rule again, with gradients, on the partial faces only: each face's points come in
  // the same order, so the filter's answers are taken from the first pass (no second φ⁻¹).
  out.points = face_points(mesh, space, partial, face_degree, /*with_gradients=*/true);
  out.used.resize(std::size_t(out.points.size()));
  for (int k = 0, at = 0; k < out.points.size(); ++k) {
    const std::size_t f = std::size_t(out.points.face[k]);
    at = k > 0 && out.points.face[k - 1] == out.points.face[k] ? at + 1 : 0;
    out.used[std::size_t(k)] = used[std::size_t(first[f] + at)];
  }
  return out;
}

}  // namespace curvefem::fem
