// Selections of the dense input, seen from the mesh: which boundary points x of the curved (or
// dense) mesh a selection takes, judged at φ⁻¹(x) on the input (DESIGN.md §1: boundary conditions
// are painted on the dense input). The filters are what fem's boundary conditions take.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <memory>

#include "mapping/boundary_inverse.hpp"
#include "mapping/selection.hpp"
#include "meshing/core/surface_mesh.hpp"

namespace curvefem::mapping {

/// x ↦ whether `s` selects φ⁻¹(x). Empty for Kind::all (everything). `closed`: a point on an
/// input edge or vertex is selected if any input face through it is (a Dirichlet part is closed,
/// whichever face the inverse returned where a feature chain runs); this matters only for
/// selections that use face data (tags, normal cones). `input` must outlive the filter; the
/// inverse is shared. φ⁻¹ throws MeshingError for a point off the boundary.
std::function<bool(const Eigen::Vector3d&)> input_selection_filter(
    const Selection& s, const SurfaceMesh& input, std::shared_ptr<const BoundaryInverse> inverse,
    bool closed);

}  // namespace curvefem::mapping
