// Spatially varying ε from an expression of x, y, z (issue 22): the bound at each input vertex
// as a factor of the run's ε, for CurvedMeshOptions::eps_scale.
#pragma once

#include <string>
#include <vector>

#include "meshing/core/surface_mesh.hpp"

namespace curvefem::pipeline {

/// Per input vertex: min(eps_rel, field(x)) / eps_rel, field an expression of x, y, z giving the
/// bound relative to the longest bbox edge (like eps_rel itself). A value that is not a positive
/// number at a vertex is an InputError naming `where`, the vertex and its coordinates.
std::vector<double> eps_scale_from_expression(const SurfaceMesh& input, const std::string& field,
                                              double eps_rel, const std::string& where);

}  // namespace curvefem::pipeline
