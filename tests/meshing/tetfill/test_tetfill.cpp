// meshing/tetfill: fill_interior on surfaces built in code (cube, icosphere, torus, voxel L-shape,
// a cube with a cavity, two disjoint cubes), invalid inputs, and verify_tetfill catching
// tampered results. Every surface vertex must come back bit-identical, every surface triangle
// must be a boundary face, and the tets must add up to the enclosed volume.
// TetFillIsolated: detail::run_isolated (the forked child fill_interior runs gmsh in) with
// children that abort, segfault, throw, exit, or return a payload larger than a pipe buffer; and
// fill_interior with and without isolation giving the same tets and the same errors.

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/tetfill/isolated.hpp"
#include "meshing/tetfill/tetfill.hpp"

namespace tf = curvefem::meshing::tetfill;

namespace {

struct Surface {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
};

Surface from_lists(const std::vector<Eigen::Vector3d>& v, const std::vector<Eigen::Vector3i>& f) {
  Surface s;
  s.V.resize(v.size(), 3);
  s.F.resize(f.size(), 3);
  for (size_t i = 0; i < v.size(); ++i) s.V.row(i) = v[i].transpose();
  for (size_t i = 0; i < f.size(); ++i) s.F.row(i) = f[i].transpose();
  return s;
}

/// Σ over faces of det(a, b, c) / 6 (long double, from the centroid): the enclosed volume.
double enclosed_volume(const Surface& s) {
  const Eigen::RowVector3d c = s.V.colwise().mean();
  long double sum = 0;
  for (int f = 0; f < s.F.rows(); ++f) {
    const Eigen::RowVector3d a = s.V.row(s.F(f, 0)) - c, b = s.V.row(s.F(f, 1)) - c,
                             d = s.V.row(s.F(f, 2)) - c;
    sum += a.dot(b.cross(d));
  }
  return static_cast<double>(sum / 6);
}

double tet_volume_sum(const tf::TetFillResult& r) {
  long double sum = 0;
  for (int t = 0; t < r.T.rows(); ++t) {
    const Eigen::RowVector3d x0 = r.V.row(r.T(t, 0)), x1 = r.V.row(r.T(t, 1)),
                             x2 = r.V.row(r.T(t, 2)), x3 = r.V.row(r.T(t, 3));
    sum += (x1 - x0).dot((x2 - x0).cross(x3 - x0));
  }
  return static_cast<double>(sum / 6);
}

void orient_outward(Surface& s) {
  if (enclosed_volume(s) < 0) s.F.col(1).swap(s.F.col(2));
}

/// Boundary of a union of unit voxels (cells (i, j, k) with filled(i, j, k)), lattice vertices
/// shared, each exposed square split into two outward triangles.
template <class Filled>
Surface voxel_surface(int n, Filled filled) {
  std::map<std::array<int, 3>, int> id;
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector3i> f;
  auto vertex = [&](std::array<int, 3> p) {
    auto [it, inserted] = id.emplace(p, static_cast<int>(v.size()));
    if (inserted) v.emplace_back(p[0], p[1], p[2]);
    return it->second;
  };
  auto in = [&](int i, int j, int k) {
    return i >= 0 && j >= 0 && k >= 0 && i < n && j < n && k < n && filled(i, j, k);
  };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        if (!in(i, j, k)) continue;
        for (int axis = 0; axis < 3; ++axis)
          for (int side = 0; side < 2; ++side) {
            std::array<int, 3> nb{i, j, k};
            nb[axis] += side ? 1 : -1;
            if (in(nb[0], nb[1], nb[2])) continue;
            // Square at the cell side, corners counter-clockwise seen from outside.
            const int u = (axis + 1) % 3, w = (axis + 2) % 3;
            std::array<std::array<int, 3>, 4> q;
            for (int c = 0; c < 4; ++c) {
              q[c] = {i, j, k};
              q[c][axis] += side;
              q[c][u] += (c == 1 || c == 2);
              q[c][w] += (c >= 2);
            }
            std::array<int, 4> ids{vertex(q[0]), vertex(q[1]), vertex(q[2]), vertex(q[3])};
            // (u, w) is right-handed with +axis: the order 0,1,2,3 faces +axis.
            if (side == 1) {
              f.emplace_back(ids[0], ids[1], ids[2]);
              f.emplace_back(ids[0], ids[2], ids[3]);
            } else {
              f.emplace_back(ids[0], ids[2], ids[1]);
              f.emplace_back(ids[0], ids[3], ids[2]);
            }
          }
      }
  return from_lists(v, f);
}

