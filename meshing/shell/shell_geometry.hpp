#pragma once
// Index conventions of shell prisms (reference-notes §3.5, §10.1): defined in
// meshing/core/prism_split.hpp, so that the saved fibers of a shell (meshing/core/shell_fibers.hpp)
// are evaluated on the same polylines without this module; named here for the shell code.

#include "meshing/core/prism_split.hpp"

namespace curvefem::meshing::shell {

using curvefem::fiber_points;
using curvefem::is_type_a;
using curvefem::k_fiber_walk;
using curvefem::min_rotation;
using curvefem::rising_facets;
using curvefem::split_tets;

}  // namespace curvefem::meshing::shell
