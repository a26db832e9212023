#pragma once
// The local sheets of a self-intersecting input (thesis §4.5): a locally injective shell.
//
// Where the input passes through itself, two parts of it ("sheets") that share no vertex occupy
// the same space, and no prism around one of them can keep the other out: the global invariants
// (I2 section, I3 separation) fail for every thickness. A locally injective shell checks them
// against the part of the input local to each prism only. Here that part is defined by
// topology within geometry: the input faces reachable from the prism's own faces through shared
// vertices, stepping only on faces whose bounding box meets the prism's. Another sheet crossing
// the prism shares no vertex with this one inside the box, so it is not reached; a fold of the
// same sheet inside the box is, and the invariants keep it out as before.
//
// On an input free of self-intersections this gives weaker guarantees than the global checks
// (a distant part of the surface may enter a prism): locally injective shells are an explicit
// choice (ShellOptions::local_sheets, `curvefem shell --allow-self-intersections`), for
// remeshing and attribute transfer, not for meshing a volume.

#include <Eigen/Geometry>
#include <vector>

#include "meshing/shell/shell_intersection.hpp"

namespace curvefem::meshing::shell {

class LocalSheets {
 public:
  // The index must outlive this object (its faces and boxes are read by every query).
  explicit LocalSheets(const InputSurfaceIndex& index);

  // The faces reached from `seeds` (input face ids; those whose box misses `box` are not
  // stepped from) through shared vertices over faces whose bounding box meets `box`, in
  // increasing order; the seeds meeting the box are included.
  std::vector<int> sheet(const std::vector<int>& seeds, const Eigen::AlignedBox3d& box) const;

  const InputSurfaceIndex& index() const { return m_index; }

 private:
  const InputSurfaceIndex& m_index;
  std::vector<std::vector<int>> m_vertex_faces;  // input vertex → its faces
};

}  // namespace curvefem::meshing::shell