Surface cube() {
  return voxel_surface(1, [](int, int, int) { return true; });
}

// Procedural shapes from meshing/core (closed, outward).
Surface icosphere(int levels) {
  const curvefem::SurfaceMesh m = curvefem::make_icosphere(levels);
  return {m.V, m.F};
}

Surface torus(int nu, int nv, double R, double r) {
  const curvefem::SurfaceMesh m = curvefem::make_torus(R, r, nu, nv);
  return {m.V, m.F};
}

/// Runs fill_interior and checks every guarantee of the header with code of its own.
tf::TetFillResult fill_and_check(const Surface& s, const tf::TetFillOptions& o = {}) {
  const tf::TetFillResult r = tf::fill_interior(s.V, s.F, o);
  const tf::TetFillVerification v = tf::verify_tetfill(s.V, s.F, r);
  EXPECT_TRUE(v.valid()) << v.non_positive_tets << " " << v.missing_boundary_faces << " "
                         << v.extra_boundary_faces << " " << v.bad_interior_faces << " "
                         << v.moved_boundary_vertices << " " << v.volume_error_rel;
  EXPECT_EQ(v.non_positive_tets, 0);
  EXPECT_EQ(v.missing_boundary_faces, 0);
  EXPECT_EQ(v.extra_boundary_faces, 0);
  EXPECT_EQ(v.bad_interior_faces, 0);
  EXPECT_EQ(v.moved_boundary_vertices, 0);
  EXPECT_EQ(v.tets, r.T.rows());

  // Boundary vertices bit-identical (== on doubles), in the same rows.
  EXPECT_EQ(r.boundary_vertices, s.V.rows());
  EXPECT_GE(r.V.rows(), s.V.rows());
  EXPECT_EQ(r.T.cols(), 4);
  bool identical = r.V.rows() >= s.V.rows();
  for (int i = 0; identical && i < s.V.rows(); ++i)
    for (int k = 0; k < 3; ++k) identical = identical && r.V(i, k) == s.V(i, k);
  EXPECT_TRUE(identical);

  // Every tet positive (floating det; the exact test is verify_tetfill's), indices valid.
  int bad = 0;
  for (int t = 0; t < r.T.rows(); ++t) {
    if (r.T.row(t).minCoeff() < 0 || r.T.row(t).maxCoeff() >= r.V.rows()) {
      ++bad;
      continue;
    }
    const Eigen::RowVector3d x0 = r.V.row(r.T(t, 0)), x1 = r.V.row(r.T(t, 1)),
                             x2 = r.V.row(r.T(t, 2)), x3 = r.V.row(r.T(t, 3));
    const double det = (x1 - x0).dot((x2 - x0).cross(x3 - x0));
    if (!(det > 0)) ++bad;
  }
  EXPECT_EQ(bad, 0);

  // Faces used once are exactly the input triangles, with the same orientation: outward faces of
  // a positive tet (a, b, c, d) are (a, c, b), (a, b, d), (a, d, c), (b, c, d); compared after
  // rotating the smallest id first.
  auto rotated = [](int a, int b, int c) {
    std::array<int, 3> k{a, b, c};
    std::rotate(k.begin(), std::min_element(k.begin(), k.end()), k.end());
    return k;
  };
  auto sorted = [](std::array<int, 3> k) {
    std::sort(k.begin(), k.end());
    return k;
  };
  std::map<std::array<int, 3>, std::vector<std::array<int, 3>>> uses;
  for (int t = 0; t < r.T.rows(); ++t) {
    const int a = r.T(t, 0), b = r.T(t, 1), c = r.T(t, 2), d = r.T(t, 3);
    for (const auto& k : {rotated(a, c, b), rotated(a, b, d), rotated(a, d, c), rotated(b, c, d)})
      uses[sorted(k)].push_back(k);
  }
  std::set<std::array<int, 3>> once;
  int bad_interior = 0;
  for (const auto& [key, list] : uses) {
    if (list.size() == 1) once.insert(list[0]);
    if (list.size() > 2 || (list.size() == 2 && list[0] == list[1])) ++bad_interior;
  }
  EXPECT_EQ(bad_interior, 0);
  std::set<std::array<int, 3>> input;
  for (int f = 0; f < s.F.rows(); ++f) input.insert(rotated(s.F(f, 0), s.F(f, 1), s.F(f, 2)));
  EXPECT_EQ(once.size(), static_cast<size_t>(s.F.rows()));
  EXPECT_TRUE(once == input);
  // No interior vertex on the boundary: boundary faces only use input vertices.
  for (const auto& k : once) EXPECT_LT(std::max({k[0], k[1], k[2]}), s.V.rows());

  const double expected = enclosed_volume(s);
  EXPECT_GT(expected, 0);
  EXPECT_NEAR(tet_volume_sum(r), expected, 1e-12 * expected);
  EXPECT_GT(r.seconds, 0);
  return r;
}

