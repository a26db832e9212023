// Locally injective shells of self-intersecting inputs (thesis §4.5, local_sheets.hpp): built,
// simplified and verified against each prism's own sheet; the global checks fail on the same
// inputs, and the verifier still sees a fold of a prism's own sheet.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "meshing/check/self_intersections.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/shell/bevel.hpp"
#include "meshing/shell/local_sheets.hpp"
#include "meshing/shell/projection.hpp"
#include "meshing/shell/section_transfer.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/simplify.hpp"
#include "meshing/shell/verify.hpp"
#include "tests/support/test_support.hpp"

namespace sh = curvefem::meshing::shell;
using curvefem::SurfaceMesh;

namespace {

// Two unit icospheres of level 2 (320 faces each), the second shifted so that they cross: one
// surface with two components passing through each other.
SurfaceMesh crossing_spheres() {
  const SurfaceMesh a = curvefem::make_icosphere(2),
                    b = curvefem::make_icosphere(2, 1.0, Eigen::Vector3d(1.0, 0.13, 0.07));
  SurfaceMesh m;
  m.V.resize(a.V.rows() + b.V.rows(), 3);
  m.V << a.V, b.V;
  m.F.resize(a.F.rows() + b.F.rows(), 3);
  m.F << a.F, (b.F.array() + int(a.V.rows())).matrix();
  return m;
}

int self_intersecting_pairs(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  const std::vector<char> degenerate(std::size_t(F.rows()), 0);
  return int(curvefem::check::find_self_intersections(V, F, degenerate, true).pairs.size());
}

// `roundtrip`: the largest |P(P⁻¹(x)) − x| / bbox edge accepted, rounding in the fiber walk. On
// the coarse figure-eight shell (long slanted prisms) it reaches 1.0e-11 at one thread; the
// dev-mesh data test allows 1e-9 (test_shell_data.cpp), the spheres stay below 1e-12.
void expect_valid(const sh::ShellVerification& v, const std::string& what,
                  double roundtrip = 1e-12) {
  EXPECT_TRUE(v.positive()) << what;
  EXPECT_TRUE(v.separated()) << what << ": " << v.intersecting_input_faces;
  EXPECT_TRUE(v.section()) << what << ": " << v.non_section_faces;
  EXPECT_EQ(v.roundtrip_failures, 0) << what;
  EXPECT_LT(v.roundtrip_max_error_rel, roundtrip) << what;
}

sh::Shell local_shell(const SurfaceMesh& s) {
  sh::ShellOptions o;
  o.local_sheets = true;
  sh::ShellStats stats;
  return sh::build_shell(s, o, stats);
}

}  // namespace

TEST(LocalSheets, AFaceReachesItsOwnSphereOnlyWhereTheOtherCrossesIt) {
  const SurfaceMesh m = crossing_spheres();
  const int na = 320;
  const sh::InputSurfaceIndex index(m.V, m.F);
  const sh::LocalSheets sheets(index);
  // A box around the crossing circle's point nearest +y on sphere A (x = 0.5 is where they meet).
  const Eigen::Vector3d c(0.5, 0.85, 0.05);
  const Eigen::AlignedBox3d box(c - Eigen::Vector3d::Constant(0.3),
                                c + Eigen::Vector3d::Constant(0.3));
  const std::vector<int> in_box = index.faces_in_box(box.min(), box.max());
  int seed = -1, of_b = 0;
  for (int f : in_box) {
    if (f < na && seed < 0) seed = f;
    of_b += f >= na;
  }
  ASSERT_GE(seed, 0);
  ASSERT_GT(of_b, 0) << "the box must hold both spheres";
  const std::vector<int> sheet = sheets.sheet({seed}, box);
  ASSERT_FALSE(sheet.empty());
  for (int f : sheet) EXPECT_LT(f, na) << "face " << f << " of the other sphere reached";
  EXPECT_TRUE(std::is_sorted(sheet.begin(), sheet.end()));
  // Every face of A in the box is reached: A's part of the box is one patch.
  EXPECT_EQ(int(sheet.size()), int(in_box.size()) - of_b);
  // A seed outside the box steps nowhere.
  EXPECT_TRUE(sheets
                  .sheet({m.F.rows() - 1}, Eigen::AlignedBox3d(Eigen::Vector3d(-9, -9, -9),
                                                               Eigen::Vector3d(-8, -8, -8)))
                  .empty());
}

