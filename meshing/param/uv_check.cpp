// Exact checks of a UV map with CGAL predicates: flips, boundary overlaps, nested components.
#include "meshing/param/uv_check.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <numeric>
#include <unordered_map>
#include <vector>

namespace curvefem::meshing::param {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_2;
using Segment = K::Segment_2;

int find(std::vector<int>& up, int a) {
  while (up[a] != a) a = up[a] = up[up[a]];
  return a;
}

// Do boundary edges (a, b) and (c, d) meet other than at a shared endpoint?
bool edges_overlap(const std::vector<Point>& P, int a, int b, int c, int d) {
  const int shared = (a == c) + (a == d) + (b == c) + (b == d);
  if (shared == 0) return CGAL::do_intersect(Segment(P[a], P[b]), Segment(P[c], P[d]));
  if (shared == 2) return true;  // the same edge twice
  const int s = (a == c || a == d) ? a : b;
  const int x = (s == a) ? b : a, y = (s == c) ? d : c;
  // Two segments from s meet only at s unless they are collinear and point the same way.
  return CGAL::orientation(P[s], P[x], P[y]) == CGAL::COLLINEAR &&
         !CGAL::collinear_are_strictly_ordered_along_line(P[x], P[s], P[y]);
}

}  // namespace

UvCheck check_uv_map(const Eigen::MatrixXd& uv, const Eigen::MatrixXi& F) {
  UvCheck r;
  const int nf = int(F.rows()), nu = int(uv.rows());
  std::vector<Point> P(nu);
  for (int u = 0; u < nu; ++u) P[u] = Point(uv(u, 0), uv(u, 1));
  for (int f = 0; f < nf; ++f) {
    if (CGAL::orientation(P[F(f, 0)], P[F(f, 1)], P[F(f, 2)]) != CGAL::LEFT_TURN) ++r.flips;
    const Eigen::Vector2d e1 = uv.row(F(f, 1)) - uv.row(F(f, 0));
    const Eigen::Vector2d e2 = uv.row(F(f, 2)) - uv.row(F(f, 0));
    r.triangle_area += 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
  }
  // Boundary half-edges: directed edges whose reverse is absent.
  std::map<std::pair<int, int>, int> count;
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) ++count[{F(f, k), F(f, (k + 1) % 3)}];
  std::vector<std::array<int, 2>> bnd;
  for (const auto& [e, n] : count)
    if (!count.count({e.second, e.first})) bnd.push_back({e.first, e.second});
  r.boundary_edges = (long long)bnd.size();
  for (const auto& e : bnd)
    r.boundary_area += 0.5 * (uv(e[0], 0) * uv(e[1], 1) - uv(e[1], 0) * uv(e[0], 1));
  r.area_rel_error =
      std::abs(r.triangle_area - r.boundary_area) / std::max(std::abs(r.triangle_area), 1e-300);

  // Broad phase: uniform grid with cells about twice the mean boundary edge length.
  if (!bnd.empty()) {
    Eigen::Vector2d lo = uv.colwise().minCoeff().transpose(),
                    hi = uv.colwise().maxCoeff().transpose();
    double mean = 0;
    for (const auto& e : bnd) mean += (uv.row(e[0]) - uv.row(e[1])).norm();
    mean /= double(bnd.size());
    const double extent = std::max((hi - lo).maxCoeff(), 1e-300);
    const double cell = std::max(2 * mean, extent / 2048);
    const long long n = std::max(1LL, (long long)std::ceil(extent / cell) + 1);
    std::unordered_map<long long, std::vector<int>> grid;
    auto cells_of = [&](int i, auto&& visit) {
      const auto& e = bnd[i];
      const double x0 = std::min(uv(e[0], 0), uv(e[1], 0)), x1 = std::max(uv(e[0], 0), uv(e[1], 0));
      const double y0 = std::min(uv(e[0], 1), uv(e[1], 1)), y1 = std::max(uv(e[0], 1), uv(e[1], 1));
      // Cells are padded by one on each side so that rounding of the cell index cannot miss.
      const long long i0 = std::max(0LL, (long long)((x0 - lo.x()) / cell) - 1);
      const long long i1 = std::min(n - 1, (long long)((x1 - lo.x()) / cell) + 1);
      const long long j0 = std::max(0LL, (long long)((y0 - lo.y()) / cell) - 1);
      const long long j1 = std::min(n - 1, (long long)((y1 - lo.y()) / cell) + 1);
      for (long long a = i0; a <= i1; ++a)
        for (long long b = j0; b <= j1; ++b) visit(a * n + b);
    };
    for (int i = 0; i < int(bnd.size()); ++i)
      cells_of(i, [&](long long c) { grid[c].push_back(i); });
    std::vector<std::pair<int, int>> candidates;
    for (const auto& [c, list] : grid)
      for (std::size_t a = 0; a < list.size(); ++a)
        for (std::size_t b = a + 1; b < list.size(); ++b)
          candidates.emplace_back(std::min(list[a], list[b]), std::max(list[a], list[b]));
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    for (const auto& [i, j] : candidates)
      if (edges_overlap(P, bnd[i][0], bnd[i][1], bnd[j][0], bnd[j][1])) ++r.overlaps;
  }

  // Components (faces sharing a UV vertex) and nesting: a boundary vertex of one component inside
  // (or on) a face of another, with bounding boxes as the broad phase.
  std::vector<int> up(nu);
  std::iota(up.begin(), up.end(), 0);
  for (int f = 0; f < nf; ++f)
    for (int k = 1; k < 3; ++k) {
      const int a = find(up, F(f, 0)), b = find(up, F(f, k));
      if (a != b) up[std::max(a, b)] = std::min(a, b);
    }
  std::map<int, int> comp_of_root;
  std::vector<int> comp_face(nf);
  for (int f = 0; f < nf; ++f) {
    const int root = find(up, F(f, 0));
    auto it = comp_of_root.emplace(root, int(comp_of_root.size())).first;
    comp_face[f] = it->second;
  }
  r.components = int(comp_of_root.size());
  if (r.components > 1) {
    const int nc = r.components;
    std::vector<Eigen::Vector2d> clo(nc, Eigen::Vector2d::Constant(INFINITY)), chi(nc, -clo[0]);
    std::vector<int> probe(nc, -1);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        clo[comp_face[f]] = clo[comp_face[f]].cwiseMin(uv.row(F(f, k)).transpose());
        chi[comp_face[f]] = chi[comp_face[f]].cwiseMax(uv.row(F(f, k)).transpose());
      }
    // The probe of a component: any of its boundary vertices.
    for (const auto& e : bnd) {
      const int c = comp_of_root.at(find(up, e[0]));
      if (probe[c] < 0) probe[c] = e[0];
    }
    for (int f = 0; f < nf; ++f) {
      const int a = comp_face[f];
      for (int b = 0; b < nc; ++b) {
        if (b == a || probe[b] < 0) continue;
        const Eigen::Vector2d q = uv.row(probe[b]).transpose();
        if ((q.array() < clo[a].array()).any() || (q.array() > chi[a].array()).any()) continue;
        const Point& p0 = P[F(f, 0)];
        const Point& p1 = P[F(f, 1)];
        const Point& p2 = P[F(f, 2)];
        const Point& x = P[probe[b]];
        if (CGAL::orientation(p0, p1, x) != CGAL::RIGHT_TURN &&
            CGAL::orientation(p1, p2, x) != CGAL::RIGHT_TURN &&
            CGAL::orientation(p2, p0, x) != CGAL::RIGHT_TURN) {
          ++r.nested_charts;
          probe[b] = -1;  // count each component once
        }
      }
    }
  }
  return r;
}

}  // namespace curvefem::meshing::param
