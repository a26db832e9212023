#include "meshing/editing/algorithms/surface_edit_mesh.hpp"

#include <algorithm>
#include <tuple>

#include "meshing/core/error.hpp"

namespace curvefem::meshing::editing {

void SurfaceEditMesh::load(const SurfaceMesh& s) {
  // Edge manifoldness and orientation from sorted half-edges (fast on millions of faces).
  struct HalfEdge {
    int lo, hi, face;
    bool forward;
  };
  std::vector<HalfEdge> half;
  half.reserve(std::size_t(s.num_faces()) * 3);
  for (int f = 0; f < s.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = s.F(f, k), b = s.F(f, (k + 1) % 3);
      if (a < 0 || b < 0 || a >= s.num_vertices() || b >= s.num_vertices() || a == b)
        throw InputError("face " + std::to_string(f) + " has an invalid or repeated vertex index",
                         ErrorContext{.face = f});
      half.push_back({std::min(a, b), std::max(a, b), f, a < b});
    }
  std::sort(half.begin(), half.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return std::tie(x.lo, x.hi) < std::tie(y.lo, y.hi);
  });
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    while (j < half.size() && half[j].lo == half[i].lo && half[j].hi == half[i].hi) ++j;
    if (j - i > 2)
      throw InputError("edge (" + std::to_string(half[i].lo) + ", " + std::to_string(half[i].hi) +
                           ") is shared by " + std::to_string(j - i) + " faces (non-manifold)",
                       ErrorContext{.vertex = half[i].lo, .face = half[i].face});
    if (j - i == 2 && half[i].forward == half[i + 1].forward)
      throw InputError("faces " + std::to_string(half[i].face) + " and " +
                           std::to_string(half[i + 1].face) +
                           " are inconsistently oriented across edge (" +
                           std::to_string(half[i].lo) + ", " + std::to_string(half[i].hi) + ")",
                       ErrorContext{.vertex = half[i].lo, .face = half[i].face});
    i = j;
  }
  std::vector<Cell> cells(s.num_faces());
  for (int f = 0; f < s.num_faces(); ++f) cells[f] = {Id(s.F(f, 0)), Id(s.F(f, 1)), Id(s.F(f, 2))};
  initialize(std::size_t(s.num_vertices()), cells);
  for (int v = 0; v < s.num_vertices(); ++v) {
    position.set(Id(v), s.V.row(v).transpose());
    frozen.set(Id(v), 0);
  }
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    while (j < half.size() && half[j].lo == half[i].lo && half[j].hi == half[i].hi) ++j;
    if (j - i == 1) {
      frozen.set(Id(half[i].lo), 1);
      frozen.set(Id(half[i].hi), 1);
    }
    i = j;
  }
}

SurfaceMesh SurfaceEditMesh::extract() {
  consolidate();
  SurfaceMesh out;
  out.V.resize(Eigen::Index(vertex_capacity()), 3);
  for (std::size_t v = 0; v < vertex_capacity(); ++v)
    out.V.row(Eigen::Index(v)) = position[v].transpose();
  const auto cells = cells_array();
  out.F.resize(Eigen::Index(cells.size()), 3);
  for (std::size_t f = 0; f < cells.size(); ++f)
    for (int k = 0; k < 3; ++k) out.F(Eigen::Index(f), k) = int(cells[f][k]);
  return out;
}

Eigen::Vector3d SurfaceEditMesh::face_normal(Id f) const {
  const Cell& c = cell(f);
  return (position[c[1]] - position[c[0]]).cross(position[c[2]] - position[c[0]]);
}

Eigen::Vector3d SurfaceEditMesh::vertex_normal(Id v) const {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (Id f : vertex_cells(v)) n += face_normal(f);
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : n;
}

bool SurfaceEditMesh::split_edge_before(const Tuple&) {
  m_scratch.local().kind = Kind::split;
  return true;
}

bool SurfaceEditMesh::split_edge_after(const OperationRecord& r) {
  position.set(r.new_vertex, 0.5 * (position[r.v0] + position[r.v1]));
  // A split boundary edge gives a boundary (frozen) vertex.
  const Id e[2] = {r.new_vertex, r.v0};
  frozen.set(r.new_vertex, cells_containing(std::span<const Id>(e, 2)).size() == 1 ? 1 : 0);
  return true;
}

