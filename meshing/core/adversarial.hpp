#pragma once
// Procedural adversarial surfaces (issue 21): closed, oriented, manifold and free of
// self-intersections — valid inputs `curvefem check` accepts — built to stress the shell and the
// curved mesher where real scans and CAD exports do: singular vertices alone and in clusters,
// faces with three singular corners, knife edges, needle noise, slivers. Deterministic (fixed
// seeds), no files. `curvefem generate NAME -o OUT` writes any of them.

#include <string>
#include <vector>

#include "meshing/core/surface_mesh.hpp"

namespace curvefem {

struct AdversarialSurface {
  std::string name;
  std::string what;  ///< one line: what it stresses
};

/// Every generator, in a fixed order.
const std::vector<AdversarialSurface>& adversarial_surfaces();

/// The surface named `name` (InputError naming the known ones otherwise).
SurfaceMesh make_adversarial(const std::string& name);

/// A disc of radius 1 whose rim is a knife edge: the surface of revolution z = ±f(r),
/// f(r) = s (1 − r) + c (1 − r)² with rim slope s = tan(rim_half_angle_deg), n vertices around
/// and `rings` rings per side (the last at r = 0.99, so the rim faces lean by s + 0.01 c). With
/// a lean below 0.57° (the shell's singularity tolerance 1e-2) every rim vertex is singular.
/// `slivers` places that many triangles with three rim vertices (B_i, B_i+1, B_i+2) on the top
/// side, evenly around: faces with three singular corners and a min angle of about 180°/n.
SurfaceMesh make_knife_disc(int n, int rings, double rim_half_angle_deg, double c, int slivers);

/// An icosphere with `needles` thin cones pointing out of spread vertices: each vertex's faces
/// start on a tiny ring, radius height · tan(lean), and meet at its tip, `height` above the
/// sphere; with a lean below 0.57° the tip is singular.
SurfaceMesh make_needle_sphere(int level, int needles, double height, double lean_deg,
                               unsigned seed);

/// An icosphere with `slivers` edges split at parameter t from one end (the new vertex on the
/// edge): two triangles each with an angle of about t times 60°.
SurfaceMesh make_sliver_sphere(int level, int slivers, double t, unsigned seed);

/// An icosphere whose vertices (each with probability `fraction`) move radially by up to
/// `amplitude` mean edge lengths: a radial graph, embedded for any amplitude, folded and with
/// clusters of singular vertices when the amplitude is above an edge.
SurfaceMesh make_radial_noise_sphere(int level, double amplitude, double fraction, unsigned seed);

/// A rectangular ring (radii r_in..r_out, height) cut by a slit: its two flat ends face each
/// other `gap` apart at the inner radius. n sections around.
SurfaceMesh make_split_ring(double r_in, double r_out, double height, double gap, int n);

/// A closed cylinder (axis z, given radius and height) tessellated the way CAD exporters do it:
/// the side is ONE band of needle triangles zipped between a bottom rim of n_bottom and a top rim
/// of n_top vertices (the top turned by 0.37 of its spacing), the caps are `rings` concentric
/// bands around a centre vertex. Side faces are height long and about 2π radius / n wide.
SurfaceMesh make_strip_cylinder(int n_bottom, int n_top, double radius, double height, int rings);

/// The unit box, n x n quads per side, with `spikes` sharp three-sided spikes on its top: each
/// replaces a top triangle by a ring of three points `radius` from its centroid (toward its
/// corners) and a tip `height` above the centroid. Their rims and ridges are feature curves a
/// fraction of ε across, ending in corners.
SurfaceMesh make_box_with_spikes(int n, int spikes, double radius, double height);

}  // namespace curvefem