std::string message_of(const Surface& s) {
  try {
    tf::fill_interior(s.V, s.F);
  } catch (const curvefem::InputError& e) {
    return e.what();
  }
  return "no InputError";
}

}  // namespace

TEST(TetFill, Cube) {
  const Surface s = cube();
  ASSERT_EQ(s.F.rows(), 12);
  ASSERT_EQ(s.V.rows(), 8);
  const tf::TetFillResult r = fill_and_check(s);
  // 5 or 6 tets without interior points; gmsh may add a few.
  EXPECT_GE(r.T.rows(), 5);
  EXPECT_LE(r.T.rows(), 40);
  EXPECT_NEAR(tet_volume_sum(r), 1.0, 1e-14);
}

TEST(TetFill, Icosphere) {
  const Surface s = icosphere(3);
  ASSERT_EQ(s.F.rows(), 1280);
  ASSERT_EQ(s.V.rows(), 642);
  const tf::TetFillResult r = fill_and_check(s);
  // An isotropic ball: a few thousand tets, with interior vertices.
  EXPECT_GE(r.T.rows(), 1500);
  EXPECT_LE(r.T.rows(), 20000);
  EXPECT_GT(r.V.rows(), s.V.rows());
  EXPECT_NEAR(tet_volume_sum(r), 4.0 / 3.0 * M_PI, 0.02 * 4.0 / 3.0 * M_PI);
}

TEST(TetFill, TorusGenusOne) {
  const Surface s = torus(32, 12, 1.0, 0.35);
  ASSERT_EQ(s.F.rows(), 768);
  const tf::TetFillResult r = fill_and_check(s);
  EXPECT_GE(r.T.rows(), 768 / 2);
  EXPECT_LE(r.T.rows(), 10000);
  const double exact = 2 * M_PI * M_PI * 1.0 * 0.35 * 0.35;
  // The 12-gon tube section has (12 / 2π) sin(2π / 12) ≈ 0.955 of the disk's area.
  EXPECT_NEAR(tet_volume_sum(r), exact, 0.08 * exact);
}

TEST(TetFill, NonConvexLShapeWithNotch) {
  // 4×4×2 slab minus a 2×2×2 corner (L-shape) minus a 1×1×1 notch in the long arm.
  const Surface s = voxel_surface(4, [](int i, int j, int k) {
    if (k >= 2) return false;
    if (i >= 2 && j >= 2) return false;
    if (i == 0 && j == 1 && k == 1) return false;
    return true;
  });
  const tf::TetFillResult r = fill_and_check(s);
  EXPECT_NEAR(tet_volume_sum(r), 32.0 - 8.0 - 1.0, 1e-12 * 23);
  EXPECT_GE(r.T.rows(), 23 * 5);
  EXPECT_LE(r.T.rows(), 2000);
}