bool SurfaceEditMesh::collapse_edge_before(const Tuple& t) {
  m_scratch.local().kind = Kind::collapse;
  if (frozen[t.vid] || frozen[other_vertex(t)]) return false;
  return !collapse_admit || collapse_admit(t);
}

bool SurfaceEditMesh::collapse_edge_after(const OperationRecord& r) {
  // Faces of the kept vertex that the collapse did not replace move with it: remember their
  // normals before it moves.
  Scratch& s = m_scratch.local();
  s.old_normals.clear();
  for (Id f : r.affected_cells) s.old_normals.push_back(face_normal(f));
  position.set(r.v1, collapse_position(r.v0, r.v1));
  if (!collapse_acceptable(r)) return false;
  collapse_update(r);
  return true;
}

bool SurfaceEditMesh::swap_edge_before(const Tuple& t) {
  m_scratch.local().kind = Kind::swap;
  return swap_acceptable(t);
}

bool SurfaceEditMesh::swap_edge_after(const OperationRecord&) { return true; }

bool SurfaceEditMesh::smooth_before(const Tuple& t) {
  m_scratch.local().kind = Kind::smooth;
  return !frozen[t.vid];
}

bool SurfaceEditMesh::smooth_after(const OperationRecord& r) {
  Scratch& s = m_scratch.local();
  s.old_normals.clear();
  for (Id f : r.new_cells) s.old_normals.push_back(face_normal(f));
  position.set(r.v0, smooth_position(r.v0));
  return true;
}

bool SurfaceEditMesh::close_normals(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
  // cos(angle) > min_normal_cos without normalizing: a·b > c |a||b| (and a·b > 0).
  const double d = a.dot(b);
  return d > 0 && d * d > min_normal_cos * min_normal_cos * a.squaredNorm() * b.squaredNorm();
}

bool SurfaceEditMesh::no_fold(const OperationRecord& r) const {
  const Scratch& s = m_scratch.local();
  switch (s.kind) {
    case Kind::split:
      return true;
    case Kind::collapse: {
      // New face i came from the i-th old face not containing the kept vertex; those old faces
      // still read their old positions (the removed vertex is never written again). The other
      // affected faces (already incident to the kept vertex) compare with their normals from
      // before the move.
      std::size_t i = 0;
      for (Id f : r.old_cells) {
        const Cell& c = cell(f);
        if (c[0] == r.v1 || c[1] == r.v1 || c[2] == r.v1) continue;
        if (!close_normals(face_normal(r.new_cells[i++]), face_normal(f))) return false;
      }
      for (std::size_t k = 0; k < r.affected_cells.size(); ++k) {
        const Id f = r.affected_cells[k];
        if (std::binary_search(r.new_cells.begin(), r.new_cells.end(), f)) continue;
        if (!close_normals(face_normal(f), s.old_normals[k])) return false;
      }
      return true;
    }
    case Kind::swap:
      for (Id g : r.new_cells)
        for (Id f : r.old_cells)
          if (!close_normals(face_normal(g), face_normal(f))) return false;
      return true;
    case Kind::smooth:
      for (std::size_t i = 0; i < r.new_cells.size(); ++i)
        if (!close_normals(face_normal(r.new_cells[i]), s.old_normals[i])) return false;
      return true;
  }
  return true;
}

bool SurfaceEditMesh::invariants(const OperationRecord& r) {
  for (Id f : r.affected_cells) {
    const Cell& c = cell(f);
    const double e2 = std::max({(position[c[1]] - position[c[0]]).squaredNorm(),
                                (position[c[2]] - position[c[1]]).squaredNorm(),
                                (position[c[0]] - position[c[2]]).squaredNorm()});
    if (!(face_normal(f).squaredNorm() > 1e-20 * e2 * e2)) return false;  // degenerate (or NaN)
  }
  if (!no_fold(r)) return false;
  if (envelope != nullptr) {
    for (Id f : r.affected_cells) {
      const Cell& c = cell(f);
      if (!envelope->triangle_within(position[c[0]], position[c[1]], position[c[2]], envelope_eps))
        return false;
    }
  }
  return true;
}

}  // namespace curvefem::meshing::editing
