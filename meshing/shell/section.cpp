#include "meshing/shell/section.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <map>
#include <numeric>
#include <vector>

#include "meshing/shell/shell_geometry.hpp"
#include "meshing/shell/shell_intersection.hpp"

namespace curvefem::meshing::shell {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using V3 = Eigen::Vector3d;
K::Point_3 pt(const V3& p) { return K::Point_3(p.x(), p.y(), p.z()); }

// The pieces of one prism the local tests read.
struct PrismParts {
  std::vector<std::array<V3, 4>> tets;          // non-degenerate canonical split tets
  std::vector<std::pair<V3, V3>> half_pillars;  // (from, to) of the non-singular pillars
  std::array<V3, 3> base, top;                  // face order
  Eigen::Vector3i ids;                          // shell vertex ids of the corners
  std::array<bool, 3> singular;
  Eigen::AlignedBox3d box;
};

PrismParts prism_parts(const Shell& shell, int f) {
  auto row = [](const Eigen::MatrixXd& M, int v) { return V3(M.row(v)); };
  const Eigen::Vector3i F = shell.F.row(f);
  const int rot = min_rotation(F);
  PrismParts p;
  for (int half = 0; half < 2; ++half)
    for (const auto& tet : split_tets(is_type_a(F))) {
      std::array<V3, 4> c;
      for (int k = 0; k < 4; ++k) {
        const int v = F[(rot + tet[k] % 3) % 3];
        const Eigen::MatrixXd& M =
            tet[k] < 3 ? (half == 0 ? shell.base : shell.mid) : (half == 0 ? shell.mid : shell.top);
        c[k] = row(M, v);
      }
      if (CGAL::orientation(pt(c[0]), pt(c[1]), pt(c[2]), pt(c[3])) == CGAL::COPLANAR)
        continue;  // pinched
      p.tets.push_back(c);
    }
  Eigen::AlignedBox3d& box = p.box;
  for (int k = 0; k < 3; ++k) {
    const int v = F[k];
    p.base[k] = row(shell.base, v);
    p.top[k] = row(shell.top, v);
    p.ids[k] = v;
    p.singular[k] = shell.singular[v] != 0;
    box.extend(p.base[k]).extend(row(shell.mid, v)).extend(p.top[k]);
    if (p.singular[k]) continue;
    p.half_pillars.emplace_back(row(shell.base, v), row(shell.mid, v));
    p.half_pillars.emplace_back(row(shell.mid, v), row(shell.top, v));
  }
  return p;
}

// Closed, edge-manifold, consistently oriented: every undirected edge is used exactly twice, once
// in each direction.
bool closed_oriented_manifold(const SurfaceMesh& m) {
  if (m.num_faces() == 0) return false;
  std::vector<std::pair<int, int>> directed;
  directed.reserve(3 * std::size_t(m.num_faces()));
  for (int f = 0; f < m.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = m.F(f, k), b = m.F(f, (k + 1) % 3);
      if (a < 0 || b < 0 || a >= m.num_vertices() || b >= m.num_vertices() || a == b) return false;
      directed.emplace_back(a, b);
    }
  std::sort(directed.begin(), directed.end());
  if (std::adjacent_find(directed.begin(), directed.end()) != directed.end()) return false;
  for (const auto& [a, b] : directed)
    if (!std::binary_search(directed.begin(), directed.end(), std::make_pair(b, a))) return false;
  return true;
}

// One face per edge-connected component of the middle surface.
std::vector<int> component_representatives(const Eigen::MatrixXi& F) {
  std::vector<int> parent(F.rows());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::map<std::pair<int, int>, int> first_face;
  for (int f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      const auto [it, fresh] =
          first_face.emplace(std::make_pair(std::min(a, b), std::max(a, b)), f);
      if (!fresh) parent[find(f)] = find(it->second);
    }
  std::vector<int> reps;
  for (int f = 0; f < F.rows(); ++f)
    if (find(f) == f) reps.push_back(f);
  return reps;
}

}  // namespace

struct SectionChecker::Impl {
  const ShellProjection& projection;
  const Shell& shell;
  std::vector<PrismParts> prisms;
  std::map<std::array<double, 3>, int> pinches;  // singular vertices by middle position