TEST(TetFill, SchoenhardtPrismNeedsInteriorSteinerPoint) {
  // Twisted triangular prism; one choice of side diagonals gives Schönhardt's polyhedron, which
  // has no tetrahedralization without a Steiner point: gmsh must add one inside, not on the
  // boundary. The other choice is tetrahedralizable as is.
  for (const bool schoenhardt_diagonal : {true, false}) {
    std::vector<Eigen::Vector3d> v;
    for (int i = 0; i < 3; ++i)
      v.emplace_back(std::cos(2 * M_PI * i / 3), std::sin(2 * M_PI * i / 3), 0);
    for (int i = 0; i < 3; ++i) {
      const double a = 2 * M_PI * i / 3 + M_PI / 6;
      v.emplace_back(std::cos(a), std::sin(a), 1);
    }
    std::vector<Eigen::Vector3i> f = {{0, 2, 1}, {3, 4, 5}};
    for (int i = 0; i < 3; ++i) {
      const int a0 = i, a1 = (i + 1) % 3, b0 = 3 + i, b1 = 3 + (i + 1) % 3;
      if (schoenhardt_diagonal) {
        f.emplace_back(a0, a1, b1), f.emplace_back(a0, b1, b0);
      } else {
        f.emplace_back(a0, a1, b0), f.emplace_back(a1, b1, b0);
      }
    }
    Surface s = from_lists(v, f);
    orient_outward(s);
    const tf::TetFillResult r = fill_and_check(s);
    if (schoenhardt_diagonal) {
      EXPECT_GT(r.V.rows(), 6);
    }
    EXPECT_GE(r.T.rows(), 3);
  }
}

TEST(TetFill, CubeWithCavity) {
  // 3×3×3 voxels minus the centre: an outer shell and an inward-oriented inner shell.
  const Surface s =
      voxel_surface(3, [](int i, int j, int k) { return !(i == 1 && j == 1 && k == 1); });
  ASSERT_EQ(s.F.rows(), 6 * 9 * 2 + 6 * 2);
  const tf::TetFillResult r = fill_and_check(s);
  EXPECT_NEAR(tet_volume_sum(r), 26.0, 1e-12 * 26);
}

TEST(TetFill, NestedOutwardShellsAreRejected) {
  // The inner shell of CubeWithCavity flipped outward: two overlapping solids, not a cavity.
  Surface s = voxel_surface(3, [](int i, int j, int k) { return !(i == 1 && j == 1 && k == 1); });
  // Inner faces of s are those whose vertices all have coordinates in [1, 2].
  int flipped = 0;
  for (int f = 0; f < s.F.rows(); ++f) {
    bool in = true;
    for (int k = 0; k < 3; ++k)
      in = in && s.V.row(s.F(f, k)).minCoeff() >= 1 && s.V.row(s.F(f, k)).maxCoeff() <= 2;
    if (in) std::swap(s.F(f, 1), s.F(f, 2)), ++flipped;
  }
  ASSERT_EQ(flipped, 12);
  const std::string m = message_of(s);
  EXPECT_NE(m.find("nested with winding number 1"), std::string::npos) << m;
}

TEST(TetFill, TwoDisjointCubes) {
  const Surface s =
      voxel_surface(3, [](int i, int j, int k) { return (i == 0 || i == 2) && j == 0 && k == 0; });
  const tf::TetFillResult r = fill_and_check(s);
  EXPECT_NEAR(tet_volume_sum(r), 2.0, 1e-14);
}

TEST(TetFill, SizeFactorControlsInteriorDensity) {
  const Surface s = icosphere(2);
  tf::TetFillOptions fine, coarse;
  fine.size_factor = 0.5;
  coarse.size_factor = 2.0;
  const tf::TetFillResult rf = fill_and_check(s, fine);
  const tf::TetFillResult rc = fill_and_check(s, coarse);
  EXPECT_GT(rf.T.rows(), 2 * rc.T.rows());
  EXPECT_GT(rf.V.rows() - s.V.rows(), 4 * (rc.V.rows() - s.V.rows()));
}

TEST(TetFill, WithoutOptimizationStillValid) {
  tf::TetFillOptions o;
  o.optimize = false;
  fill_and_check(torus(24, 10, 1.0, 0.4), o);
}

