#include "meshing/shell/shell_intersection.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace curvefem::meshing::shell {

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Triangle = K::Triangle_3;
using Segment = K::Segment_3;
using Primitive = CGAL::AABB_triangle_primitive<K, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

Point pt(const Eigen::Vector3d& p) { return Point(p.x(), p.y(), p.z()); }
}  // namespace

struct InputSurfaceIndex::Impl {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  std::vector<Triangle> triangles;
  Tree tree;
  int id(const std::vector<Triangle>::const_iterator& it) const {
    return int(it - triangles.cbegin());
  }
};

InputSurfaceIndex::InputSurfaceIndex(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F)
    : m_impl(std::make_unique<Impl>()) {
  m_impl->V = V;
  m_impl->F = F;
  m_impl->triangles.reserve(F.rows());
  for (int f = 0; f < F.rows(); ++f)
    m_impl->triangles.emplace_back(pt(V.row(F(f, 0))), pt(V.row(F(f, 1))), pt(V.row(F(f, 2))));
  m_impl->tree.insert(m_impl->triangles.cbegin(), m_impl->triangles.cend());
  m_impl->tree.build();
  m_impl->tree.accelerate_distance_queries();
}

InputSurfaceIndex::~InputSurfaceIndex() = default;
const Eigen::MatrixXd& InputSurfaceIndex::V() const { return m_impl->V; }
const Eigen::MatrixXi& InputSurfaceIndex::F() const { return m_impl->F; }

double InputSurfaceIndex::ray_distance(const Eigen::Vector3d& origin,
                                       const Eigen::Vector3d& direction,
                                       const std::vector<int>& ignore) const {
  const K::Ray_3 ray(pt(origin), K::Vector_3(direction.x(), direction.y(), direction.z()));
  auto skip = [&](const std::vector<Triangle>::const_iterator& it) {
    return std::find(ignore.begin(), ignore.end(), m_impl->id(it)) != ignore.end();
  };
  const auto hit = m_impl->tree.first_intersection(ray, skip);
  if (!hit) return std::numeric_limits<double>::infinity();
  if (const Point* p = boost::get<Point>(&hit->first))
    return std::sqrt(CGAL::to_double(CGAL::squared_distance(*p, ray.source())));
  if (const Segment* s = boost::get<Segment>(&hit->first))
    return std::sqrt(std::min(CGAL::to_double(CGAL::squared_distance(s->source(), ray.source())),
                              CGAL::to_double(CGAL::squared_distance(s->target(), ray.source()))));
  return 0.0;
}

bool InputSurfaceIndex::triangle_intersects(const std::array<Eigen::Vector3d, 3>& c,
                                            const std::array<bool, 3>& singular,
                                            const Eigen::Vector3i& corner_ids) const {
  const Triangle tri(pt(c[0]), pt(c[1]), pt(c[2]));
  if (tri.is_degenerate()) return true;  // never accept a flat base/top triangle
  std::vector<std::vector<Triangle>::const_iterator> hits;
  m_impl->tree.all_intersected_primitives(tri, std::back_inserter(hits));
  for (const auto& it : hits) {
    const int f = m_impl->id(it);
    int pinch = -1;  // local corner of the triangle that is a singular input vertex of face f
    for (int k = 0; k < 3; ++k)
      if (singular[k])
        for (int j = 0; j < 3; ++j)
          if (m_impl->F(f, j) == corner_ids[k]) pinch = k;
    if (pinch < 0) return true;
    // Contact at the shared point only: neither opposite edge touches the other triangle.
    const Segment mine(pt(c[(pinch + 1) % 3]), pt(c[(pinch + 2) % 3]));
    int shared = 0;
    while (m_impl->F(f, shared) != corner_ids[pinch]) ++shared;
    const Segment theirs(pt(m_impl->V.row(m_impl->F(f, (shared + 1) % 3))),
                         pt(m_impl->V.row(m_impl->F(f, (shared + 2) % 3))));
    if (CGAL::do_intersect(mine, *it) || CGAL::do_intersect(theirs, tri)) return true;
    if (CGAL::coplanar(tri[0], tri[1], tri[2], (*it)[0]) &&
        CGAL::coplanar(tri[0], tri[1], tri[2], (*it)[1]) &&
        CGAL::coplanar(tri[0], tri[1], tri[2], (*it)[2]))
      return true;  // coplanar fans: conservatively an intersection
  }
  return false;
}

std::vector<int> InputSurfaceIndex::faces_touching_tet(
    const std::array<Eigen::Vector3d, 4>& t) const {
  const K::Tetrahedron_3 tet(pt(t[0]), pt(t[1]), pt(t[2]), pt(t[3]));
  std::vector<std::vector<Triangle>::const_iterator> hits;
  m_impl->tree.all_intersected_primitives(tet.bbox(), std::back_inserter(hits));
  std::vector<int> out;
  for (const auto& it : hits)
    if (CGAL::do_intersect(*it, tet)) out.push_back(m_impl->id(it));
  return out;
}

std::vector<int> InputSurfaceIndex::faces_in_box(const Eigen::Vector3d& lo,
                                                 const Eigen::Vector3d& hi) const {
  const CGAL::Bbox_3 box(lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z());
  std::vector<std::vector<Triangle>::const_iterator> hits;
  m_impl->tree.all_intersected_primitives(box, std::back_inserter(hits));
  std::vector<int> out;
  out.reserve(hits.size());
  for (const auto& it : hits) out.push_back(m_impl->id(it));
  return out;
}

bool InputSurfaceIndex::face_touches_tet(int f, const std::array<Eigen::Vector3d, 4>& t) const {
  const K::Tetrahedron_3 tet(pt(t[0]), pt(t[1]), pt(t[2]), pt(t[3]));
  return CGAL::do_intersect(m_impl->triangles[std::size_t(f)], tet);
}

int InputSurfaceIndex::closest_face(const Eigen::Vector3d& p, Eigen::Vector3d& closest) const {
  const auto [q, it] = m_impl->tree.closest_point_and_primitive(pt(p));
  closest = Eigen::Vector3d(q.x(), q.y(), q.z());
  return m_impl->id(it);
}

int InputSurfaceIndex::segment_hit(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                   Eigen::Vector3d& bary) const {
  const Segment seg(pt(a), pt(b));
  std::vector<std::vector<Triangle>::const_iterator> hits;
  m_impl->tree.all_intersected_primitives(seg, std::back_inserter(hits));
  int best = -1;
  double best_t = std::numeric_limits<double>::infinity();
  for (const auto& it : hits) {
    const int f = m_impl->id(it);
    const Eigen::Vector3d p0 = m_impl->V.row(m_impl->F(f, 0)), p1 = m_impl->V.row(m_impl->F(f, 1)),
                          p2 = m_impl->V.row(m_impl->F(f, 2));
    const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
    const double denom = n.dot(b - a);
    double t = 0.0;
    if (std::abs(denom) > 0) t = std::clamp(n.dot(p0 - a) / denom, 0.0, 1.0);
    if (t >= best_t) continue;
    const Eigen::Vector3d x = a + t * (b - a);
    const double area = n.squaredNorm();
    Eigen::Vector3d w;
    w[1] = n.dot((x - p0).cross(p2 - p0)) / area;
    w[2] = n.dot((p1 - p0).cross(x - p0)) / area;
    w[0] = 1.0 - w[1] - w[2];
    best = f;
    best_t = t;
    bary = w;
  }
  return best;
}

}  // namespace curvefem::meshing::shell
