// Boolean operations with correspondence (thesis §4.4, Fig. 4.25): the corefined results are
// closed, embedded (exact check) and have the volumes inclusion–exclusion says; every result
// face lies in the operand face it is attributed to (CGAL distances of meshing/check).

#include <gtest/gtest.h>

#include "meshing/check/self_intersections.hpp"
#include "meshing/check/surface_distance.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/shell/boolean.hpp"

namespace sh = curvefem::meshing::shell;
using curvefem::SurfaceMesh;

TEST(Boolean, ResultsAreEmbeddedWithInclusionExclusionVolumesAndKnownOrigins) {
  const SurfaceMesh a = curvefem::make_icosphere(3);
  const SurfaceMesh b = curvefem::make_icosphere(3, 0.7, Eigen::Vector3d(0.9, 0.3, 0.2));
  double volume[3];
  int k = 0;
  for (auto op : {sh::BooleanOperation::union_of, sh::BooleanOperation::intersection,
                  sh::BooleanOperation::difference}) {
    const sh::BooleanResult r = sh::corefine_boolean(a, b, op);
    EXPECT_EQ(curvefem::check::count_self_intersecting_pairs(r.mesh.V, r.mesh.F), 0) << k;
    EXPECT_EQ(r.mesh.num_vertices() - r.mesh.num_faces() / 2, 2) << k;  // closed, genus 0
    volume[k] = curvefem::signed_volume(r.mesh);
    // Every face is on the operand face it names: its corners at distance ~0 from it.
    int from[2] = {0, 0};
    for (int f = 0; f < r.mesh.num_faces(); ++f) {
      const SurfaceMesh& m = r.operand[std::size_t(f)] == 0 ? a : b;
      const int g = r.operand_face[std::size_t(f)];
      Eigen::MatrixXd corners(3, 3);
      for (int c = 0; c < 3; ++c) corners.row(c) = r.mesh.V.row(r.mesh.F(f, c));
      Eigen::MatrixXi one(1, 3);
      one << m.F(g, 0), m.F(g, 1), m.F(g, 2);
      ASSERT_LT(curvefem::check::distances_to_surface(corners, m.V, one).maxCoeff(), 1e-12) << f;
      ++from[r.operand[std::size_t(f)]];
    }
    EXPECT_GT(from[0], 0);
    EXPECT_GT(from[1], 0);
    ++k;
  }
  const double va = curvefem::signed_volume(a), vb = curvefem::signed_volume(b);
  EXPECT_NEAR(volume[0] + volume[1], va + vb, 1e-12 * (va + vb));  // |A ∪ B| + |A ∩ B|
  EXPECT_NEAR(volume[2], va - volume[1], 1e-12 * va);              // |A − B| = |A| − |A ∩ B|
  EXPECT_GT(volume[1], 0.05);                                      // they do overlap
}

TEST(Boolean, UnknownOperationAndOpenOperandAreRefused) {
  EXPECT_THROW(sh::parse_boolean_operation("xor"), curvefem::InputError);
  SurfaceMesh open = curvefem::make_icosphere(1);
  open.F.conservativeResize(open.F.rows() - 1, 3);
  EXPECT_ANY_THROW(
      sh::corefine_boolean(curvefem::make_icosphere(1), open, sh::BooleanOperation::union_of));
}