  explicit Impl(const ShellProjection& p) : projection(p), shell(p.shell()) {}

  // Prisms that can meet triangle t: bounding box meeting t's, and not on one side of t's plane.
  // The plane test is conservative: a box is dropped only when its distance to the plane exceeds
  // its reach by far more than the rounding error of the normal (|δn| ≤ 4ε|e1||e2|) and of the
  // dot products, hence the 1e-9 |e1||e2| (|c| + 2|r|) margin; a degenerate t drops nothing.
  std::vector<int> candidates(const SectionChecker::Triangle& t) const {
    const V3 lo = t[0].cwiseMin(t[1]).cwiseMin(t[2]), hi = t[0].cwiseMax(t[1]).cwiseMax(t[2]);
    std::vector<int> out = projection.prisms_in_box(lo, hi);
    const V3 e1 = t[1] - t[0], e2 = t[2] - t[0], n = e1.cross(e2);
    const double scale = 1e-9 * e1.norm() * e2.norm();
    std::erase_if(out, [&](int f) {
      const Eigen::AlignedBox3d& box = prisms[std::size_t(f)].box;
      const V3 c = box.center() - t[0], r = 0.5 * box.sizes();
      const double reach = n.cwiseAbs().dot(r);
      return std::abs(n.dot(c)) > reach + scale * (c.norm() + 2 * r.norm());
    });
    return out;
  }
  bool separated(const SectionChecker::Triangle& t, const std::array<int, 3>& pinch,
                 const std::vector<int>& prisms_near) const {
    if (CGAL::collinear(pt(t[0]), pt(t[1]), pt(t[2]))) return false;  // never a section face
    for (int f : prisms_near) {
      const PrismParts& p = prisms[std::size_t(f)];
      int kt = -1, kp = -1;  // a corner of t on a pinch point that is a corner of this prism
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k)
          if (pinch[j] >= 0 && p.singular[k] && p.ids[k] == pinch[j]) {
            kt = j;
            kp = k;
          }
      if (triangles_meet_beyond_pinch(t, kt, p.base, kp) ||
          triangles_meet_beyond_pinch(t, kt, p.top, kp))
        return false;
    }
    return true;
  }
  bool transversal(const SectionChecker::Triangle& t, const std::vector<int>& prisms_near) const {
    for (int f : prisms_near) {
      const PrismParts& p = prisms[std::size_t(f)];
      bool seen = true;
      for (const auto& [from, to] : p.half_pillars)
        if (normal_dot_sign(t, from, to) <= 0) {
          seen = false;
          break;
        }
      if (seen) continue;
      for (const auto& tet : p.tets)
        if (triangle_section_contact(t, tet)) return false;
    }
    return true;
  }

  // Crossings of the fiber of (face, u, v) with the surface in `index`, or -1 when the fiber is
  // not generic for it (meets an edge or vertex of it, runs in a face's plane, or an end of the
  // fiber lies on it). A fiber corner on a face (the middle triangle for the middle surface) is
  // a crossing of the segment starting there: segments are half-open [a, b).
  int fiber_crossings(const InputSurfaceIndex& index, int face, double u, double v) const {
    const auto fiber = projection.fiber(face, u, v);
    const int last = int(fiber.size()) - 1;
    int count = 0;
    for (int s = 0; s < last; ++s) {
      const V3 &a = fiber[s], &b = fiber[s + 1];
      if (a == b) continue;
      const K::Point_3 pa = pt(a), pb = pt(b);
      for (int t : index.faces_in_box(a.cwiseMin(b), a.cwiseMax(b))) {
        const auto tri = index.face_triangle(t);
        const K::Point_3 q[3] = {pt(tri[0]), pt(tri[1]), pt(tri[2])};
        const int oa = int(CGAL::orientation(q[0], q[1], q[2], pa)),
                  ob = int(CGAL::orientation(q[0], q[1], q[2], pb));
        if (oa * ob > 0) continue;
        const bool meets =
            CGAL::do_intersect(K::Segment_3(pa, pb), K::Triangle_3(q[0], q[1], q[2]));
        if (!meets) continue;
        if ((oa == 0 && ob == 0) || (oa == 0 && s == 0) || (ob == 0 && s + 1 == last)) return -1;
        if (ob == 0) continue;  // at b: counted by the segment starting there
        // The line through a and b crosses the plane inside the triangle, on an edge or vertex?
        int pos = 0, neg = 0;
        for (int i = 0; i < 3; ++i) {
          const int o = int(CGAL::orientation(pa, pb, q[i], q[(i + 1) % 3]));
          pos += o > 0;
          neg += o < 0;
        }
        if (pos != 3 && neg != 3) return -1;
        ++count;
      }
    }
    return count;
  }
};

