#pragma once
// Section remeshing (thesis §4.4 "remeshing"): isotropic remeshing [Botsch & Kobbelt 2004] of the
// shell's middle surface, constrained so that the result stays a section of the shell. The passes
// are meshing/editing's isotropic_remeshing() (split > 4/3 L, collapse < 4/5 L, valence flips,
// tangential relaxation); the shell adds:
//   placement   every new or moved vertex is put on the input along its fiber: a split or
//               collapse at the edge midpoint p, a relaxed vertex at its tangential target p,
//               goes to P(p) (projection.hpp). A p outside the shell rejects the operation.
//               The start surface (the middle surface) has its vertices on the input, so every
//               vertex of the result lies on the input, exactly where P puts it.
//   invariants  every triangle an operation creates or moves passes SectionChecker::separated
//               and ::transversal (section.hpp (c) and (d)), on top of SurfaceEditMesh's
//               no-fold / non-degenerate tests. Pinch points (singular pillars) are frozen.
// By the argument in section.hpp the result is a section when the start is one; both are checked
// in full (SectionChecker::check) and reported. Being a section, the result has no
// self-intersections, and P restricted to it is a bijection onto the input.
//
// Shapes: the result is a closed, oriented SurfaceMesh (V #V × 3, F #F × 3) with the input's
// orientation. target_edge is absolute.

#include "meshing/core/surface_mesh.hpp"
#include "meshing/editing/algorithms/isotropic_remeshing.hpp"
#include "meshing/shell/projection.hpp"
#include "meshing/shell/section.hpp"

namespace curvefem::meshing::shell {

struct SectionRemeshOptions {
  double target_edge = 0;  // absolute target edge length L (> 0)
  int iterations = 5;      // rounds of split / collapse / flip / relax
  int threads = 1;
};

struct SectionRemeshResult {
  SurfaceMesh mesh;
  editing::PassLog passes;  // one entry per scheduler pass
  SectionCheck start;       // the middle surface the remeshing started from
  SectionCheck result;      // the remeshed surface
  double seconds = 0;
};

// `projection` projects onto the input (ShellProjection(shell, input)). Throws InputError for a
// non-positive target length, MeshingError when the middle surface is not a section.
SectionRemeshResult remesh_section(const ShellProjection& projection,
                                   const SectionRemeshOptions& options);

}  // namespace curvefem::meshing::shell