TEST(TetFill, RepeatableAndSameAtTwoThreads) {
  // gmsh is global state: a second call (and a call with 2 threads) must give the same mesh.
  // In process: an isolated child always runs gmsh on one thread.
  const Surface s = torus(24, 10, 1.0, 0.4);
  tf::TetFillOptions two;
  two.threads = 2;
  two.isolate = false;
  const tf::TetFillResult a = tf::fill_interior(s.V, s.F);
  const tf::TetFillResult b = tf::fill_interior(s.V, s.F, two);
  ASSERT_EQ(a.T.rows(), b.T.rows());
  ASSERT_EQ(a.V.rows(), b.V.rows());
  EXPECT_TRUE((a.T.array() == b.T.array()).all());
  EXPECT_TRUE((a.V.array() == b.V.array()).all());
}

TEST(TetFill, SelfIntersectingSurfaceFailsAsMeshingError) {
  // A vertex of a sphere pulled through the opposite side: combinatorially a valid closed
  // surface, geometrically self-intersecting. Outside the contract (meshing/check rejects it);
  // fill_interior must then throw, never return a mesh.
  Surface s = icosphere(2);
  s.V.row(0) *= -1.6;
  try {
    tf::fill_interior(s.V, s.F);
    ADD_FAILURE() << "no exception";
  } catch (const curvefem::MeshingError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("tetfill: ", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find("boundary recovery failed"), std::string::npos)
        << e.what();
    std::printf("%s\n", e.what());
  }
  // gmsh is global state: a failure must not leave it unusable for the next call.
  const Surface ok = cube();
  EXPECT_EQ(tf::fill_interior(ok.V, ok.F).T.rows() >= 5, true);
}

TEST(TetFill, InvertedFaceThrows) {
  Surface s = icosphere(1);
  std::swap(s.F(7, 1), s.F(7, 2));
  const std::string m = message_of(s);
  EXPECT_NE(m.find("same direction"), std::string::npos) << m;
  EXPECT_NE(m.find("face"), std::string::npos) << m;
}

TEST(TetFill, OpenSurfaceThrows) {
  Surface s = cube();
  s.F.conservativeResize(11, 3);
  const std::string m = message_of(s);
  EXPECT_NE(m.find("open"), std::string::npos) << m;
}

TEST(TetFill, CavityOutsideAnySolidThrows) {
  // A 2×1×1 bar and a separate unit cube oriented inward: an inverted shell, not a cavity.
  Surface s = voxel_surface(4, [](int i, int j, int k) { return i != 2 && j == 0 && k == 0; });
  for (int f = 0; f < s.F.rows(); ++f)
    if (s.V(s.F(f, 0), 0) >= 3 && s.V(s.F(f, 1), 0) >= 3 && s.V(s.F(f, 2), 0) >= 3)
      std::swap(s.F(f, 1), s.F(f, 2));
  const std::string m = message_of(s);
  EXPECT_NE(m.find("inward component 1 is nested with winding number 0"), std::string::npos) << m;
}

TEST(TetFill, InwardSurfaceThrows) {
  Surface s = icosphere(1);
  s.F.col(1).swap(s.F.col(2));
  const std::string m = message_of(s);
  EXPECT_NE(m.find("oriented outward"), std::string::npos) << m;
}

TEST(TetFill, IndexOutOfRangeThrows) {
  Surface s = cube();
  s.F(3, 2) = 8;
  const std::string m = message_of(s);
  EXPECT_NE(m.find("out of range"), std::string::npos) << m;
}