SectionChecker::SectionChecker(const ShellProjection& projection)
    : m_impl(std::make_unique<Impl>(projection)) {
  Impl& m = *m_impl;
  const Shell& s = m.shell;
  const int nf = int(s.F.rows());
  m.prisms.reserve(std::size_t(nf));
  for (int f = 0; f < nf; ++f) m.prisms.push_back(prism_parts(s, f));
  for (int v = 0; v < int(s.mid.rows()); ++v)
    if (s.singular[v]) m.pinches[{s.mid(v, 0), s.mid(v, 1), s.mid(v, 2)}] = v;
}

SectionChecker::~SectionChecker() = default;

int SectionChecker::pinch_vertex(const Eigen::Vector3d& p) const {
  const auto it = m_impl->pinches.find({p.x(), p.y(), p.z()});
  return it == m_impl->pinches.end() ? -1 : it->second;
}

bool SectionChecker::separated(const Triangle& t, const std::array<int, 3>& pinch) const {
  return m_impl->separated(t, pinch, m_impl->candidates(t));
}

bool SectionChecker::transversal(const Triangle& t) const {
  return m_impl->transversal(t, m_impl->candidates(t));
}

bool SectionChecker::triangle_ok(const Triangle& t, const std::array<int, 3>& pinch) const {
  const std::vector<int> near = m_impl->candidates(t);
  return m_impl->separated(t, pinch, near) && m_impl->transversal(t, near);
}

SectionCheck SectionChecker::check(const SurfaceMesh& m) const {
  const auto t0 = std::chrono::steady_clock::now();
  SectionCheck r;
  r.manifold = closed_oriented_manifold(m);
  std::vector<int> pinch(std::size_t(m.num_vertices()), -1);
  for (int v = 0; v < m.num_vertices(); ++v) {
    const V3 x = m.V.row(v);
    if (!m_impl->projection.locate(x)) ++r.vertices_outside;
    pinch[std::size_t(v)] = pinch_vertex(x);
  }
  for (int f = 0; f < m.num_faces(); ++f) {
    Triangle t;
    std::array<int, 3> p;
    for (int k = 0; k < 3; ++k) {
      t[k] = m.V.row(m.F(f, k));
      p[k] = pinch[std::size_t(m.F(f, k))];
    }
    const std::vector<int> near = m_impl->candidates(t);
    if (!m_impl->separated(t, p, near)) ++r.faces_crossing_cage;
    if (!m_impl->transversal(t, near)) ++r.faces_not_transversal;
  }
  if (m.num_faces() > 0) {
    // (e): a few generic points per component, until one gives a generic fiber.
    const InputSurfaceIndex index(m.V, m.F);
    static constexpr double k_uv[4][2] = {
        {0.2887, 0.3231}, {0.4121, 0.1733}, {0.1559, 0.5417}, {0.6173, 0.2291}};
    for (int face : component_representatives(m_impl->shell.F)) {
      int crossings = -1;
      for (const auto& uv : k_uv) {
        crossings = m_impl->fiber_crossings(index, face, uv[0], uv[1]);
        if (crossings >= 0) break;
      }
      if (crossings != 1) ++r.degree_failures;
    }
  } else {
    r.degree_failures = int(component_representatives(m_impl->shell.F).size());
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

SectionCheck check_section(const ShellProjection& projection, const SurfaceMesh& m) {
  return SectionChecker(projection).check(m);
}

}  // namespace curvefem::meshing::shell
