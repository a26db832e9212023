// Isotropic remeshing [Botsch & Kobbelt 2004], target edge length L, repeated `iterations` times:
//   1. split every edge longer than 4/3 L at its midpoint,
//   2. collapse every edge shorter than 4/5 L into its midpoint unless that creates an edge
//      longer than 4/3 L,
//   3. flip edges that reduce the squared deviation of the four vertices' valences from 6
//      (4 on the boundary),
//   4. tangential relaxation: move each vertex towards the centroid of its neighbours within
//      its tangent plane, then back onto the surface (place_on_surface: by default the closest
//      point of the input).
// Each step is one scheduler pass; splits and collapses renew the edges around the new vertex,
// flips renew the improving edges around their four vertices (each flip lowers the total
// valence deviation, so the pass terminates).

#include "meshing/editing/algorithms/isotropic_remeshing.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <span>

#include "meshing/editing/algorithms/surface_passes.hpp"

namespace curvefem::meshing::editing {

int IsotropicMesh::deviation_change(const Tuple& t) const {
  const Id a = t.vid, b = other_vertex(t);
  const Id e[2] = {a, b};
  const auto faces = cells_containing(std::span<const Id>(e, 2));
  if (faces.size() != 2) return 0;
  Id opp[2];
  for (int i = 0; i < 2; ++i)
    for (Id v : cell(faces[i]))
      if (v != a && v != b) opp[i] = v;
  auto dev = [&](Id v, int change) {
    const int d = valence(v) + change - target_valence(v);
    return d * d;
  };
  const int before = dev(a, 0) + dev(b, 0) + dev(opp[0], 0) + dev(opp[1], 0);
  const int after = dev(a, -1) + dev(b, -1) + dev(opp[0], 1) + dev(opp[1], 1);
  return after - before;
}

bool IsotropicMesh::collapse_acceptable(const OperationRecord& r) const {
  for (Id u : one_ring(r.v1))
    if ((position[u] - position[r.v1]).squaredNorm() > high2) return false;
  return true;
}

// Flip toward valence 6, but never create an edge longer than 4/3 L (it would stay: splits come
// before flips in a round).
bool IsotropicMesh::swap_acceptable(const Tuple& t) const {
  if (deviation_change(t) >= 0) return false;
  const Id a = t.vid, b = other_vertex(t);
  const Id e[2] = {a, b};
  const auto faces = cells_containing(std::span<const Id>(e, 2));
  if (faces.size() != 2) return false;
  Id opp[2] = {k_no_id, k_no_id};
  for (int i = 0; i < 2; ++i)
    for (Id v : cell(faces[i]))
      if (v != a && v != b) opp[i] = v;
  return (position[opp[0]] - position[opp[1]]).squaredNorm() <= high2;
}

Eigen::Vector3d IsotropicMesh::place_on_surface(const Eigen::Vector3d& p) const {
  return input != nullptr ? input->closest_point(p) : p;
}

Eigen::Vector3d IsotropicMesh::smooth_position(Id v) const {
  const auto ring = one_ring(v);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (Id u : ring) centroid += position[u];
  centroid /= double(ring.size());
  const Eigen::Vector3d n = vertex_normal(v);
  const Eigen::Vector3d d = centroid - position[v];
  return place_on_surface(position[v] + d - n * n.dot(d));
}

namespace {

std::vector<SurfacePass::Work> edges_where(const SurfaceEditMesh& m,
                                           const std::vector<TriMesh::Tuple>& edges,
                                           const std::string& op,
                                           const std::function<bool(double)>& keep) {
  std::vector<SurfacePass::Work> work;
  for (const auto& e : edges)
    if (keep(m.edge_length2(e))) work.emplace_back(op, e);
  return work;
}

}  // namespace

std::unique_ptr<SurfaceEditMesh> make_isotropic_mesh() { return std::make_unique<IsotropicMesh>(); }

void isotropic_remeshing(SurfaceEditMesh& base, const SurfaceDistance& input, double target_edge,
                         int iterations, int threads, PassLog& log) {
  auto& m = dynamic_cast<IsotropicMesh&>(base);
  m.input = &input;
  isotropic_remeshing(m, target_edge, iterations, threads, log);
}

void isotropic_remeshing(IsotropicMesh& m, double target_edge, int iterations, int threads,
                         PassLog& log) {
  const double high2 = std::pow(4.0 / 3.0 * target_edge, 2),
               low2 = std::pow(4.0 / 5.0 * target_edge, 2);
  m.high2 = high2;
  auto length_priority = [&m](double sign) {
    return [&m, sign](const TriMesh&, const std::string&, const TriMesh::Tuple& t) {
      return sign * m.edge_length2(t);
    };
  };
  for (int it = 0; it < iterations; ++it) {
    {  // 1. split long edges, longest first
      SurfacePass pass = make_surface_pass(m, threads);
      pass.operations["split"] = [&m](TriMesh&, const TriMesh::Tuple& t) {
        return m.split_edge(t);
      };
      pass.priority = length_priority(1.0);
      pass.should_process = [&m](const TriMesh&, const SurfacePass::Work& w, double queued) {
        return m.edge_length2(w.second) == queued;
      };
      pass.renew_neighbor_tuples = [&m, high2](const TriMesh&, const std::string&,
                                               const TriMesh::Tuple& t) {
        return edges_where(m, m.edges_of_faces(m.vertex_cells(t.vid)), "split",
                           [high2](double l2) { return l2 > high2; });
      };
      log.emplace_back("split",
                       pass.run(m, edges_where(m, m.get_edges(), "split",
                                               [high2](double l2) { return l2 > high2; })));
    }
    {  // 2. collapse short edges, shortest first
      SurfacePass pass = make_surface_pass(m, threads);
      pass.operations["collapse"] = [&m](TriMesh&, const TriMesh::Tuple& t) {
        return m.collapse_edge(t);
      };
      pass.priority = length_priority(-1.0);
      pass.should_process = [&m](const TriMesh&, const SurfacePass::Work& w, double queued) {
        return -m.edge_length2(w.second) == queued;
      };
      pass.renew_neighbor_tuples = [&m, low2](const TriMesh&, const std::string&,
                                              const TriMesh::Tuple& t) {
        return edges_where(m, m.edges_of_faces(m.vertex_cells(t.vid)), "collapse",
                           [low2](double l2) { return l2 < low2; });
      };
      log.emplace_back("collapse",
                       pass.run(m, edges_where(m, m.get_edges(), "collapse",
                                               [low2](double l2) { return l2 < low2; })));
    }
    {  // 3. flip towards valence 6
      SurfacePass pass = make_surface_pass(m, threads);
      pass.operations["swap"] = [&m](TriMesh&, const TriMesh::Tuple& t) { return m.swap_edge(t); };
      pass.priority = [&m](const TriMesh&, const std::string&, const TriMesh::Tuple& t) {
        return -double(m.deviation_change(t));
      };
      // Only flips that lower the deviation are queued. A flip changes the valences of its four
      // vertices, which changes the gain of every edge in their stars: those are re-queued (read
      // under a two-ring lock, since their opposite vertices lie two rings away).
      pass.lock_rings = 2;
      pass.renew_neighbor_tuples = [&m](const TriMesh&, const std::string&, const TriMesh::Tuple&) {
        std::vector<SurfacePass::Work> work;
        const auto& r = m.operation_record();
        std::vector<Id> star;
        for (Id v : {r.v0, r.v1, r.new_edge[0], r.new_edge[1]})
          star.insert(star.end(), m.vertex_cells(v).begin(), m.vertex_cells(v).end());
        std::sort(star.begin(), star.end());
        star.erase(std::unique(star.begin(), star.end()), star.end());
        for (const auto& x : m.edges_of_faces(star))
          if (m.deviation_change(x) < 0) work.emplace_back("swap", x);
        return work;
      };
      std::vector<SurfacePass::Work> work;
      for (const auto& e : m.get_edges())
        if (m.deviation_change(e) < 0) work.emplace_back("swap", e);
      log.emplace_back("swap", pass.run(m, work));
    }
    {  // 4. tangential relaxation, projected back onto the input
      SurfacePass pass = make_surface_pass(m, threads);
      pass.operations["smooth"] = [&m](TriMesh&, const TriMesh::Tuple& t) {
        return m.smooth_vertex(t);
      };
      std::vector<SurfacePass::Work> work;
      for (const auto& v : m.get_vertices()) work.emplace_back("smooth", v);
      log.emplace_back("smooth", pass.run(m, work));
    }
    m.consolidate();
  }
}

}  // namespace curvefem::meshing::editing
