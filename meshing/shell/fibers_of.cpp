#include "meshing/shell/fibers_of.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/shell/shell_geometry.hpp"
#include "meshing/shell/shell_intersection.hpp"

namespace curvefem::meshing::shell {

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
  // The reference copy as the projection sees it (rounded snapped points).
  const InputSurfaceIndex index(input.V, input.F, shell.reference);
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
    for (int c = 0; c < 3; ++c) {
      const int v = out.faces(f, c);
      box.extend(Eigen::Vector3d(shell.base.row(v)));
      box.extend(Eigen::Vector3d(shell.mid.row(v)));
      box.extend(Eigen::Vector3d(shell.top.row(v)));
    }
    // Fiber points are rounded convex combinations of the corners: the margin covers their
    // rounding (relative to the coordinates) many times over.
    const double pad = 1e-9 * (box.diagonal().norm() +
                               box.min().cwiseAbs().cwiseMax(box.max().cwiseAbs()).maxCoeff());
    std::vector<int> faces = index.faces_in_box(box.min().array() - pad, box.max().array() + pad);
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    out.candidate_faces.insert(out.candidate_faces.end(), faces.begin(), faces.end());
    out.candidate_offsets.push_back(int(out.candidate_faces.size()));
  }
  return out;
}

}  // namespace curvefem::meshing::shell
