#pragma once
// A shell's fibers at the middle surface as self-contained data (meshing/core/shell_fibers.hpp):
// the layers, the faces rotated to their smallest vertex id, the reference copy's moved vertices,
// and per prism the input faces its fibers may cross, found here with the exact box queries of
// the input index (CGAL, in the .cpp), so that φ⁻¹ can be evaluated later without this module
// (meshing/core/fiber_projection.hpp agrees with ShellProjection::project at h = 0).
#include "meshing/core/shell_fibers.hpp"
#include "meshing/core/surface_mesh.hpp"
#include "meshing/shell/shell.hpp"

namespace curvefem::meshing::shell {

/// `input`: the surface the shell was built around (the one ShellProjection(shell, input) projects
/// onto). Candidate faces of prism f: the input faces whose box (reference copy and input) meets
/// the box of f's 9 corners, widened by a margin of 1e-9 of its diagonal and coordinates, less
/// those whose reference triangle a separating axis puts farther than the margin from the hull
/// of the corners.
ShellFibers fibers_of(const Shell& shell, const SurfaceMesh& input);

}  // namespace curvefem::meshing::shell
