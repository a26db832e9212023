// slab_nodes.hpp: the order-k slab tets of one half-prism carry the patch only as far as it needs
// (issue 20: at k ≥ 3 the old shear t · d made every curved slab map cubic).
#include <gtest/gtest.h>

#include <map>

#include "meshing/core/lagrange_nodes.hpp"
#include "meshing/curved/element_distortion.hpp"
#include "meshing/curved/jacobian_certificate.hpp"
#include "meshing/curved/slab_nodes.hpp"
#include "meshing/shell/shell_geometry.hpp"

using namespace curvefem;
namespace cv = curvefem::meshing::curved;
namespace sh = curvefem::meshing::shell;

namespace {

// A prism: base corners below a middle triangle, pillars not parallel.
struct Prism {
  Eigen::Vector3d base[3] = {{0, 0, -0.45}, {1.05, 0.05, -0.4}, {-0.05, 0.95, -0.5}};
  Eigen::Vector3d mid[3] = {{0, 0, 0}, {1, 0, 0.02}, {0, 1, -0.03}};
};

// Patch displacement at (u, v): a quadratic bulge plus `cubic` times a cubic term (0 at corners).
Eigen::Vector3d bulge(double u, double v, double cubic) {
  const double w = 1 - u - v;
  return Eigen::Vector3d(0.02 * w * u, -0.03 * u * v, 0.12 * (w * u + u * v + v * w)) +
         cubic * Eigen::Vector3d(0.1, 0.05, 0.4) * (w * u * v + 0.5 * w * u * (w - u));
}
std::vector<Eigen::Vector3d> patch(int k, double cubic) {
  std::vector<Eigen::Vector3d> d;
  for (const auto& a : lagrange_lattice(CellKind::triangle, k))
    d.push_back(bulge(double(a[1]) / k, double(a[2]) / k, cubic));
  return d;
}

// The corners of split tet `tet` of the bottom half-prism, as slab_tet_nodes takes them.
struct Corners {
  Eigen::Vector3d P[4];
  int lv[4], on_mid[4];
};
Corners corners_of(const Prism& p, const std::array<int, 4>& tet) {
  Corners c;
  for (int j = 0; j < 4; ++j) {
    c.lv[j] = tet[std::size_t(j)] % 3;
    c.on_mid[j] = tet[std::size_t(j)] >= 3;
    c.P[j] = c.on_mid[j] ? p.mid[c.lv[j]] : p.base[c.lv[j]];
  }
  return c;
}

struct SlabTet {
  int corner[4];  // prism corners 0..2 base, 3..5 middle
  Eigen::MatrixXd nodes;
};
std::vector<SlabTet> slab(int k, const Prism& p, const std::vector<Eigen::Vector3d>& d,
                          bool type_a) {
  std::vector<SlabTet> out;
  for (const auto& tet : sh::split_tets(type_a)) {
    const Corners c = corners_of(p, tet);
    SlabTet t;
    for (int j = 0; j < 4; ++j) t.corner[j] = tet[std::size_t(j)];
    t.nodes = cv::slab_tet_nodes(k, c.P, c.lv, c.on_mid, d);
    out.push_back(std::move(t));
  }
  return out;
}

// The shear of the whole patch, t · d(u, v) at every node (the construction before issue 20).
Eigen::MatrixXd full_shear(int k, const Prism& p, const std::array<int, 4>& tet,
                           const std::vector<Eigen::Vector3d>& d) {
  const auto& lattice = lagrange_lattice(CellKind::tetrahedron, k);
  const double xy[3][2] = {{0, 0}, {1, 0}, {0, 1}};
  Eigen::MatrixXd nodes(Eigen::Index(lattice.size()), 3);
  for (std::size_t n = 0; n < lattice.size(); ++n) {
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    double u = 0, v = 0, t = 0;
    for (int j = 0; j < 4; ++j) {
      const double l = double(lattice[n][j]) / k;
      const int c = tet[j];
      x += l * (c >= 3 ? p.mid[c % 3] : p.base[c % 3]);
      u += l * xy[c % 3][0];
      v += l * xy[c % 3][1];
      t += l * (c >= 3);
    }
    nodes.row(Eigen::Index(n)) = (x + t * cv::patch_displacement(d, k, u, v)).transpose();
  }
  return nodes;
}

// Node positions keyed by the multiset of prism corners of their lattice point.
using Key = std::array<int, 4>;
Key key_of(const SlabTet& t, const std::array<int, 4>& a, int k) {
  Key key;
  key.fill(99);
  int n = 0;
  for (int j = 0; j < 4; ++j)
    for (int m = 0; m < a[j]; ++m) key[std::size_t(n++)] = t.corner[j];
  std::sort(key.begin(), key.begin() + k);
  return key;
}

}  // namespace

