#include "meshing/check/self_intersections.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>
#include <tbb/concurrent_vector.h>

#include <algorithm>
#include <iterator>

#include "meshing/core/error.hpp"

namespace curvefem::check {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Segment = Kernel::Segment_3;
using Triangle = Kernel::Triangle_3;
using Mesh = CGAL::Surface_mesh<Point>;
using Box =
    CGAL::Box_intersection_d::Box_with_info_d<double, 3, int,
                                              CGAL::Box_intersection_d::ID_FROM_BOX_ADDRESS>;

// Faces per box-tree leaf before brute force (the value PMP uses).
constexpr std::ptrdiff_t k_box_cutoff = 2000;

std::vector<Point> to_points(const Eigen::MatrixXd& V) {
  std::vector<Point> points;
  points.reserve(static_cast<std::size_t>(V.rows()));
  for (Eigen::Index i = 0; i < V.rows(); ++i) points.emplace_back(V(i, 0), V(i, 1), V(i, 2));
  return points;
}

// The rule of the header, on vertex indices.
class SoupPairTest {
 public:
  SoupPairTest(const std::vector<Point>& points, const Eigen::MatrixXi& F)
      : m_points(points), m_F(F) {}

  bool operator()(int f, int g) const {
    int fi[3], gi[3];
    for (int k = 0; k < 3; ++k) {
      fi[k] = m_F(f, k);
      gi[k] = m_F(g, k);
    }
    int shared = 0, f_shared = -1, g_shared = -1, f_free = -1;
    for (int i = 0; i < 3; ++i) {
      bool found = false;
      for (int j = 0; j < 3 && !found; ++j) {
        if (fi[i] == gi[j]) {
          found = true;
          f_shared = i;
          g_shared = j;
        }
      }
      if (found)
        ++shared;
      else
        f_free = i;
    }
    if (shared == 3) return true;  // the same triangle twice
    if (shared == 2) {
      int g_free = 0;
      while (gi[g_free] == fi[0] || gi[g_free] == fi[1] || gi[g_free] == fi[2]) ++g_free;
      const Point& p = m_points[fi[(f_free + 1) % 3]];
      const Point& q = m_points[fi[(f_free + 2) % 3]];
      const Point& r = m_points[fi[f_free]];
      const Point& s = m_points[gi[g_free]];
      return CGAL::coplanar(p, q, r, s) && CGAL::coplanar_orientation(p, q, r, s) == CGAL::POSITIVE;
    }
    const Triangle tf = triangle(fi), tg = triangle(gi);
    if (shared == 1) {
      const Segment sf(m_points[fi[(f_shared + 1) % 3]], m_points[fi[(f_shared + 2) % 3]]);
      const Segment sg(m_points[gi[(g_shared + 1) % 3]], m_points[gi[(g_shared + 2) % 3]]);
      // Bounding boxes of double points are exact: disjoint boxes decide without the predicates
      // (the fans of a fine sampled surface are mostly such pairs).
      return (CGAL::do_overlap(tf.bbox(), sg.bbox()) && CGAL::do_intersect(tf, sg)) ||
             (CGAL::do_overlap(tg.bbox(), sf.bbox()) && CGAL::do_intersect(tg, sf));
    }
    return CGAL::do_intersect(tf, tg);
  }

