// The built-in CAD-like part used by the demo and by tests that need a shape with sharp features
// and curved faces without any data file: a 2 × 1 × 0.5 plate with a through hole (r 0.25) and a
// cylindrical boss (r 0.3, height 0.9), built with Gmsh's OpenCASCADE kernel.
//
// Two products from the same CAD model:
//  - a dense triangle surface (the kind of input curvefem is for), oriented outward, face tags =
//    CAD surface ids;
//  - a coarse tetrahedral mesh of geometric order k from Gmsh, high-order nodes snapped to the CAD
//    surfaces (Gmsh's own curving; a comparison / fallback, not curvefem's bijective mesher).
#pragma once

#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/surface_mesh.hpp"

namespace curvefem::io {

struct CadPartOptions {
  double dense_size = 0.03;         ///< target edge length of the dense surface
  double coarse_size = 0.25;        ///< target edge length of the coarse volume mesh
  int order = 3;                    ///< geometric order of the coarse volume mesh (1..4)
  bool optimize_high_order = true;  ///< run Gmsh's high-order optimizer (elastic + optimization)
};

struct CadPart {
  SurfaceMesh dense_surface;
  LagrangeMesh coarse_volume;  ///< tetrahedra, canonical node order, cell_tags = 1
  double exact_volume = 0.0;   ///< of the CAD solid (OpenCASCADE mass)
};

CadPart make_cad_part(const CadPartOptions& options = {});

/// Ball of `radius` centred at the origin meshed by Gmsh (OpenCASCADE sphere) with target edge
/// length `size`, geometric order `order` (high-order boundary nodes on the sphere; Gmsh's
/// high-order optimizer on when order > 1). Boundary triangles are not included.
LagrangeMesh make_ball_mesh(double radius, double size, int order);

}  // namespace curvefem::io
