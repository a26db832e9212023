// Section remeshing (thesis §4.4): the remeshed surface is a section, and the field roundtrip
// input → remeshed → input through P converges like interpolation (integration label: ~1 s each).

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "meshing/core/primitives.hpp"
#include "meshing/shell/projection.hpp"
#include "meshing/shell/section_remesh.hpp"
#include "meshing/shell/section_transfer.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/verify.hpp"

namespace sh = curvefem::meshing::shell;
using curvefem::SurfaceMesh;

namespace {

sh::Shell build(const SurfaceMesh& s) {
  sh::ShellOptions o;
  sh::ShellStats stats;
  return sh::build_shell(s, o, stats);
}

}  // namespace

TEST(ShellSectionRemesh, SphereFieldRoundtripConvergesQuadratically) {
  const SurfaceMesh sphere = curvefem::make_icosphere(4);  // 5120 faces, edge ≈ 0.077
  const sh::Shell shell = build(sphere);
  const sh::ShellProjection p(shell, sphere);
  const Eigen::VectorXd f = sh::smooth_test_field(sphere.V, Eigen::Vector3d::Zero(), 1.0);
  // The remeshed values come from the input's own interpolant, whose O(h_in²) error adds to the
  // O(h²) of the roundtrip: targets well above the input's edge keep it small.
  double max_error[2] = {0, 0}, mean_error[2] = {0, 0};
  const double lengths[2] = {0.3, 0.15};
  for (int i = 0; i < 2; ++i) {
    sh::SectionRemeshOptions o;
    o.target_edge = lengths[i];
    const sh::SectionRemeshResult r = sh::remesh_section(p, o);
    EXPECT_TRUE(r.start.is_section());
    EXPECT_TRUE(r.result.is_section()) << lengths[i];
    // A closed surface of area 4π in equilateral triangles of edge L has 2A / (√3 L²) vertices.
    const double expected = 8 * std::numbers::pi / (std::sqrt(3.0) * lengths[i] * lengths[i]);
    EXPECT_GT(r.mesh.num_vertices(), 0.6 * expected) << lengths[i];
    EXPECT_LT(r.mesh.num_vertices(), 1.6 * expected) << lengths[i];
    // Every remeshed vertex lies on the input (P places it there), so inside the unit sphere.
    for (int v = 0; v < r.mesh.num_vertices(); ++v) EXPECT_LE(r.mesh.V.row(v).norm(), 1.0 + 1e-12);
    const sh::FieldRoundtrip rt = sh::field_roundtrip(p, sphere, r.mesh, f);
    EXPECT_EQ(rt.failures, 0);
    max_error[i] = rt.max_error;
    mean_error[i] = rt.mean_error;
    const std::string at = "_L" + std::to_string(lengths[i]);
    RecordProperty("max_error" + at, std::to_string(rt.max_error));
    RecordProperty("mean_error" + at, std::to_string(rt.mean_error));
    RecordProperty("vertices" + at, std::to_string(r.mesh.num_vertices()));
  }
  const double max_rate = std::log2(max_error[0] / max_error[1]),
               mean_rate = std::log2(mean_error[0] / mean_error[1]);
  RecordProperty("max_rate", std::to_string(max_rate));
  RecordProperty("mean_rate", std::to_string(mean_rate));
  EXPECT_LT(max_error[1], 0.05);
  EXPECT_GT(max_rate, 1.5) << max_error[0] << " " << max_error[1];
  EXPECT_GT(mean_rate, 1.5) << mean_error[0] << " " << mean_error[1];
}

TEST(ShellSectionRemesh, PointsRoundtripExactlyAndFlatRegionsReproduceLinearFields) {
  // On a box the remeshed triangles inside a side lie in the side's plane: there the remeshed
  // point on an input vertex's fiber is the vertex itself and a linear field comes back exactly.
  // Triangles across an edge of the box are chords, and there it does not.
  const SurfaceMesh box =
      curvefem::make_box(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1), 12);
  const sh::Shell shell = build(box);
  ASSERT_TRUE(sh::verify_shell(shell, box).valid());
  const sh::ShellProjection p(shell, box);
  sh::SectionRemeshOptions o;
  o.target_edge = 0.15;
  const sh::SectionRemeshResult r = sh::remesh_section(p, o);
  ASSERT_TRUE(r.result.is_section());
  const sh::ShellProjection onto_remeshed(shell, r.mesh);
  Eigen::MatrixXd linear(box.num_vertices(), 1);
  for (int v = 0; v < box.num_vertices(); ++v)
    linear(v, 0) = 0.3 + box.V.row(v).dot(Eigen::RowVector3d(1.5, -2.0, 0.7));
  const sh::FieldRoundtrip rt = sh::field_roundtrip(p, box, r.mesh, linear);
  EXPECT_EQ(rt.failures, 0);
  int flat = 0;
  for (int v = 0; v < box.num_vertices(); ++v) {
    const Eigen::Vector3d x = box.V.row(v);
    const auto q = p.unproject(x);
    ASSERT_TRUE(q);
    const auto there = onto_remeshed.project(*q);
    ASSERT_TRUE(there);
    // The point roundtrip input → remeshed → input is the identity up to rounding.
    const auto q2 = p.locate(there->position);
    ASSERT_TRUE(q2);
    const auto back = p.project(*q2);
    ASSERT_TRUE(back);
    EXPECT_LT((back->position - x).norm(), 1e-12) << v;
    // Is the remeshed triangle there in the plane of a side containing x?
    bool in_side = false;
    for (int axis = 0; axis < 3 && !in_side; ++axis) {
      if (x[axis] != 0.0 && x[axis] != 1.0) continue;
      in_side = true;
      for (int k = 0; k < 3; ++k)
        in_side = in_side && std::abs(r.mesh.V(r.mesh.F(there->face, k), axis) - x[axis]) < 1e-14;
    }
    if (!in_side) continue;
    ++flat;
    EXPECT_NEAR(rt.back(v, 0), linear(v, 0), 1e-12) << v;
  }
  EXPECT_GT(flat, box.num_vertices() / 2);
  RecordProperty("flat_vertices", std::to_string(flat));
  RecordProperty("linear_max_error_all", std::to_string(rt.max_error));
}

TEST(ShellSectionRemesh, TorusRemeshIsASection) {
  const SurfaceMesh torus = curvefem::make_torus(1.0, 0.4, 96, 40);
  const sh::Shell shell = build(torus);
  const sh::ShellProjection p(shell, torus);
  sh::SectionRemeshOptions o;
  o.target_edge = 0.12;
  o.threads = 2;
  const sh::SectionRemeshResult r = sh::remesh_section(p, o);
  EXPECT_TRUE(r.result.is_section());
  const double area = 4 * std::numbers::pi * std::numbers::pi * 1.0 * 0.4;
  const double expected = 2 * area / (std::sqrt(3.0) * o.target_edge * o.target_edge);
  EXPECT_GT(r.mesh.num_vertices(), 0.6 * expected);
  EXPECT_LT(r.mesh.num_vertices(), 1.6 * expected);
  const Eigen::VectorXd f = sh::smooth_test_field(torus.V, Eigen::Vector3d::Zero(), 1.4);
  const sh::FieldRoundtrip rt = sh::field_roundtrip(p, torus, r.mesh, f);
  EXPECT_EQ(rt.failures, 0);
  EXPECT_LT(rt.max_error, 0.05);
  RecordProperty("vertices", std::to_string(r.mesh.num_vertices()));
  RecordProperty("max_error", std::to_string(rt.max_error));
}