TEST(LocalShell, CrossingSpheresGetAVerifiedLocallyInjectiveShellAndCoarsen) {
  const SurfaceMesh m = crossing_spheres();
  ASSERT_GT(self_intersecting_pairs(m.V, m.F), 0);
  {  // The global invariants cannot hold: no prism at the crossing can keep the other sphere out.
    sh::ShellStats stats;
    EXPECT_THROW(sh::build_shell(m, sh::ShellOptions{}, stats), curvefem::MeshingError);
  }
  const sh::Shell shell = local_shell(m);
  EXPECT_TRUE(shell.local_sheets);
  expect_valid(sh::verify_shell(shell, m), "built");
  // The same prisms claimed globally fail: the other sheet does cross them.
  sh::Shell claimed = shell;
  claimed.local_sheets = false;
  EXPECT_GT(sh::verify_shell(claimed, m).intersecting_input_faces, 0);

  // One sphere alone, with the global invariants and the same options (`curvefem shell`'s zoom).
  sh::SimplifyOptions o;
  o.zoom = 0.1 * 3.0;  // 0.1 of the longest bbox edge of both
  int alone = 0;
  {
    const SurfaceMesh one = curvefem::make_icosphere(2);
    sh::ShellStats built;
    sh::SimplifyStats stats;
    alone = int(sh::simplify_shell(sh::build_shell(one, sh::ShellOptions{}, built), one, o, stats)
                    .F.rows());
    ASSERT_LT(alone, 320 / 3);
  }
  for (int threads : {1, 2}) {
    o.threads = threads;
    sh::SimplifyStats stats;
    const sh::Shell coarse = sh::simplify_shell(shell, m, o, stats);
    const std::string what = "simplified, " + std::to_string(threads) + " thread(s)";
    EXPECT_TRUE(coarse.local_sheets) << what;
    // The crossing costs little: both spheres coarsen about as far as one alone does.
    EXPECT_LE(coarse.F.rows(), 2 * alone) << what;
    expect_valid(sh::verify_shell(coarse, m), what);
    // The coarse middle surface passes through itself too: it is locally injective only.
    EXPECT_GT(self_intersecting_pairs(coarse.mid, coarse.F), 0) << what;
    // P⁻¹ of a point on both spheres' prisms takes the face's sheet: an input vertex of B inside
    // A maps into a prism whose P returns it.
    const sh::ShellProjection projection(coarse, m);
    int inside = 0;
    for (int f = 320; f < m.F.rows(); ++f) {
      const int v = m.F(f, 0);
      const Eigen::Vector3d x = m.V.row(v).transpose();
      if (x.norm() >= 0.98) continue;  // not inside sphere A
      ++inside;
      const auto q = projection.unproject(x, f);
      ASSERT_TRUE(q) << what << ", vertex " << v;
      const auto back = projection.project(*q);
      ASSERT_TRUE(back) << what << ", vertex " << v;
      EXPECT_GE(back->face, 320) << what << ": mapped onto the other sphere";
      EXPECT_LT((back->position - x).norm(), 1e-12) << what << ", vertex " << v;
    }
    EXPECT_GT(inside, 10) << what;
  }
}

TEST(LocalShell, AFigureEightTubeCoarsensThroughItsCrossing) {
  const SurfaceMesh m = curvefem::make_figure_eight_tube(96, 10, 0.12);  // 1920 faces
  ASSERT_GT(self_intersecting_pairs(m.V, m.F), 0);
  double volume = 0;  // outward: positive signed volume
  for (int f = 0; f < m.F.rows(); ++f)
    volume +=
        Eigen::Vector3d(m.V.row(m.F(f, 0)))
            .dot(Eigen::Vector3d(m.V.row(m.F(f, 1))).cross(Eigen::Vector3d(m.V.row(m.F(f, 2))))) /
        6;
  EXPECT_GT(volume, 0);
  {
    sh::ShellStats stats;
    EXPECT_THROW(sh::build_shell(m, sh::ShellOptions{}, stats), curvefem::MeshingError);
  }
  const sh::Shell shell = local_shell(m);
  expect_valid(sh::verify_shell(shell, m), "built");
  sh::SimplifyOptions o;
  o.threads = 1;        // the same coarse shell every run (two threads: the crossing spheres above)
  o.zoom = 0.1 * 2.24;  // 0.1 of the longest bbox edge, as `curvefem shell` does
  sh::SimplifyStats stats;
  const sh::Shell coarse = sh::simplify_shell(shell, m, o, stats);
  // An embedded torus of the same tube and faces, with the global invariants: the figure eight
  // is 1.2 times as long and bends more, and the crossing costs little more than that.
  const SurfaceMesh torus = curvefem::make_torus(0.8, 0.12, 96, 10);
  sh::ShellStats built;
  sh::SimplifyStats torus_stats;
  const int embedded = int(
      sh::simplify_shell(sh::build_shell(torus, sh::ShellOptions{}, built), torus, o, torus_stats)
          .F.rows());
  EXPECT_LT(coarse.F.rows(), m.F.rows() / 4);
  EXPECT_LE(coarse.F.rows(), 1.6 * embedded) << embedded << " faces for the torus";
  expect_valid(sh::verify_shell(coarse, m), "simplified", 1e-10);
}

