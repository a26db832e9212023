#pragma once
// Attribute transfer between sections of one shell through P (thesis §4.4, Fig. 4.7): a point x
// of section S2 is located in its prism (face, u, v, h); the fiber of (face, u, v) crosses section
// S1 exactly once, at a point of an S1 triangle with barycentric coordinates λ; a per-vertex field
// of S1 is evaluated there as Σ λ_i value(S1 vertex i). ShellProjection(shell, S1) does the fiber
// walk, so the same function carries a field from the input to a remeshed section and back.
//
// What is exact and what is not. The points are mapped bijectively: x ∈ S2 and its image on S1 lie
// on the same fiber, and mapping that image back to S2 returns x up to rounding. Values are not:
// each direction interpolates linearly in a triangle of the other surface. For a smooth field f
// sampled at the input vertices, input → remeshed → input returns f(v) + O(h²) at an input vertex
// v (h: remeshed edge length; assuming a finer input): the remeshed triangle's interpolation error,
// the gap |x_v − v| between v and the remeshed point on its fiber (the remeshed triangle is a chord
// of the curved input), and the input's own interpolation error at the remeshed vertices. A field
// that is linear in space is reproduced exactly only where that gap vanishes, i.e. where the
// remeshed triangle around x_v lies in the plane of the input around v (flat regions); on a curved
// surface it returns with an O(h²) error too.

#include <Eigen/Core>

#include "meshing/core/surface_mesh.hpp"
#include "meshing/shell/projection.hpp"

namespace curvefem::meshing::shell {

// values: #source.V × k per-vertex field of `source`; onto_source = ShellProjection(shell,
// source); points: #P × 3, each in the shell. Returns #P × k; rows that cannot be mapped (point
// outside the shell, fiber missing the source) are NaN and counted in *failures.
Eigen::MatrixXd transfer_vertex_field(const ShellProjection& onto_source, const SurfaceMesh& source,
                                      const Eigen::MatrixXd& values, const Eigen::MatrixXd& points,
                                      int* failures = nullptr);

struct FieldRoundtrip {
  Eigen::MatrixXd there;  // #section.V × k: the field on the section
  Eigen::MatrixXd back;   // #input.V × k: carried back to the input
  double max_error = 0;   // max |back − values| over referenced input vertices and components
  double mean_error = 0;  // mean of the per-vertex max over the components
  int failures = 0;       // section vertices, and referenced input vertices, not mapped
};

// values (#input.V × k) → the section's vertices → back to the input's vertices.
// onto_input = ShellProjection(shell, input); section: a section of the same shell.
FieldRoundtrip field_roundtrip(const ShellProjection& onto_input, const SurfaceMesh& input,
                               const SurfaceMesh& section, const Eigen::MatrixXd& values);

// values (#input.V × k) → the shell's own middle surface → back to the input's vertices, by
// prism coordinates rather than point location, so that it works on a locally injective shell
// (Shell::local_sheets) too, whose prisms overlap where the input passes through itself: a
// middle vertex is a corner of its incident prisms, whose fiber P crosses with the input; an
// input vertex goes through unproject(x, face) with a face at it. onto_input =
// ShellProjection(shell, input). `there` is #shell.mid × k.
FieldRoundtrip middle_field_roundtrip(const ShellProjection& onto_input, const SurfaceMesh& input,
                                      const Eigen::MatrixXd& values);

// The smooth test field of the section remeshing example, f = sin(3x) cos(2y) + z², in the
// coordinates (p − center) / scale (#V × 1).
Eigen::VectorXd smooth_test_field(const Eigen::MatrixXd& V, const Eigen::Vector3d& center,
                                  double scale);

}  // namespace curvefem::meshing::shell
