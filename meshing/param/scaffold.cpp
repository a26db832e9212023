// Scaffold triangulation with CGAL's constrained Delaunay triangulation (the only CGAL user of the
// optimizer; the independent checks in uv_check.cpp use CGAL predicates separately).
#include "meshing/param/scaffold.hpp"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <cmath>
#include <deque>

#include "meshing/core/error.hpp"

namespace curvefem::meshing::param {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
using Fbb = CGAL::Triangulation_face_base_with_info_2<int, K>;
using Fb = CGAL::Constrained_triangulation_face_base_2<K, Fbb>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using Cdt =
    CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::No_constraint_intersection_tag>;
using Point = K::Point_2;

// Nesting level of every finite face: 0 outside the box, +1 across each constraint.
void mark_levels(Cdt& cdt) {
  for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->info() = -1;
  std::deque<std::pair<Cdt::Face_handle, int>> border{{cdt.infinite_face(), 0}};
  while (!border.empty()) {
    auto [start, level] = border.front();
    border.pop_front();
    if (start->info() != -1) continue;
    std::deque<Cdt::Face_handle> queue{start};
    start->info() = level;
    while (!queue.empty()) {
      Cdt::Face_handle f = queue.front();
      queue.pop_front();
      for (int i = 0; i < 3; ++i) {
        Cdt::Face_handle n = f->neighbor(i);
        if (n->info() != -1) continue;
        if (cdt.is_constrained({f, i})) {
          border.emplace_back(n, level + 1);
        } else {
          n->info() = level;
          queue.push_back(n);
        }
      }
    }
  }
}

}  // namespace

Scaffold build_scaffold(const Eigen::MatrixXd& uv, const std::vector<std::vector<int>>& loops,
                        const ScaffoldOptions& options) {
  const int nu = int(uv.rows());
  std::size_t nb = 0;
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(INFINITY), hi = -lo;
  for (const auto& loop : loops) {
    nb += loop.size();
    for (int u : loop) {
      lo = lo.cwiseMin(uv.row(u).transpose());
      hi = hi.cwiseMax(uv.row(u).transpose());
    }
  }
  const Eigen::Vector2d center = 0.5 * (lo + hi);
  const double half = 0.5 * options.box_scale * std::max((hi - lo).maxCoeff(), 1e-300);
  Scaffold s;
  s.box_lo = center - Eigen::Vector2d::Constant(half);
  s.box_hi = center + Eigen::Vector2d::Constant(half);
  const int m = options.box_segments > 0 ? options.box_segments
                                         : std::max(4, int(std::ceil(0.5 * std::sqrt(double(nb)))));
  std::vector<Eigen::Vector2d> extra;
  const Eigen::Vector2d corner[4] = {
      s.box_lo, {s.box_hi.x(), s.box_lo.y()}, s.box_hi, {s.box_lo.x(), s.box_hi.y()}};
  for (int side = 0; side < 4; ++side)
    for (int i = 0; i < m; ++i)
      extra.push_back(corner[side] + (corner[(side + 1) % 4] - corner[side]) * (double(i) / m));
  s.num_fixed = int(extra.size());

  Cdt cdt;
  std::vector<Cdt::Vertex_handle> handle(nu);
  Cdt::Face_handle hint;
  auto insert = [&](const Point& p, int id) {
    const auto before = cdt.number_of_vertices();
    Cdt::Vertex_handle v = cdt.insert(p, hint);
    if (cdt.number_of_vertices() == before)
      throw MeshingError("param: scaffold: two boundary vertices at the same UV point (" +
                         std::to_string(p.x()) + ", " + std::to_string(p.y()) + ")");
    v->info() = id;
    hint = v->face();
    return v;
  };
  for (int i = 0; i < s.num_fixed; ++i) insert({extra[i].x(), extra[i].y()}, nu + i);
  for (const auto& loop : loops)
    for (int u : loop) handle[u] = insert({uv(u, 0), uv(u, 1)}, u);
  std::vector<Cdt::Vertex_handle> box(s.num_fixed);
  for (auto v = cdt.finite_vertices_begin(); v != cdt.finite_vertices_end(); ++v)
    if (v->info() >= nu) box[v->info() - nu] = v;
  try {
    for (int i = 0; i < s.num_fixed; ++i) cdt.insert_constraint(box[i], box[(i + 1) % s.num_fixed]);
    for (const auto& loop : loops)
      for (std::size_t i = 0; i < loop.size(); ++i)
        cdt.insert_constraint(handle[loop[i]], handle[loop[(i + 1) % loop.size()]]);
  } catch (const Cdt::Intersection_of_constraints_exception&) {
    throw MeshingError(
        "param: scaffold: chart boundary edges intersect (the map is not bijective)");
  }
  if (cdt.number_of_vertices() != std::size_t(s.num_fixed) + nb)
    throw MeshingError("param: scaffold: a boundary vertex lies on another boundary edge");
  for (const auto& loop : loops)
    for (std::size_t i = 0; i < loop.size(); ++i)
      if (!cdt.is_edge(handle[loop[i]], handle[loop[(i + 1) % loop.size()]]))
        throw MeshingError("param: scaffold: a chart boundary edge is split by another vertex");

  mark_levels(cdt);
  double target = options.refine_area;
  if (target <=
      0) {  // auto: the mean area of a scaffold triangle if there were ~4 per boundary vertex
    target = (2 * half) * (2 * half) / (4.0 * double(std::max<std::size_t>(nb, 16)));
  }
  for (int round = 0; round < options.refine_rounds; ++round) {
    std::vector<Point> centroids;
    for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
      if (f->info() != 1) continue;
      const Point &a = f->vertex(0)->point(), &b = f->vertex(1)->point(),
                  &c = f->vertex(2)->point();
      if (CGAL::area(a, b, c) > target) centroids.push_back(CGAL::centroid(a, b, c));
    }
    if (centroids.empty()) break;
    // Keep only centroids strictly inside a scaffold face (exact test, before any insertion: the
    // scaffold region does not change by inserting inside it): a rounded centroid of a sliver
    // must not land in a chart or on a boundary edge.
    std::vector<Point> inside;
    for (const Point& p : centroids) {
      Cdt::Locate_type type;
      int li;
      Cdt::Face_handle where = cdt.locate(p, type, li);
      if (type == Cdt::FACE && where->info() == 1) inside.push_back(p);
    }
    for (const Point& p : inside) {
      const auto before = cdt.number_of_vertices();
      Cdt::Vertex_handle v = cdt.insert(p);
      if (cdt.number_of_vertices() > before) {
        v->info() = nu + int(extra.size());
        extra.emplace_back(p.x(), p.y());
      }
    }
    mark_levels(cdt);
  }
  s.V.resize(Eigen::Index(extra.size()), 2);
  for (std::size_t i = 0; i < extra.size(); ++i) s.V.row(Eigen::Index(i)) = extra[i].transpose();
  std::vector<Eigen::Vector3i> faces;
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f)
    if (f->info() == 1)
      faces.emplace_back(f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info());
  s.F.resize(Eigen::Index(faces.size()), 3);
  for (std::size_t i = 0; i < faces.size(); ++i) s.F.row(Eigen::Index(i)) = faces[i].transpose();
  return s;
}

}  // namespace curvefem::meshing::param
