// Procedural closed surfaces for tests and built-in cases (no data files needed).
// All are closed, manifold, oriented outward, free of self-intersections.
#pragma once

#include "meshing/core/surface_mesh.hpp"

namespace curvefem {

/// Icosahedron subdivided `level` times and projected on the sphere: 20·4^level faces.
SurfaceMesh make_icosphere(int level, double radius = 1.0,
                           const Eigen::Vector3d& center = Eigen::Vector3d::Zero());
/// Torus around z: major radius R, minor r, nu × nv quads split into 2·nu·nv triangles (genus 1).
SurfaceMesh make_torus(double R, double r, int nu, int nv);
/// Axis-aligned box [lo, hi] with n × n quads per side, 12·n² faces; tags 1..6 = -x,+x,-y,+y,-z,+z.
SurfaceMesh make_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int n = 1);

}  // namespace curvefem
