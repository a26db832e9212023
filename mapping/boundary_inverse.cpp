#include "mapping/boundary_inverse.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <mutex>
#include <numeric>
#include <string>
#include <unordered_map>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/shell/projection.hpp"

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

struct BitsKey {
  std::array<std::uint64_t, 3> bits;
  bool operator==(const BitsKey&) const = default;
};
struct BitsHash {
  std::size_t operator()(const BitsKey& k) const {
    return k.bits[0] * 0x9E3779B97F4A7C15ull ^ (k.bits[1] + 0x7F4A7C15ull) * 31 ^ k.bits[2];
  }
};
BitsKey bits_of(const Eigen::Vector3d& p) {
  BitsKey k;
  for (int i = 0; i < 3; ++i) std::memcpy(&k.bits[i], &p[i], sizeof(double));
  return k;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
struct TriangleLocator::Impl {
  const LagrangeMesh* tri = nullptr;
  double tolerance = 0;
  std::vector<Box> boxes;
  std::vector<int> items;
  std::vector<BvhNode> nodes;

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

  /// Gauss–Newton for min |T_f(u, v) − x|², (u, v) kept in the reference triangle.
  BoundaryPoint invert(int f, const Eigen::Vector3d& x) const {
    double u = 1.0 / 3, v = 1.0 / 3;
    Eigen::Vector3d r = tri->map(f, Eigen::Vector3d(u, v, 0)) - x;
    for (int it = 0; it < 40; ++it) {
      const Eigen::MatrixXd J = tri->jacobian(f, Eigen::Vector3d(u, v, 0));  // 3 × 2
      const Eigen::Matrix2d JtJ = J.transpose() * J;
      const Eigen::Vector2d step = JtJ.ldlt().solve(-(J.transpose() * r));
      if (!step.allFinite()) break;
      double nu = u + step[0], nv = v + step[1];
      clamp_to_triangle(nu, nv);
      const double moved = std::abs(nu - u) + std::abs(nv - v);
      u = nu;
      v = nv;
      r = tri->map(f, Eigen::Vector3d(u, v, 0)) - x;
      if (moved < 1e-15) break;
    }
    return {f, u, v, r.norm()};
  }

  std::optional<BoundaryPoint> locate(const Eigen::Vector3d& x) const {
    std::optional<BoundaryPoint> best;
    if (nodes.empty()) return best;
    std::vector<int> stack{0};
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
        const BoundaryPoint p = invert(f, x);
        if (!best || p.residual < best->residual) best = p;
      }
    }
    if (best && best->residual > tolerance) best.reset();
    return best;
  }
};

TriangleLocator::TriangleLocator(const LagrangeMesh& triangles, double tolerance_rel)
    : m_impl(std::make_unique<Impl>()) {
  CF_VERIFY(triangles.kind == CellKind::triangle, "TriangleLocator: triangles expected");
  Impl& m = *m_impl;
  m.tri = &triangles;
  const double scale = triangles.num_nodes() > 0 ? bbox_longest_edge(triangles.nodes) : 1.0;
  m.tolerance = tolerance_rel * std::max(scale, 1e-300);
  const int nc = triangles.num_cells();
  m.boxes.resize(nc);
  for (int f = 0; f < nc; ++f) {
    Box b;
    for (int j = 0; j < triangles.cells.cols(); ++j) {
      const Eigen::Vector3d p = triangles.nodes.row(triangles.cells(f, j)).transpose();
      b.lo = b.lo.cwiseMin(p);
      b.hi = b.hi.cwiseMax(p);
    }
    // A curved Lagrange triangle may leave its nodes' hull: inflate by a share of its size.
    const double pad =
        (triangles.order > 1 ? 0.25 : 0.0) * (b.hi - b.lo).maxCoeff() + 2 * m.tolerance;
    b.lo.array() -= pad;
    b.hi.array() += pad;
    m.boxes[f] = b;
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
  std::unique_ptr<meshing::shell::ShellProjection> projection;  // curved pipeline only
  mutable std::mutex mutex;
  mutable std::unordered_map<BitsKey, std::optional<InputPoint>, BitsHash> cache;
};

BoundaryInverse::BoundaryInverse() : m_impl(std::make_unique<Impl>()) {}
BoundaryInverse::~BoundaryInverse() = default;
BoundaryInverse::BoundaryInverse(BoundaryInverse&&) noexcept = default;
BoundaryInverse& BoundaryInverse::operator=(BoundaryInverse&&) noexcept = default;

BoundaryInverse BoundaryInverse::through_shell(const BoundaryMap& map,
                                               const meshing::shell::Shell& shell,
                                               const SurfaceMesh& input) {
  CF_VERIFY(map.boundary.num_cells() == shell.F.rows(),
            "boundary inverse: " + std::to_string(map.boundary.num_cells()) +
                " boundary triangles but " + std::to_string(shell.F.rows()) + " shell faces");
  BoundaryInverse b;
  b.m_impl->input = &input;
  b.m_impl->locator = std::make_unique<TriangleLocator>(map.boundary);
  b.m_impl->projection = std::make_unique<meshing::shell::ShellProjection>(shell, input);
  return b;
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
    const auto p = m.projection->project(meshing::shell::PrismPoint{face, u, v, 0.0});
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
  const BitsKey key = bits_of(x);
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