TEST(LocalShell, TheVerifierStillSeesAFoldOfAPrismsOwnSheet) {
  const SurfaceMesh m = crossing_spheres();
  const sh::Shell shell = local_shell(m);
  expect_valid(sh::verify_shell(shell, m), "built");
  // Push the input vertex of sphere A farthest from B (its -x pole region) outward past the
  // tops of its prisms: its faces now cross prisms of the same sheet.
  int x = 0;
  for (int v = 1; v < 162; ++v)
    if (m.V(v, 0) < m.V(x, 0)) x = v;
  SurfaceMesh spiked = m;
  const double top = (shell.top.row(x) - shell.mid.row(x)).norm();
  spiked.V.row(x) *= 1 + 3 * top;
  const sh::ShellVerification v = sh::verify_shell(shell, spiked);
  EXPECT_FALSE(v.valid());
  EXPECT_GT(v.intersecting_input_faces, 0);
}

// Attribute transfer through a locally injective shell (thesis Fig. 4.28): a field on the input
// carried to the coarse middle surface and back by prism coordinates. A constant returns exactly;
// a smooth field with the coarse surface's interpolation error, no worse than on one sphere alone.
TEST(LocalShell, FieldsGoToTheCoarseMiddleSurfaceAndBack) {
  const SurfaceMesh m = crossing_spheres();
  sh::SimplifyOptions o;
  o.threads = 1;
  o.zoom = 0.3;
  sh::SimplifyStats stats;
  const sh::Shell coarse = sh::simplify_shell(local_shell(m), m, o, stats);
  const sh::ShellProjection projection(coarse, m);
  const sh::FieldRoundtrip constant =
      sh::middle_field_roundtrip(projection, m, Eigen::MatrixXd::Constant(m.V.rows(), 1, 2.5));
  EXPECT_EQ(constant.failures, 0);
  EXPECT_LT(constant.max_error, 1e-12);
  const Eigen::VectorXd f = sh::smooth_test_field(m.V, Eigen::Vector3d(0.5, 0, 0), 1.5);
  const sh::FieldRoundtrip smooth = sh::middle_field_roundtrip(projection, m, f);
  EXPECT_EQ(smooth.failures, 0);
  EXPECT_EQ(smooth.there.rows(), coarse.mid.rows());
  // Sphere A alone, embedded shell, the same field on its vertices.
  const SurfaceMesh one = curvefem::make_icosphere(2);
  sh::ShellStats built;
  const sh::Shell alone =
      sh::simplify_shell(sh::build_shell(one, sh::ShellOptions{}, built), one, o, stats);
  const sh::FieldRoundtrip ref =
      sh::middle_field_roundtrip(sh::ShellProjection(alone, one), one, f.head(one.V.rows()));
  EXPECT_EQ(ref.failures, 0);
  EXPECT_GT(ref.max_error, 0);
  // The same vertices of A (the first 162) in both runs.
  double max_a = 0, sum_a = 0;
  for (int v = 0; v < one.V.rows(); ++v) {
    const double e = std::abs(smooth.back(v, 0) - f[v]);
    max_a = std::max(max_a, e);
    sum_a += e;
  }
  EXPECT_LT(max_a, 2 * ref.max_error) << ref.max_error << " on sphere A alone";
  EXPECT_LT(sum_a / double(one.V.rows()), 2 * ref.mean_error)
      << ref.mean_error << " on sphere A alone";
}

// Beveling (bevel.hpp) in local mode: the crater whose own shell is no section, crossed by a
// sphere. The non-section prisms are found against their sheets, beveled, and the rebuilt shell
// verifies; its singular vertices (the crater's pinch points) go through P⁻¹ and P too.
TEST(LocalShell, ACraterCrossedByASphereIsBeveledAndVerified) {
  const SurfaceMesh crater = curvefem::test::crater_mesh();
  const SurfaceMesh ball = curvefem::make_icosphere(2, 0.5, Eigen::Vector3d(0.3, 0.2, 0.9));
  SurfaceMesh m;
  m.V.resize(crater.V.rows() + ball.V.rows(), 3);
  m.V << crater.V, ball.V;
  m.F.resize(crater.F.rows() + ball.F.rows(), 3);
  m.F << crater.F, (ball.F.array() + int(crater.V.rows())).matrix();
  ASSERT_GT(self_intersecting_pairs(m.V, m.F), 0);
  sh::ShellOptions o;
  o.local_sheets = true;
  sh::ShellStats stats;
  const sh::BeveledShell b = sh::build_beveled_shell(m, o, stats);
  EXPECT_TRUE(b.stats.needed);
  EXPECT_GT(b.stats.beveled_faces, 0);
  EXPECT_TRUE(b.shell.local_sheets);
  EXPECT_GT(stats.singular_vertices, 0);
  expect_valid(sh::verify_shell(b.shell, b.surface.mesh), "beveled");
}
