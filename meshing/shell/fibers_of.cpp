#include "meshing/shell/fibers_of.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/shell/shell_geometry.hpp"
#include "meshing/shell/shell_intersection.hpp"

namespace curvefem::meshing::shell {
namespace {

// Is the triangle farther than `margin` from the convex hull of the prism's 9 corners along one
// of these axes: its normal, the normals of the base, middle and top triangles, and the cross
// products of its edges with the prism's 15 edges (pillars and layer edges)? A subset of the
// separating axes of two convex sets, so "true" proves separation (with the margin) and "false"
// proves nothing.
bool separated(const std::array<Eigen::Vector3d, 3>& tri, const std::array<Eigen::Vector3d, 9>& P,
               double margin) {
  auto apart = [&](const Eigen::Vector3d& axis) {
    const double len = axis.norm();
    if (!(len > 0)) return false;
    const Eigen::Vector3d a = axis / len;
    double tlo = a.dot(tri[0]), thi = tlo;
    for (int k = 1; k < 3; ++k)
      tlo = std::min(tlo, a.dot(tri[k])), thi = std::max(thi, a.dot(tri[k]));
    double plo = a.dot(P[0]), phi = plo;
    for (int k = 1; k < 9; ++k) plo = std::min(plo, a.dot(P[k])), phi = std::max(phi, a.dot(P[k]));
    return tlo > phi + margin || thi < plo - margin;
  };
  if (apart((tri[1] - tri[0]).cross(tri[2] - tri[0]))) return true;
  for (int layer = 0; layer < 3; ++layer) {  // corners 3·layer + c: base, mid, top
    const Eigen::Vector3d* q = &P[std::size_t(3 * layer)];
    if (apart((q[1] - q[0]).cross(q[2] - q[0]))) return true;
  }
  std::array<Eigen::Vector3d, 15> edges;
  int n = 0;
  for (int c = 0; c < 3; ++c) {
    edges[std::size_t(n++)] = P[std::size_t(3 + c)] - P[std::size_t(c)];      // lower pillar
    edges[std::size_t(n++)] = P[std::size_t(6 + c)] - P[std::size_t(3 + c)];  // upper pillar
    for (int layer = 0; layer < 3; ++layer)
      edges[std::size_t(n++)] =
          P[std::size_t(3 * layer + (c + 1) % 3)] - P[std::size_t(3 * layer + c)];
  }
  for (int k = 0; k < 3; ++k)
    for (const Eigen::Vector3d& e : edges)
      if (apart((tri[(k + 1) % 3] - tri[k]).cross(e))) return true;
  return false;
}

}  // namespace

ShellFibers fibers_of(const Shell& shell, const SurfaceMesh& input) {
  CF_VERIFY(shell.base.rows() == shell.mid.rows() && shell.top.rows() == shell.mid.rows(),
            "fibers_of: the shell's layers differ in size");
  ShellFibers out;
  out.base = shell.base;
  out.mid = shell.mid;
  out.top = shell.top;
  const int nf = int(shell.F.rows());
  out.faces.resize(nf, 3);
  for (int f = 0; f < nf; ++f) {
    const Eigen::Vector3i F = shell.F.row(f);
    const int r = min_rotation(F);
    for (int c = 0; c < 3; ++c) out.faces(f, c) = F[(r + c) % 3];
  }
  // The reference copy as the projection sees it (rounded snapped points), of the refined surface
  // when the shell was built on one (Shell::refinement).
  const Shell::Refinement& rf = shell.refinement;
  Eigen::MatrixXd V = input.V;
  if (!rf.empty()) {
    V.resize(input.V.rows() + rf.points.rows(), 3);
    V << input.V, rf.points;
    out.surface_points = rf.points;
    out.surface_faces = rf.faces;
    out.surface_parent = rf.parent;
    out.surface_bary.resize(rf.faces.rows(), 9);
    for (Eigen::Index t = 0; t < rf.faces.rows(); ++t)
      for (int k = 0; k < 3; ++k)
        out.surface_bary.row(t).segment<3>(3 * k) = rf.bary[std::size_t(t)].col(k).transpose();
  }
  const InputSurfaceIndex index(V, rf.empty() ? input.F : rf.faces,
                                rf.empty() ? shell.reference : rf.reference);
  const std::vector<SnappedVertex> snaps = index.snaps();  // increasing vertex order
  out.reference_positions.resize(Eigen::Index(snaps.size()), 3);
  for (std::size_t i = 0; i < snaps.size(); ++i) {
    out.reference_vertices.push_back(snaps[i].vertex);
    out.reference_positions.row(Eigen::Index(i)) = index.reference_V().row(snaps[i].vertex);
  }
  out.candidate_offsets.reserve(std::size_t(nf) + 1);
  out.candidate_offsets.push_back(0);
  for (int f = 0; f < nf; ++f) {
    Eigen::AlignedBox3d box;
    std::array<Eigen::Vector3d, 9> corners;  // base, mid, top corners (rotated order)
    for (int c = 0; c < 3; ++c) {
      const int v = out.faces(f, c);
      corners[std::size_t(c)] = shell.base.row(v).transpose();
      corners[std::size_t(3 + c)] = shell.mid.row(v).transpose();
      corners[std::size_t(6 + c)] = shell.top.row(v).transpose();
    }
    for (const Eigen::Vector3d& p : corners) box.extend(p);
    // Fiber points are rounded convex combinations of the corners: the margin covers their
    // rounding (relative to the coordinates) many times over.
    const double pad = 1e-9 * (box.diagonal().norm() +
                               box.min().cwiseAbs().cwiseMax(box.max().cwiseAbs()).maxCoeff());
    std::vector<int> faces = index.faces_in_box(box.min().array() - pad, box.max().array() + pad);
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    // Faces of the reference copy (as the fibers see them: rounded where snapped) proven apart
    // from the prism's hull by more than the margin cannot be crossed by its fibers.
    faces.erase(
        std::remove_if(faces.begin(), faces.end(),
                       [&](int t) { return separated(index.face_triangle(t), corners, pad); }),
        faces.end());
    out.candidate_faces.insert(out.candidate_faces.end(), faces.begin(), faces.end());
    out.candidate_offsets.push_back(int(out.candidate_faces.size()));
  }
  return out;
}

}  // namespace curvefem::meshing::shell
