// is_section (thesis §4.4) on sections and on surfaces that are not (unit label; the section
// remesher and the field roundtrip are in test_shell_section_remesh.cpp).

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "meshing/core/primitives.hpp"
#include "meshing/shell/projection.hpp"
#include "meshing/shell/section.hpp"
#include "meshing/shell/shell.hpp"

namespace sh = curvefem::meshing::shell;
using curvefem::SurfaceMesh;

namespace {

sh::Shell build(const SurfaceMesh& s) {
  sh::ShellOptions o;
  sh::ShellStats stats;
  return sh::build_shell(s, o, stats);
}

SurfaceMesh middle_of(const sh::Shell& shell) {
  SurfaceMesh m;
  m.V = shell.mid;
  m.F = shell.F;
  return m;
}

}  // namespace

TEST(ShellSection, InputAndMiddleSurfaceAreSections) {
  const SurfaceMesh sphere = curvefem::make_icosphere(3);
  const sh::Shell shell = build(sphere);
  const sh::ShellProjection p(shell, sphere);
  EXPECT_TRUE(p.is_section(sphere));
  const sh::SectionCheck c = sh::check_section(p, middle_of(shell));
  EXPECT_TRUE(c.manifold);
  EXPECT_EQ(c.vertices_outside, 0);
  EXPECT_EQ(c.faces_crossing_cage, 0);
  EXPECT_EQ(c.faces_not_transversal, 0);
  EXPECT_EQ(c.degree_failures, 0);
  // A copy pushed a quarter of the way towards the top is a section too.
  SurfaceMesh inflated = sphere;
  inflated.V *= 1.01;
  EXPECT_TRUE(p.is_section(inflated));
}

TEST(ShellSection, RejectsSurfacesThatAreNotSections) {
  const SurfaceMesh sphere = curvefem::make_icosphere(3);
  const sh::Shell shell = build(sphere);
  const sh::ShellProjection p(shell, sphere);
  const sh::SectionChecker checker(p);

  {  // One face flipped: not consistently oriented, and the face fails the pillar test.
    SurfaceMesh m = sphere;
    std::swap(m.F(5, 1), m.F(5, 2));
    const sh::SectionCheck c = checker.check(m);
    EXPECT_FALSE(c.is_section());
    EXPECT_FALSE(c.manifold);
    EXPECT_EQ(c.faces_not_transversal, 1);
  }
  {  // Every face flipped: a closed oriented manifold whose normals oppose the pillars.
    SurfaceMesh m = sphere;
    m.F.col(1).swap(m.F.col(2));
    const sh::SectionCheck c = checker.check(m);
    EXPECT_TRUE(c.manifold);
    EXPECT_FALSE(c.is_section());
    EXPECT_EQ(c.faces_not_transversal, m.num_faces());
  }
  {  // Outside the shell (the half-pillars are 0.04 long): no fiber meets it.
    SurfaceMesh m = sphere;
    m.V *= 1.2;
    const sh::SectionCheck c = checker.check(m);
    EXPECT_FALSE(c.is_section());
    EXPECT_EQ(c.vertices_outside, m.num_vertices());
    EXPECT_EQ(c.degree_failures, 1);
  }
  {  // One vertex pulled out through the top: its faces cross the top surface.
    SurfaceMesh m = sphere;
    m.V.row(m.F(0, 0)) *= 1.1;
    const sh::SectionCheck c = checker.check(m);
    EXPECT_FALSE(c.is_section());
    EXPECT_EQ(c.vertices_outside, 1);
    EXPECT_GT(c.faces_crossing_cage, 0);
  }
  {  // Two nested copies, each a section alone: every fiber crosses twice.
    SurfaceMesh m;
    m.V.resize(2 * sphere.num_vertices(), 3);
    m.V << sphere.V * 0.99, sphere.V * 1.01;
    m.F.resize(2 * sphere.num_faces(), 3);
    m.F << sphere.F, (sphere.F.array() + sphere.num_vertices()).matrix();
    const sh::SectionCheck c = checker.check(m);
    EXPECT_TRUE(c.manifold);
    EXPECT_EQ(c.vertices_outside, 0);
    EXPECT_EQ(c.faces_crossing_cage, 0);
    EXPECT_EQ(c.faces_not_transversal, 0);
    EXPECT_EQ(c.degree_failures, 1);
    EXPECT_FALSE(c.is_section());
  }
}