TEST(TetFillVerify, CatchesTamperedResults) {
  const Surface s = icosphere(2);
  const tf::TetFillResult good = tf::fill_interior(s.V, s.F);
  ASSERT_TRUE(tf::verify_tetfill(s.V, s.F, good).valid());

  tf::TetFillResult flipped = good;  // one tet with two vertices swapped
  std::swap(flipped.T(0, 0), flipped.T(0, 1));
  const auto vf = tf::verify_tetfill(s.V, s.F, flipped);
  EXPECT_EQ(vf.non_positive_tets, 1);
  EXPECT_FALSE(vf.valid());

  tf::TetFillResult moved = good;  // a boundary vertex nudged by one ulp
  moved.V(3, 0) = std::nextafter(moved.V(3, 0), 10.0);
  const auto vm = tf::verify_tetfill(s.V, s.F, moved);
  EXPECT_EQ(vm.moved_boundary_vertices, 1);
  EXPECT_FALSE(vm.valid());

  tf::TetFillResult dropped = good;  // a tet removed: its faces become boundary or vanish
  dropped.T = good.T.bottomRows(good.T.rows() - 1);
  const auto vd = tf::verify_tetfill(s.V, s.F, dropped);
  EXPECT_GT(vd.missing_boundary_faces + vd.extra_boundary_faces, 0);
  EXPECT_GT(vd.volume_error_rel, 0);
  EXPECT_FALSE(vd.valid());

  tf::TetFillResult doubled = good;  // a tet used twice
  doubled.T.conservativeResize(good.T.rows() + 1, 4);
  doubled.T.row(good.T.rows()) = good.T.row(0);
  const auto vdd = tf::verify_tetfill(s.V, s.F, doubled);
  EXPECT_GT(vdd.bad_interior_faces + vdd.extra_boundary_faces, 0);
  EXPECT_FALSE(vdd.valid());
}

// ---- isolation (detail::run_isolated, the code path of TetFillOptions::isolate) -------------
// Each test fails if the body ran in the test process instead of a child: the crash tests would
// kill the test binary, the others check the child's pid or that its side effects stay there.

namespace {

namespace detail = curvefem::meshing::tetfill::detail;

const detail::IsolationText k_text{.failed = "test: ", .name = "worker", .note = "; note"};

/// Called in the child before a deliberate crash: no core file.
void no_core_dump() {
  const rlimit zero{0, 0};
  setrlimit(RLIMIT_CORE, &zero);
}

/// The text of the MeshingError run_isolated throws ("no MeshingError" if it returns); other
/// exception types propagate and fail the test.
std::string isolated_error(const std::function<std::string()>& body) {
  try {
    detail::run_isolated(body, k_text);
  } catch (const curvefem::MeshingError& e) {
    return e.what();
  }
  return "no MeshingError";
}

std::string pid_text(pid_t pid) { return "pid " + std::to_string(pid); }

}  // namespace

TEST(TetFillIsolated, AbortInChildIsMeshingErrorNamingTheSignal) {
  const std::string m = isolated_error([] {
    no_core_dump();
    std::abort();
    return std::string();
  });
  // Reaching this line is the parent surviving the child's abort.
  EXPECT_EQ(m, "test: worker crashed (signal " + std::to_string(SIGABRT) + " " +
                   strsignal(SIGABRT) + "; note)");
  EXPECT_NE(m.find("Aborted"), std::string::npos) << m;  // glibc's strsignal(SIGABRT)
  // The parent can go on isolating after a crash.
  EXPECT_EQ(detail::run_isolated([] { return std::string("after"); }), "after");
}

TEST(TetFillIsolated, SegfaultInChildIsMeshingError) {
  const std::string m = isolated_error([] {
    no_core_dump();
    std::raise(SIGSEGV);
    return std::string();
  });
  EXPECT_EQ(m, "test: worker crashed (signal " + std::to_string(SIGSEGV) + " " +
                   strsignal(SIGSEGV) + "; note)");
}

TEST(TetFillIsolated, ChildErrorsAreRethrownWithTheirText) {
  // MeshingError: same text, thrown in another process (its pid is in the text).
  const std::string m = isolated_error(
      []() -> std::string { throw curvefem::MeshingError("xyz from " + pid_text(getpid())); });
  EXPECT_NE(m.find("xyz from pid "), std::string::npos) << m;
  EXPECT_EQ(m.find(pid_text(getpid())), std::string::npos) << "body ran in the parent: " << m;
  // Any std::exception arrives as a MeshingError with its text (a runtime_error would escape
  // isolated_error if the body ran here).
  EXPECT_EQ(isolated_error([]() -> std::string { throw std::runtime_error("abc"); }), "abc");
  // Anything else, and a child that leaves without reporting.
  EXPECT_EQ(isolated_error([]() -> std::string { throw 42; }), "test: unknown error in worker");
  EXPECT_EQ(isolated_error([]() -> std::string { ::_exit(7); }),
            "test: the worker child process exited with status 7");
}

