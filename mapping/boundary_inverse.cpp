#include "mapping/boundary_inverse.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <numeric>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/core/fiber_projection.hpp"
#include "meshing/core/position_key.hpp"

namespace curvefem::mapping {
namespace {

struct Box {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  void add(const Box& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  bool contains(const Eigen::Vector3d& x) const {
    return (x.array() >= lo.array()).all() && (x.array() <= hi.array()).all();
  }
};

struct BvhNode {
  Box box;
  int left = -1, right = -1;  // children (inner node)
  int begin = 0, end = 0;     // item range (leaf, left < 0)
};

/// Projects reference coordinates onto the reference triangle.
void clamp_to_triangle(double& u, double& v) {
  u = std::max(u, 0.0);
  v = std::max(v, 0.0);
  if (u + v > 1) {
    const double d = 0.5 * (u + v - 1);
    u -= d;
    v -= d;
    if (u < 0) v = 1, u = 0;
    if (v < 0) u = 1, v = 0;
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
struct TriangleLocator::Impl {
  const LagrangeMesh* tri = nullptr;
  double tolerance = 0;
  std::vector<Box> boxes;  // node boxes inflated by the bulge margin: the candidate filter
  // Bounds of the Bernstein control points, whose convex hull contains the whole triangle: their
  // box, and their slab along the unit normal of the corner triangle (offsets along `slab_normal`).
  std::vector<Box> hulls;
  std::vector<Eigen::Vector3d> slab_normal;
  std::vector<std::array<double, 2>> slab;
  std::vector<int> items;
  std::vector<BvhNode> nodes;
  // The triangles' nodes, copied face by face (n per face), and the lattice of their order: the
  // Gauss–Newton loop evaluates the map without allocating or locking.
  int order = 1, n = 3;
  std::vector<std::array<int, 4>> lattice;
  std::vector<Eigen::Vector3d> face_nodes;

  int build(int begin, int end) {
    BvhNode n;
    for (int i = begin; i < end; ++i) n.box.add(boxes[items[i]]);
    const int id = int(nodes.size());
    nodes.push_back(n);
    if (end - begin <= 4) {
      nodes[id].begin = begin;
      nodes[id].end = end;
      return id;
    }
    const Eigen::Vector3d ext = n.box.hi - n.box.lo;
    int axis = 0;
    ext.maxCoeff(&axis);
    const int mid = (begin + end) / 2;
    std::nth_element(
        items.begin() + begin, items.begin() + mid, items.begin() + end, [&](int a, int b) {
          return boxes[a].lo[axis] + boxes[a].hi[axis] < boxes[b].lo[axis] + boxes[b].hi[axis];
        });
    const int l = build(begin, mid);
    const int r = build(mid, end);
    nodes[id].left = l;
    nodes[id].right = r;
    return id;
  }

  /// T_f(u, v) and, if J is set, its 3 × 2 Jacobian: the arithmetic of LagrangeMesh::map and
  /// ::jacobian (lagrange_shape_values / _gradients) on the copied nodes.
  Eigen::Vector3d evaluate(int f, double u, double v, Eigen::Matrix<double, 3, 2>* J) const {
    const double lambda[3] = {1.0 - u - v - 0.0, u, v};
    const Eigen::Vector3d* X = face_nodes.data() + static_cast<std::size_t>(f) * n;
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    if (J) J->setZero();
    for (int i = 0; i < n; ++i) {
      double value[3], derivative[3];
      for (int c = 0; c < 3; ++c) {  // Π_{j<a} (kλ − j)/(j + 1) and its derivative
        value[c] = 1.0;
        derivative[c] = 0.0;
        for (int j = 0; j < lattice[i][c]; ++j) {
          const double fj = (order * lambda[c] - j) / (j + 1.0);
          const double dfj = order / (j + 1.0);
          derivative[c] = derivative[c] * fj + value[c] * dfj;
          value[c] *= fj;
        }
      }
      double phi = 1.0;
      for (int c = 0; c < 3; ++c) phi *= value[c];
      x += phi * X[i];
      if (!J) continue;
      double dlambda[3];  // ∂φ/∂λ_c
      for (int c = 0; c < 3; ++c) {
        double p = derivative[c];
        for (int j = 0; j < 3; ++j)
          if (j != c) p *= value[j];
        dlambda[c] = p;
      }
      J->col(0) += X[i] * (dlambda[1] - dlambda[0]);
      J->col(1) += X[i] * (dlambda[2] - dlambda[0]);
    }
    return x;
  }

  /// Gauss–Newton for min |T_f(u, v) − x|², (u, v) kept in the reference triangle, from the
  /// centroid or, with `restarts`, also from the corners and edge midpoints: on a strongly curved
  /// triangle the centroid start can stop at a local minimum on the triangle's border.
  BoundaryPoint invert(int f, const Eigen::Vector3d& x, bool restarts) const {
    BoundaryPoint best = gauss_newton(f, x, 1.0 / 3, 1.0 / 3);
    if (!restarts || best.residual <= tolerance) return best;
    static constexpr double starts[6][2] = {{0, 0}, {1, 0}, {0, 1}, {0.5, 0}, {0.5, 0.5}, {0, 0.5}};
    for (const auto& s : starts) {
      const BoundaryPoint p = gauss_newton(f, x, s[0], s[1]);
      if (p.residual < best.residual) best = p;
    }
    return best;
  }
  BoundaryPoint gauss_newton(int f, const Eigen::Vector3d& x, double u, double v) const {
    Eigen::Vector3d r = evaluate(f, u, v, nullptr) - x;
    Eigen::Matrix<double, 3, 2> J;
    for (int it = 0; it < 40; ++it) {
      evaluate(f, u, v, &J);
      const Eigen::Matrix2d JtJ = J.transpose() * J;
      const Eigen::Vector2d step = JtJ.ldlt().solve(-(J.transpose() * r));
      if (!step.allFinite()) break;
      double nu = u + step[0], nv = v + step[1];
      clamp_to_triangle(nu, nv);
      const double moved = std::abs(nu - u) + std::abs(nv - v);
      u = nu;
      v = nv;
      r = evaluate(f, u, v, nullptr) - x;
      if (moved < 1e-15) break;
    }
    return {f, u, v, r.norm()};
  }

  std::optional<BoundaryPoint> locate(const Eigen::Vector3d& x) const {
    std::optional<BoundaryPoint> best;
    if (nodes.empty()) return best;
    struct Candidate {
      double distance;
      int face;
    };
    thread_local std::vector<int> stack;
    thread_local std::vector<Candidate> candidates;
    stack.assign(1, 0);
    candidates.clear();
    while (!stack.empty()) {
      const BvhNode& n = nodes[stack.back()];
      stack.pop_back();
      if (!n.box.contains(x)) continue;
      if (n.left >= 0) {
        stack.push_back(n.left);
        stack.push_back(n.right);
        continue;
      }
      for (int i = n.begin; i < n.end; ++i) {
        const int f = items[i];
        if (!boxes[f].contains(x)) continue;
        // A lower bound of |T_f(u, v) − x| over the triangle: x's distance to the hull's box or
        // to its normal slab.
        const Eigen::Vector3d gap =
            (hulls[f].lo - x).cwiseMax(x - hulls[f].hi).cwiseMax(Eigen::Vector3d::Zero());
        const double offset = slab_normal[f].dot(x);
        const double slab_gap = std::max({slab[f][0] - offset, offset - slab[f][1], 0.0});
        candidates.push_back({std::max(gap.norm(), slab_gap), f});
      }
    }
    thread_local std::vector<int> ranks;  // BVH order, stable-sorted by distance
    ranks.resize(candidates.size());
    std::iota(ranks.begin(), ranks.end(), 0);
    for (std::size_t i = 1; i < ranks.size(); ++i)  // insertion sort: stable, few candidates
      for (std::size_t j = i;
           j > 0 && candidates[ranks[j]].distance < candidates[ranks[j - 1]].distance; --j)
        std::swap(ranks[j], ranks[j - 1]);
    // Centroid starts first; restarts only if no candidate came within the tolerance (most
    // candidates do not hold x, and restarting on each of them would cost 7x).
    for (const bool restarts : {false, true}) {
      int best_rank = -1;
      for (const int k : ranks) {
        if (best && candidates[k].distance > best->residual) break;
        if (restarts && candidates[k].distance > tolerance) break;
        const BoundaryPoint p = invert(candidates[k].face, x, restarts);
        if (!best || p.residual < best->residual ||
            (p.residual == best->residual && k < best_rank)) {
          best = p;
          best_rank = k;
        }
      }
      if (best && best->residual <= tolerance) return best;
    }
    return std::nullopt;
  }
};

namespace {

/// Lagrange-to-Bernstein matrix of order-k triangles: Bernstein coefficients = M · nodes.
Eigen::MatrixXd lagrange_to_bernstein(const std::vector<std::array<int, 4>>& lattice, int k) {
  const int n = static_cast<int>(lattice.size());
  auto factorial = [](int m) {
    double f = 1;
    for (int i = 2; i <= m; ++i) f *= i;
    return f;
  };
  Eigen::MatrixXd B(n, n);  // B(node, β) = k!/β! λ(node)^β
  for (int i = 0; i < n; ++i)
    for (int b = 0; b < n; ++b) {
      double value = factorial(k);
      for (int c = 0; c < 3; ++c)
        value *= std::pow(double(lattice[i][c]) / k, lattice[b][c]) / factorial(lattice[b][c]);
      B(i, b) = value;
    }
  return B.inverse();
}

}  // namespace

TriangleLocator::TriangleLocator(const LagrangeMesh& triangles, double tolerance_rel)
    : m_impl(std::make_unique<Impl>()) {
  CF_VERIFY(triangles.kind == CellKind::triangle, "TriangleLocator: triangles expected");
  Impl& m = *m_impl;
  m.tri = &triangles;
  const double scale = triangles.num_nodes() > 0 ? bbox_longest_edge(triangles.nodes) : 1.0;
  m.tolerance = tolerance_rel * std::max(scale, 1e-300);
  const int nc = triangles.num_cells();
  m.order = triangles.order;
  m.lattice = lagrange_lattice(CellKind::triangle, triangles.order);
  m.n = static_cast<int>(m.lattice.size());
  CF_VERIFY(nc == 0 || triangles.cells.cols() == m.n,
            "TriangleLocator: cells do not match the order of the triangles");
  const Eigen::MatrixXd to_bernstein = lagrange_to_bernstein(m.lattice, m.order);
  m.face_nodes.resize(static_cast<std::size_t>(nc) * m.n);
  m.boxes.resize(nc);
  m.hulls.resize(nc);
  m.slab_normal.resize(nc);
  m.slab.resize(nc);
  Eigen::MatrixXd X(m.n, 3);
  for (int f = 0; f < nc; ++f) {
    Box b;
    for (int j = 0; j < m.n; ++j) {
      const Eigen::Vector3d p = triangles.nodes.row(triangles.cells(f, j)).transpose();
      m.face_nodes[static_cast<std::size_t>(f) * m.n + j] = p;
      X.row(j) = p.transpose();
      b.lo = b.lo.cwiseMin(p);
      b.hi = b.hi.cwiseMax(p);
    }
    // A curved Lagrange triangle may leave its nodes' hull: inflate by a share of its size.
    const double pad =
        (triangles.order > 1 ? 0.25 : 0.0) * (b.hi - b.lo).maxCoeff() + 2 * m.tolerance;
    b.lo.array() -= pad;
    b.hi.array() += pad;
    m.boxes[f] = b;
    // The triangle lies in the convex hull of its Bernstein control points; the box is widened
    // far beyond the round-off of the conversion.
    const Eigen::MatrixXd control = to_bernstein * X;
    Box h;
    h.lo = control.colwise().minCoeff().transpose();
    h.hi = control.colwise().maxCoeff().transpose();
    const double margin =
        1e-9 * ((h.hi - h.lo).maxCoeff() + h.lo.cwiseAbs().cwiseMax(h.hi.cwiseAbs()).maxCoeff());
    h.lo.array() -= margin;
    h.hi.array() += margin;
    m.hulls[f] = h;
    // Corner nodes are the first three (canonical order). A degenerate corner triangle gets a
    // zero normal: its slab is [−margin, margin] and bounds nothing.
    const Eigen::Vector3d e1 = (X.row(1) - X.row(0)).transpose();
    const Eigen::Vector3d e2 = (X.row(2) - X.row(0)).transpose();
    const Eigen::Vector3d normal = e1.cross(e2).stableNormalized();
    const Eigen::VectorXd offsets = control * normal;
    m.slab_normal[f] = normal;
    m.slab[f] = {offsets.minCoeff() - margin, offsets.maxCoeff() + margin};
  }
  m.items.resize(nc);
  std::iota(m.items.begin(), m.items.end(), 0);
  m.nodes.reserve(2 * std::size_t(nc) / 4 + 4);
  if (nc > 0) m.build(0, nc);
}

TriangleLocator::~TriangleLocator() = default;
TriangleLocator::TriangleLocator(TriangleLocator&&) noexcept = default;
TriangleLocator& TriangleLocator::operator=(TriangleLocator&&) noexcept = default;

std::optional<BoundaryPoint> TriangleLocator::locate(const Eigen::Vector3d& x) const {
  return m_impl->locate(x);
}

// ---------------------------------------------------------------------------------------------
struct BoundaryInverse::Impl {
  const SurfaceMesh* input = nullptr;
  LagrangeMesh identity_triangles;  // dense pipeline: the input faces as order-1 triangles
  std::unique_ptr<TriangleLocator> locator;
  std::unique_ptr<FiberProjection> projection;  // curved pipeline only
  mutable std::mutex mutex;
  mutable std::unordered_map<PositionKey, std::optional<InputPoint>, PositionHash> cache;
};

BoundaryInverse::BoundaryInverse() : m_impl(std::make_unique<Impl>()) {}
BoundaryInverse::~BoundaryInverse() = default;
BoundaryInverse::BoundaryInverse(BoundaryInverse&&) noexcept = default;
BoundaryInverse& BoundaryInverse::operator=(BoundaryInverse&&) noexcept = default;

BoundaryInverse::BoundaryInverse(const BoundaryMap& map, ShellFibers fibers,
                                 const SurfaceMesh& input)
    : BoundaryInverse() {
  if (map.boundary.num_cells() != fibers.num_prisms())
    throw InputError("boundary inverse: " + std::to_string(map.boundary.num_cells()) +
                     " boundary triangles but " + std::to_string(fibers.num_prisms()) +
                     " shell prisms");
  m_impl->input = &input;
  m_impl->locator = std::make_unique<TriangleLocator>(map.boundary);
  m_impl->projection = std::make_unique<FiberProjection>(std::move(fibers), input);
}

BoundaryInverse BoundaryInverse::identity(const SurfaceMesh& input) {
  BoundaryInverse b;
  b.m_impl->input = &input;
  LagrangeMesh& t = b.m_impl->identity_triangles;
  t.kind = CellKind::triangle;
  t.order = 1;
  t.nodes = input.V;
  t.cells = input.F;
  b.m_impl->locator = std::make_unique<TriangleLocator>(t);
  return b;
}

std::optional<InputPoint> BoundaryInverse::from_boundary(int face, double u, double v) const {
  const Impl& m = *m_impl;
  if (m.projection) {
    const auto p = m.projection->project(face, u, v);
    if (!p) return std::nullopt;
    return InputPoint{p->face, p->bary, p->position};
  }
  if (face < 0 || face >= m.input->num_faces()) return std::nullopt;
  InputPoint p;
  p.face = face;
  p.bary = Eigen::Vector3d(1 - u - v, u, v);
  p.position.setZero();
  for (int j = 0; j < 3; ++j)
    p.position += p.bary[j] * m.input->V.row(m.input->F(face, j)).transpose();
  return p;
}

std::optional<BoundaryPoint> BoundaryInverse::locate(const Eigen::Vector3d& x) const {
  return m_impl->locator->locate(x);
}

std::optional<InputPoint> BoundaryInverse::operator()(const Eigen::Vector3d& x) const {
  const PositionKey key = position_key(x);
  {
    std::lock_guard<std::mutex> lock(m_impl->mutex);
    auto it = m_impl->cache.find(key);
    if (it != m_impl->cache.end()) return it->second;
  }
  std::optional<InputPoint> out;
  if (const auto b = locate(x)) out = from_boundary(b->face, b->u, b->v);
  std::lock_guard<std::mutex> lock(m_impl->mutex);
  m_impl->cache.emplace(key, out);
  return out;
}

InputPoint BoundaryInverse::at(const Eigen::Vector3d& x) const {
  const auto p = (*this)(x);
  if (!p) {
    const bool located = locate(x).has_value();
    throw MeshingError(
        "boundary inverse: point (" + std::to_string(x[0]) + ", " + std::to_string(x[1]) + ", " +
        std::to_string(x[2]) + ") " +
        (located ? "has no input point on its shell fiber" : "is not on the boundary of the mesh"));
  }
  return *p;
}

BoundaryMap make_identity_boundary_map(const SurfaceMesh& input) {
  BoundaryMap map;
  map.boundary.kind = CellKind::triangle;
  map.boundary.order = 1;
  map.boundary.nodes = input.V;
  map.boundary.cells = input.F;
  const int nv = input.num_vertices();
  map.boundary_node_to_volume.resize(nv);
  std::iota(map.boundary_node_to_volume.begin(), map.boundary_node_to_volume.end(), 0);
  map.vertex_face = Eigen::VectorXi::Constant(nv, -1);
  map.vertex_uv = Eigen::MatrixXd::Zero(nv, 2);
  for (int f = 0; f < input.num_faces(); ++f)
    for (int j = 0; j < 3; ++j) {
      const int v = input.F(f, j);
      if (map.vertex_face[v] >= 0) continue;
      map.vertex_face[v] = f;
      map.vertex_uv(v, 0) = j == 1 ? 1.0 : 0.0;
      map.vertex_uv(v, 1) = j == 2 ? 1.0 : 0.0;
    }
  return map;
}

}  // namespace curvefem::mapping
