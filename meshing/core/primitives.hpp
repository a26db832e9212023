// Procedural closed surfaces for tests and built-in cases (no data files needed).
// All are closed, manifold, oriented outward, free of self-intersections.
#pragma once

#include <functional>

#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/surface_mesh.hpp"

namespace curvefem {

/// Icosahedron subdivided `level` times and projected on the sphere: 20·4^level faces.
SurfaceMesh make_icosphere(int level, double radius = 1.0,
                           const Eigen::Vector3d& center = Eigen::Vector3d::Zero());
/// Torus around z: major radius R, minor r, nu × nv quads split into 2·nu·nv triangles (genus 1).
SurfaceMesh make_torus(double R, double r, int nu, int nv);
/// NOT free of self-intersections (an immersed surface, for the locally injective shell,
/// meshing/shell/local_sheets.hpp): a closed tube of radius r around the planar figure eight
/// (lemniscate of Gerono, x = cos t, y = sin 2t / 2, z = 0), n rings of m vertices, 2·n·m faces,
/// oriented outward, one component of genus 1. The tube passes through itself where the curve
/// crosses itself, at the origin (r < 1, the curve's least radius of curvature).
SurfaceMesh make_figure_eight_tube(int n, int m, double r);
/// Axis-aligned box [lo, hi] with n × n quads per side, 12·n² faces; tags 1..6 = -x,+x,-y,+y,-z,+z.
SurfaceMesh make_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int n = 1);

/// Closed cylinder of radius 1 around z from z = 0 to z = h: `around` segments, `rows` rows on
/// the side, `rings` concentric rings on each flat cap (its centre a vertex); its two rims are
/// sharp (90°) curved feature chains.
SurfaceMesh make_cylinder(int around, int rows, int rings, double h);

/// Unit cube [0,1]³ cut into n³ cubes of 6 positively oriented tetrahedra each (Kuhn split along
/// the main diagonal; conforming). Order 1, cell_tags 1.
LagrangeMesh make_cube_tets(int n);

/// Raises an order-1 tet mesh to geometric order k: the order-k lattice points of every cell are
/// placed at `deform(affine image)`; shared edge/face nodes are shared (keyed by the global vertex
/// ids and barycentric weights). With deform = identity the mesh is straight-sided.
LagrangeMesh elevate_order(const LagrangeMesh& linear, int k,
                           const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& deform);

}  // namespace curvefem