TEST(SlabNodes, SlabMapIsOnlyAsCurvedAsThePatch) {
  // A patch that is exactly quadratic needs no cubic slab: d3 = 0 at k = 3 and 4, where the full
  // shear t · d is cubic (the cause of issue 20: worse answers at k = 3 than at k = 2).
  const Prism p;
  for (int k : {3, 4})
    for (bool type_a : {true, false}) {
      const auto d = patch(k, 0.0);
      double old_d3 = 0;
      for (const auto& t : slab(k, p, d, type_a)) {
        const cv::ElementDistortion e = cv::element_distortion(k, t.nodes);
        EXPECT_LT(e.d3, 1e-9) << "k = " << k;
        EXPECT_GT(e.jacobian_ratio, 0);
        std::array<int, 4> tet{t.corner[0], t.corner[1], t.corner[2], t.corner[3]};
        old_d3 = std::max(old_d3, cv::element_distortion(k, full_shear(k, p, tet, d)).d3);
      }
      EXPECT_GT(old_d3, 0.05) << "the full shear is cubic: k = " << k;
    }
}

TEST(SlabNodes, OrderTwoIsTheShearOfThePatch) {
  const Prism p;
  const auto d = patch(2, 0.0);
  for (bool type_a : {true, false})
    for (const auto& t : slab(2, p, d, type_a)) {
      std::array<int, 4> tet{t.corner[0], t.corner[1], t.corner[2], t.corner[3]};
      EXPECT_LT((t.nodes - full_shear(2, p, tet, d)).cwiseAbs().maxCoeff(), 1e-15);
    }
}

TEST(SlabNodes, MiddleFaceIsThePatchBaseIsLinearAndTetsConform) {
  const Prism p;
  for (int k : {2, 3, 4})
    for (bool type_a : {true, false}) {
      const auto d = patch(k, 1.0);
      std::map<Key, Eigen::Vector3d> seen;
      const auto& lattice = lagrange_lattice(CellKind::tetrahedron, k);
      for (const auto& t : slab(k, p, d, type_a))
        for (std::size_t n = 0; n < lattice.size(); ++n) {
          const Eigen::Vector3d x = t.nodes.row(Eigen::Index(n)).transpose();
          const Key key = key_of(t, lattice[n], k);
          // Shared lattice points of the three tets coincide exactly.
          if (auto [it, fresh] = seen.try_emplace(key, x); !fresh)
            EXPECT_LT((it->second - x).norm(), 1e-14) << "k = " << k;
          // A node on the middle triangle is the linear point plus the patch there; one on the
          // base is linear.
          double w[3] = {0, 0, 0}, wb[3] = {0, 0, 0};
          bool on_mid = true, on_base = true;
          for (int j = 0; j < 4; ++j) {
            if (lattice[n][j] == 0) continue;
            const int c = t.corner[j];
            (c >= 3 ? w : wb)[c % 3] += double(lattice[n][j]) / k;
            on_mid = on_mid && c >= 3;
            on_base = on_base && c < 3;
          }
          if (on_mid) {
            const Eigen::Vector3d L = w[0] * p.mid[0] + w[1] * p.mid[1] + w[2] * p.mid[2];
            EXPECT_LT((x - L - cv::patch_displacement(d, k, w[1], w[2])).norm(), 1e-14);
          }
          if (on_base) {
            const Eigen::Vector3d L = wb[0] * p.base[0] + wb[1] * p.base[1] + wb[2] * p.base[2];
            EXPECT_LT((x - L).norm(), 1e-15);
          }
        }
    }
}

TEST(SlabNodes, SideFacesDependOnlyOnTheirEdge) {
  // A neighbour prism shares one side quad: its nodes there may depend on that edge's patch nodes
  // only. Changing the rest of the patch (interior and the other edges) must leave them.
  const Prism p;
  for (int k : {3, 4}) {
    const auto d = patch(k, 1.0);
    auto other = d;
    const auto& tri = lagrange_lattice(CellKind::triangle, k);
    for (std::size_t i = 0; i < tri.size(); ++i)
      if (tri[i][2] > 0 && (tri[i][0] > 0 || tri[i][1] > 0))  // every non-corner node off edge 01
        other[i] += Eigen::Vector3d(0.01, -0.02, 0.03);
    for (bool type_a : {true, false}) {
      const auto a = slab(k, p, d, type_a), b = slab(k, p, other, type_a);
      const auto& lattice = lagrange_lattice(CellKind::tetrahedron, k);
      int checked = 0;
      for (std::size_t t = 0; t < a.size(); ++t)
        for (std::size_t n = 0; n < lattice.size(); ++n) {
          bool side = true;  // on the quad of corners 0, 1, 3, 4 (edge 01 and its pillars)
          for (int j = 0; j < 4; ++j)
            if (lattice[n][j] > 0) side = side && a[t].corner[j] % 3 != 2;
          if (!side) continue;
          ++checked;
          EXPECT_LT((a[t].nodes.row(Eigen::Index(n)) - b[t].nodes.row(Eigen::Index(n))).norm(),
                    1e-15);
        }
      EXPECT_GT(checked, 0);
    }
  }
}

