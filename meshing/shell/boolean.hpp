// Boolean operations with correspondence (thesis §4.4, Fig. 4.25): the union, intersection or
// difference of two closed surfaces by CGAL's corefinement (exact constructions), rounded to
// double, with every result face's origin — which operand and which of its faces it lies in — so
// that attributes of both operands can be carried onto the result and, through a shell built on
// the result, onto its coarse remeshing (`curvefem shell A --boolean OP --with B`).
//
// Origin: each result face lies in one operand face (corefinement only splits faces); which one
// is tracked through the corefinement (a visitor passes a face's origin to its pieces and to the
// result's copy), not guessed from positions, so slivers along the intersection curve, close to
// faces of both operands, keep the right one.
#pragma once

#include <string>
#include <vector>

#include "meshing/core/surface_mesh.hpp"

namespace curvefem::meshing::shell {

enum class BooleanOperation { union_of, intersection, difference };

/// "union", "intersection", "difference"; InputError otherwise.
BooleanOperation parse_boolean_operation(const std::string& name);

struct BooleanResult {
  SurfaceMesh mesh;          ///< the result, vertices rounded to double
  std::vector<int> operand;  ///< per result face: 0 (A) or 1 (B)
  std::vector<int> operand_face;
  double max_origin_distance = 0;  ///< largest corner distance to its operand face (rounding)
};

/// MeshingError when CGAL's corefinement refuses (e.g. an operand is not closed or it
/// self-intersects), naming the operation.
BooleanResult corefine_boolean(const SurfaceMesh& a, const SurfaceMesh& b, BooleanOperation op);

/// For points of the result, their place in the operands: operand, face and barycentric
/// coordinates of the closest point of the result face's operand face (#P rows; `faces` = the
/// result face each point lies in).
struct OperandPoint {
  int operand = -1, face = -1;
  Eigen::Vector3d bary{0, 0, 0};
};
std::vector<OperandPoint> locate_in_operands(const SurfaceMesh& a, const SurfaceMesh& b,
                                             const BooleanResult& result,
                                             const Eigen::MatrixXd& points,
                                             const std::vector<int>& faces);

}  // namespace curvefem::meshing::shell
