// mapping/ on real curved meshes (meshing/curved): φ⁻¹ ∘ φ is the identity on the input, a field
// is transferred exactly, and a box painted on the input selects exactly the expected DOFs.
#include <gtest/gtest.h>

#include <set>

#include "fem/problems/constraints.hpp"
#include "fem/space/function_space.hpp"
#include "mapping/boundary_inverse.hpp"
#include "mapping/selection.hpp"
#include "mapping/surface_transfer.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/curved/curved_mesher.hpp"
#include "meshing/curved/features.hpp"
#include "meshing/shell/fibers_of.hpp"

using namespace curvefem;
using namespace curvefem::mapping;
namespace cv = curvefem::meshing::curved;

namespace {
cv::CurvedMesh curved(const SurfaceMesh& input, int k, bool features, double eps = 1e-2) {
  cv::CurvedMeshOptions o;
  o.order = k;
  o.eps_rel = eps;
  o.threads = 1;
  if (features) o.feature_edges = cv::detect_feature_edges(input, 60);
  cv::CurvedMeshStats stats;
  return cv::build_curved_mesh(input, o, stats);
}
double linear_g(const Eigen::Vector3d& x) { return 0.3 + 1.7 * x.x() - 0.9 * x.y() + 2.1 * x.z(); }
}  // namespace

TEST(MappingCurved, LinearFieldPushedThroughInverseAndPulledBackMatchesOnIcosphere) {
  const SurfaceMesh input = make_icosphere(2);
  for (int k : {2, 3}) {
    // ε = 5% so the shell is coarsened: input vertices land inside coarse faces.
    const cv::CurvedMesh cm = curved(input, k, false, 0.05);
    ASSERT_LT(cm.map.boundary.num_cells(), input.num_faces());
    const BoundaryInverse inv(cm.map, meshing::shell::fibers_of(cm.shell, input), input);
    // Push: the field g painted on the input is what a boundary point x of the curved mesh sees,
    // g(φ⁻¹(x)). Pull back: the value at input vertex v is read at φ(v). Round trip: g(v).
    double worst = 0, worst_position = 0;
    for (int v = 0; v < input.num_vertices(); ++v) {
      const Eigen::Vector3d x = cm.map.image(v);
      const InputPoint p = inv.at(x);
      worst =
          std::max(worst, std::abs(linear_g(p.position) - linear_g(input.V.row(v).transpose())));
      worst_position = std::max(worst_position, (p.position - input.V.row(v).transpose()).norm());
      EXPECT_NEAR(p.bary.sum(), 1.0, 1e-12);
      EXPECT_GE(p.bary.minCoeff(), -1e-9);
    }
    EXPECT_LT(worst, 1e-8) << "k = " << k;
    EXPECT_LT(worst_position, 1e-8) << "k = " << k;

    // Every boundary DOF of a degree-k space has a preimage on the input within the shell.
    const fem::FunctionSpace space = fem::build_function_space(cm.mesh, k);
    int boundary_dofs = 0;
    for (int d = 0; d < space.num_dofs; ++d) {
      if (!space.on_boundary[d]) continue;
      ++boundary_dofs;
      const Eigen::Vector3d x = space.dof_points.row(d).transpose();
      const InputPoint p = inv.at(x);
      EXPECT_LT((p.position - x).norm(), 0.1) << d;  // within the shell (ε = 5% of 2)
    }
    EXPECT_GT(boundary_dofs, 0);

    // Exact transfer: a field linear in the physical coordinates is in the isoparametric space;
    // read at φ(v) through the tet's reference coordinates it is exact.
    Eigen::VectorXd u(space.num_dofs);
    for (int d = 0; d < space.num_dofs; ++d) u[d] = linear_g(space.dof_points.row(d).transpose());
    const SurfaceSamples s = locate_input_vertices(cm.mesh, cm.map);
    const Eigen::MatrixXd values = evaluate_on_surface(space, u, 1, s);
    const Eigen::MatrixXd X = sample_positions(cm.mesh, s);
    for (int v = 0; v < input.num_vertices(); ++v) {
      const Eigen::Vector3d phi_v = cm.map.image(v);
      EXPECT_LT((X.row(v).transpose() - phi_v).norm(), 1e-12) << v;
      EXPECT_NEAR(values(v, 0), linear_g(phi_v), 1e-10) << v;
    }
    // Continued from φ(v) to v to first order, it is exact at the input vertex itself.
    const Eigen::MatrixXd extended = evaluate_on_surface_extended(cm.mesh, space, u, 1, s, input.V);
    double moved = 0;
    for (int v = 0; v < input.num_vertices(); ++v) {
      const Eigen::Vector3d x = input.V.row(v).transpose();
      moved = std::max(moved, (cm.map.image(v) - x).norm());
      EXPECT_NEAR(extended(v, 0), linear_g(x), 1e-10) << v;
    }
    EXPECT_GT(moved, 1e-3) << "k = " << k;  // the images are off the input: not a trivial check
  }
}

TEST(MappingCurved, BoxOnTheInputSelectsExactlyTheDofsOfOneCubeSide) {
  // A cube with its edges as features stays flat: the boundary DOFs of side x = 1 are exactly the
  // ones whose preimage on the input has x ≥ 0.999 — an answer known without the map.
  const SurfaceMesh input = make_box({0, 0, 0}, {1, 1, 1}, 4);
  const cv::CurvedMesh cm = curved(input, 2, true);
  const BoundaryInverse inv(cm.map, meshing::shell::fibers_of(cm.shell, input), input);
  const fem::FunctionSpace space = fem::build_function_space(cm.mesh, 2);
  Selection box{.kind = Selection::Kind::box};
  box.lo = {0.999, -1, -1};
  box.hi = {2, 2, 2};
  Selection top{.kind = Selection::Kind::plane};
  top.point = {0, 0, 0.999};
  top.direction = {0, 0, 1};
  for (const auto& [sel, axis] : {std::pair{box, 0}, std::pair{top, 2}}) {
    const Selection s = sel;
    std::set<int> got, expected;
    const std::vector<char> all_faces(space.boundary_faces.size(), 1);
    fem::for_each_boundary_dof(
        space, all_faces,
        [&](const Eigen::Vector3d& x) { return selects(s, site_of(input, inv.at(x))); },
        [&](int d) { got.insert(d); });
    for (int d = 0; d < space.num_dofs; ++d)
      if (space.on_boundary[d] && std::abs(space.dof_points(d, axis) - 1.0) < 1e-9)
        expected.insert(d);
    EXPECT_EQ(got, expected) << "axis " << axis;
    // (2·n_side + 1)² DOFs on a side meshed with n_side edges per side at degree 2: at least 9.
    EXPECT_GE(expected.size(), 9u);
  }
}