TEST(SlabNodes, TheShearFallbackConformsEdgeByEdge) {
  // Without the low-degree nodes the slab is the full shear; a side quad takes the construction
  // its edge is given, whatever the inside of the prism uses.
  const Prism p;
  for (int k : {3, 4})
    for (bool type_a : {true, false}) {
      const auto d = patch(k, 1.0);
      const auto& lattice = lagrange_lattice(CellKind::tetrahedron, k);
      for (const auto& tet : sh::split_tets(type_a)) {
        const Corners cs = corners_of(p, tet);
        const auto& P = cs.P;
        const auto& lv = cs.lv;
        const auto& on_mid = cs.on_mid;
        const Eigen::MatrixXd shear = full_shear(k, p, tet, d);
        const Eigen::MatrixXd low = cv::slab_tet_nodes(k, P, lv, on_mid, d);
        EXPECT_LT((cv::slab_tet_nodes(k, P, lv, on_mid, d, {false, {false, false, false}}) - shear)
                      .cwiseAbs()
                      .maxCoeff(),
                  1e-14);
        // Edge opposite local vertex 1 (vertices 0 and 2) sheared, the rest low-degree.
        const Eigen::MatrixXd mixed =
            cv::slab_tet_nodes(k, P, lv, on_mid, d, {true, {true, false, true}});
        for (std::size_t n = 0; n < lattice.size(); ++n) {
          bool above[3] = {false, false, false};
          for (int j = 0; j < 4; ++j) above[lv[j]] = above[lv[j]] || lattice[n][j] > 0;
          const bool on_quad_02 = above[0] && above[2] && !above[1];
          const Eigen::MatrixXd& expected = on_quad_02 ? shear : low;
          EXPECT_LT((mixed.row(Eigen::Index(n)) - expected.row(Eigen::Index(n))).norm(), 1e-14);
        }
      }
    }
}

TEST(SlabNodes, TheShearCertifiesThinSlabsUnderLargerInwardBulges) {
  // Why the fallback exists: the shear stretches every fiber of the column alike. A flat slab of
  // depth 0.05 under an inward bulge (0.02 at the edge midpoints, 0.033 at the centroid): the
  // low-degree nodes are not certified, the shear is (they hold up to 0.75 and 1.25 times it).
  Prism p;
  for (int i = 0; i < 3; ++i) {
    p.mid[i] = Eigen::Vector3d(i == 1, i == 2, 0);
    p.base[i] = p.mid[i] - Eigen::Vector3d(0, 0, 0.05);
  }
  const int k = 3;
  std::vector<Eigen::Vector3d> d;
  for (const auto& a : lagrange_lattice(CellKind::triangle, k)) {
    const double w = double(a[0]) / k, u = double(a[1]) / k, v = double(a[2]) / k;
    d.push_back(Eigen::Vector3d(0, 0, -0.08 * (w * u + u * v + v * w) - 0.162 * w * u * v));
  }
  for (bool type_a : {true, false}) {
    bool low_ok = true, shear_ok = true;
    for (const auto& tet : sh::split_tets(type_a)) {
      const Corners cs = corners_of(p, tet);
      const auto& P = cs.P;
      const auto& lv = cs.lv;
      const auto& on_mid = cs.on_mid;
      low_ok =
          low_ok && cv::certify_tet_jacobian(k, cv::slab_tet_nodes(k, P, lv, on_mid, d)).verdict ==
                        cv::JacobianVerdict::positive;
      shear_ok = shear_ok &&
                 cv::certify_tet_jacobian(
                     k, cv::slab_tet_nodes(k, P, lv, on_mid, d, {false, {false, false, false}}))
                         .verdict == cv::JacobianVerdict::positive;
    }
    EXPECT_FALSE(low_ok);
    EXPECT_TRUE(shear_ok);
  }
}

