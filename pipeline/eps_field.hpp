// Spatially varying ε (issue 22): the bound at each input vertex as a factor of the run's ε, for
// CurvedMeshOptions::eps_scale — from an expression of x, y, z, or per face from a table of the
// input's face tags.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "meshing/core/surface_mesh.hpp"

namespace curvefem::pipeline {

/// Per input vertex: min(eps_rel, field(x)) / eps_rel, field an expression of x, y, z giving the
/// bound relative to the longest bbox edge (like eps_rel itself). A value that is not a positive
/// number at a vertex is an InputError naming `where`, the vertex and its coordinates.
std::vector<double> eps_scale_from_expression(const SurfaceMesh& input, const std::string& field,
                                              double eps_rel, const std::string& where);

/// Per input vertex: min(eps_rel, bound of each face around it) / eps_rel, where a face's bound is
/// by_tag's value for its tag (keys: a tag value such as "3", or a tag name of the input, e.g. an
/// OBJ group) and eps_rel for a tag the table does not name. InputError naming `where` when the
/// input has no face tags, a key names no tag of the input (the message lists the tags it has),
/// or a bound is not in (0, 0.5].
std::vector<double> eps_scale_from_tags(const SurfaceMesh& input,
                                        const std::map<std::string, double>& by_tag, double eps_rel,
                                        const std::string& where);

/// The pointwise minimum of two factor vectors, either of which may be empty (no field).
std::vector<double> min_eps_scale(std::vector<double> a, const std::vector<double>& b);

}  // namespace curvefem::pipeline