TEST(TetFillIsolated, LargePayloadArrivesBitIdentical) {
  // 2^16 doubles (special values included) and 2^16 ints: 768 KiB, far more than a 64 KiB pipe
  // buffer, so reading only after waitpid would deadlock (the alarm then kills the test).
  std::mt19937_64 rng(12345);
  std::vector<double> d(1 << 16);
  std::vector<std::int32_t> k(1 << 16);
  for (auto& x : d) x = std::ldexp(static_cast<double>(rng()), -64) * 1e3 - 500;
  for (auto& x : k) x = static_cast<std::int32_t>(rng());
  d[0] = -0.0, d[1] = std::numeric_limits<double>::denorm_min(), d[2] = INFINITY;
  d[3] = std::numeric_limits<double>::quiet_NaN(), d[4] = std::nextafter(1.0, 2.0);
  int touched = 0;
  ::alarm(30);
  const std::string bytes = detail::run_isolated(
      [&] {
        touched = 1;  // in the child's copy of the memory only
        const pid_t pid = getpid();
        std::string b(sizeof pid + d.size() * sizeof(double) + k.size() * sizeof(std::int32_t),
                      '\0');
        std::memcpy(b.data(), &pid, sizeof pid);
        std::memcpy(b.data() + sizeof pid, d.data(), d.size() * sizeof(double));
        std::memcpy(b.data() + sizeof pid + d.size() * sizeof(double), k.data(),
                    k.size() * sizeof(std::int32_t));
        return b;
      },
      k_text);
  ::alarm(0);
  EXPECT_EQ(touched, 0) << "body ran in the parent";
  ASSERT_EQ(bytes.size(), sizeof(pid_t) + d.size() * sizeof(double) + k.size() * 4);
  pid_t child = 0;
  std::memcpy(&child, bytes.data(), sizeof child);
  EXPECT_NE(child, getpid());
  std::vector<double> d_back(d.size());
  std::vector<std::int32_t> k_back(k.size());
  std::memcpy(d_back.data(), bytes.data() + sizeof child, d.size() * sizeof(double));
  std::memcpy(k_back.data(), bytes.data() + sizeof child + d.size() * sizeof(double),
              k.size() * sizeof(std::int32_t));
  EXPECT_EQ(std::memcmp(d_back.data(), d.data(), d.size() * sizeof(double)), 0);
  EXPECT_EQ(k_back, k);
  // An empty payload is a success, not a child that died before reporting.
  EXPECT_EQ(detail::run_isolated([] { return std::string(); }), "");
}

TEST(TetFillIsolated, FillInteriorSameWithAndWithoutIsolation) {
  tf::TetFillOptions in_process, isolated;
  in_process.isolate = false;
  isolated.isolate = true;
  // A ball with interior vertices and a cube with a cavity (two gmsh surfaces).
  for (const Surface& s : {icosphere(3), voxel_surface(3, [](int i, int j, int k) {
                             return !(i == 1 && j == 1 && k == 1);
                           })}) {
    const tf::TetFillResult a = fill_and_check(s, in_process);
    const tf::TetFillResult b = fill_and_check(s, isolated);
    EXPECT_GT(a.V.rows(), s.V.rows());
    ASSERT_EQ(a.T.rows(), b.T.rows());
    ASSERT_EQ(a.V.rows(), b.V.rows());
    EXPECT_TRUE((a.T.array() == b.T.array()).all());
    EXPECT_EQ(std::memcmp(a.V.data(), b.V.data(), a.V.size() * sizeof(double)), 0);
    EXPECT_GT(b.gmsh_seconds, 0);
  }
  // A gmsh failure in the child arrives with the same text as in the process.
  Surface bad = icosphere(2);
  bad.V.row(0) *= -1.6;
  std::string errors[2];
  for (const bool isolate : {false, true}) {
    tf::TetFillOptions o;
    o.isolate = isolate;
    try {
      tf::fill_interior(bad.V, bad.F, o);
      ADD_FAILURE() << "no exception";
    } catch (const curvefem::MeshingError& e) {
      errors[isolate] = e.what();
    }
  }
  EXPECT_NE(errors[0].find("boundary recovery failed"), std::string::npos) << errors[0];
  EXPECT_EQ(errors[1], errors[0]);
}