TEST(SlabNodes, APinchedCornerGivesOneNodeWhicheverLevelNamesIt) {
  // Issue 21: at a singular (pinched) vertex the base and middle corners are one point with one
  // global id. Every sub-simplex through it must get the same nodes whether a tet names the
  // corner on the base or on the middle triangle, the edges to base corners straight (they are
  // edges of the inner surface the straight interior shares) and those to middle corners on the
  // patch. Before, the full shear gave the diagonal (middle 0, base 1) the patch's share along
  // it, and stitched into the interior as its edge (0, base 1) that tet inverted (the knife disc).
  Prism p;
  p.base[0] = p.mid[0];
  const cv::SlabBlend shear{false, {false, false, false}};
  for (int k : {2, 3, 4})
    for (const cv::SlabBlend& blend : {cv::SlabBlend{}, shear}) {
      const auto d = patch(k, 1.0);
      const auto& lattice = lagrange_lattice(CellKind::tetrahedron, k);
      // Tets naming the pinched corner 0 on the base (prism corner 0) or the middle (3): the
      // same point and the same node keys when 0 and 3 are identified.
      std::map<Key, Eigen::Vector3d> seen;
      int compared = 0;
      for (const std::array<int, 4>& tet :
           {std::array<int, 4>{0, 1, 2, 4}, std::array<int, 4>{3, 1, 2, 4},
            std::array<int, 4>{0, 4, 5, 2}, std::array<int, 4>{3, 4, 5, 2},
            std::array<int, 4>{0, 1, 4, 5}, std::array<int, 4>{3, 1, 4, 5}}) {
        Corners c = corners_of(p, tet);
        const Eigen::MatrixXd X = cv::slab_tet_nodes(k, c.P, c.lv, c.on_mid, d, blend, 1u);
        SlabTet t;
        for (int j = 0; j < 4; ++j)
          t.corner[j] = tet[std::size_t(j)] == 3 ? 0 : tet[std::size_t(j)];
        for (std::size_t n = 0; n < lattice.size(); ++n) {
          const Eigen::Vector3d x = X.row(Eigen::Index(n)).transpose();
          const Key key = key_of(t, lattice[n], k);
          if (auto [it, fresh] = seen.try_emplace(key, x); !fresh) {
            EXPECT_LT((it->second - x).norm(), 1e-14) << "k = " << k;
            ++compared;
          }
          // On an edge from the pinched corner to a base corner: the straight segment.
          int others = 0, other = -1;
          for (int j = 0; j < 4; ++j)
            if (lattice[n][j] > 0 && t.corner[j] != 0) ++others, other = t.corner[j];
          if (others == 1 && other < 3 &&
              lattice[n][0] + lattice[n][1] + lattice[n][2] + lattice[n][3] == k) {
            double l0 = 0;
            for (int j = 0; j < 4; ++j)
              if (t.corner[j] == 0) l0 += double(lattice[n][j]) / k;
            const Eigen::Vector3d L = l0 * p.mid[0] + (1 - l0) * p.base[other];
            EXPECT_LT((x - L).norm(), 1e-14) << "k = " << k << ", edge (0, base " << other << ")";
          }
          // On an edge from it to a middle corner: the patch.
          if (others == 1 && other >= 3) {
            double l0 = 0;
            for (int j = 0; j < 4; ++j)
              if (t.corner[j] == 0) l0 += double(lattice[n][j]) / k;
            const double w[3] = {other == 3 ? 1.0 : l0, other == 4 ? 1 - l0 : 0.0,
                                 other == 5 ? 1 - l0 : 0.0};
            const Eigen::Vector3d L = w[0] * p.mid[0] + w[1] * p.mid[1] + w[2] * p.mid[2];
            EXPECT_LT((x - L - cv::patch_displacement(d, k, w[1], w[2])).norm(), 1e-14)
                << "k = " << k << ", edge (0, middle " << other << ")";
          }
        }
      }
      EXPECT_GT(compared, 0);
      // Without the flag the diagonal (middle 0, base 1) is curved: the defect this guards.
      if (!blend.face) {
        Corners c = corners_of(p, {3, 1, 2, 4});
        const Eigen::MatrixXd X = cv::slab_tet_nodes(k, c.P, c.lv, c.on_mid, d, blend);
        const Eigen::Vector3d e = X.row(4).transpose();  // first node on edge (0, 1)
        const auto& a = lattice[4];
        ASSERT_TRUE(a[0] > 0 && a[1] > 0 && a[2] == 0 && a[3] == 0);
        const double l0 = double(a[0]) / k;
        EXPECT_GT((e - (l0 * p.mid[0] + (1 - l0) * p.base[1])).norm(), 1e-4) << "k = " << k;
      }
    }
}