 private:
  Triangle triangle(const int* v) const {
    return Triangle(m_points[v[0]], m_points[v[1]], m_points[v[2]]);
  }
  const std::vector<Point>& m_points;
  const Eigen::MatrixXi& m_F;
};

std::vector<std::pair<int, int>> soup_self_intersections(const Eigen::MatrixXd& V,
                                                         const Eigen::MatrixXi& F,
                                                         const std::vector<char>& degenerate) {
  const std::vector<Point> points = to_points(V);
  std::vector<Box> boxes;
  boxes.reserve(static_cast<std::size_t>(F.rows()));
  for (int f = 0; f < F.rows(); ++f) {
    if (degenerate[f]) continue;
    boxes.emplace_back(points[F(f, 0)].bbox() + points[F(f, 1)].bbox() + points[F(f, 2)].bbox(), f);
  }
  std::vector<const Box*> box_ptrs;
  box_ptrs.reserve(boxes.size());
  for (const Box& b : boxes) box_ptrs.push_back(&b);

  const SoupPairTest intersects(points, F);
  tbb::concurrent_vector<std::pair<int, int>> found;
  auto callback = [&](const Box* a, const Box* b) {
    if (intersects(a->info(), b->info())) found.push_back(std::minmax(a->info(), b->info()));
  };
  CGAL::box_self_intersection_d<CGAL::Parallel_if_available_tag>(box_ptrs.begin(), box_ptrs.end(),
                                                                 callback, k_box_cutoff);
  return {found.begin(), found.end()};
}

// PMP on a Surface_mesh whose face i is row i of F; false if the soup is not a halfedge mesh.
bool mesh_self_intersections(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                             std::vector<std::pair<int, int>>& pairs) {
  Mesh mesh;
  mesh.reserve(static_cast<Mesh::size_type>(V.rows()), static_cast<Mesh::size_type>(3 * F.rows()),
               static_cast<Mesh::size_type>(F.rows()));
  for (Eigen::Index i = 0; i < V.rows(); ++i) mesh.add_vertex(Point(V(i, 0), V(i, 1), V(i, 2)));
  for (int f = 0; f < F.rows(); ++f) {
    const Mesh::Face_index added = mesh.add_face(
        Mesh::Vertex_index(F(f, 0)), Mesh::Vertex_index(F(f, 1)), Mesh::Vertex_index(F(f, 2)));
    if (added == Mesh::null_face() || static_cast<int>(added.idx()) != f) return false;
  }
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> mesh_pairs;
  CGAL::Polygon_mesh_processing::self_intersections<CGAL::Parallel_if_available_tag>(
      mesh, std::back_inserter(mesh_pairs));
  pairs.clear();
  for (const auto& [a, b] : mesh_pairs) {
    if (a == b) continue;  // PMP's marker of a degenerate face
    pairs.push_back(std::minmax(static_cast<int>(a.idx()), static_cast<int>(b.idx())));
  }
  return true;
}

}  // namespace

std::vector<char> exactly_degenerate_faces(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  std::vector<char> degenerate(static_cast<std::size_t>(F.rows()), 0);
  for (int f = 0; f < F.rows(); ++f) {
    const int a = F(f, 0), b = F(f, 1), c = F(f, 2);
    if (a == b || b == c || c == a) {
      degenerate[f] = 1;
      continue;
    }
    const Point p(V(a, 0), V(a, 1), V(a, 2)), q(V(b, 0), V(b, 1), V(b, 2)),
        r(V(c, 0), V(c, 1), V(c, 2));
    degenerate[f] = CGAL::collinear(p, q, r) ? 1 : 0;
  }
  return degenerate;
}

SelfIntersectionResult find_self_intersections(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                               const std::vector<char>& degenerate,
                                               bool is_oriented_manifold,
                                               SelfIntersectionEngine engine) {
  CF_VERIFY(degenerate.size() == static_cast<std::size_t>(F.rows()),
            "one degenerate flag per face");
  SelfIntersectionResult result;
  if (engine == SelfIntersectionEngine::mesh ||
      (engine == SelfIntersectionEngine::automatic && is_oriented_manifold)) {
    result.used_mesh_api = mesh_self_intersections(V, F, result.pairs);
    CF_VERIFY(result.used_mesh_api || engine != SelfIntersectionEngine::mesh,
              "the triangles do not form a CGAL halfedge mesh (non-manifold or misoriented)");
  }
  if (!result.used_mesh_api) result.pairs = soup_self_intersections(V, F, degenerate);
  std::sort(result.pairs.begin(), result.pairs.end());
  return result;
}

int count_self_intersecting_pairs(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  const auto degenerate = exactly_degenerate_faces(V, F);
  return int(find_self_intersections(V, F, degenerate, true).pairs.size());
}

int intersecting_pairs_between(const Eigen::MatrixXd& Va, const Eigen::MatrixXi& Fa,
                               const Eigen::MatrixXd& Vb, const Eigen::MatrixXi& Fb) {
  Eigen::MatrixXd V(Va.rows() + Vb.rows(), 3);
  V << Va, Vb;
  Eigen::MatrixXi F(Fa.rows() + Fb.rows(), 3);
  F << Fa, (Fb.array() + int(Va.rows())).matrix();
  const auto degenerate = exactly_degenerate_faces(V, F);
  int n = 0;
  for (const auto& [f, g] :
       find_self_intersections(V, F, degenerate, false, SelfIntersectionEngine::soup).pairs)
    n += (f < Fa.rows()) != (g < Fa.rows());
  return n;
}

}  // namespace curvefem::check
