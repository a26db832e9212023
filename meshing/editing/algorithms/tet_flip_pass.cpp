#include "meshing/editing/algorithms/tet_flip_pass.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

namespace curvefem::meshing::editing {

bool positively_oriented(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                         const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  using P = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  // CGAL's orientation is positive when d lies on the positive side of (a, b, c), matching
  // (b-a)x(c-a)·(d-a) > 0.
  return CGAL::orientation(P(a.x(), a.y(), a.z()), P(b.x(), b.y(), b.z()), P(c.x(), c.y(), c.z()),
                           P(d.x(), d.y(), d.z())) == CGAL::POSITIVE;
}

PassStats run_flip_pass(TetMesh& mesh, const std::function<Eigen::Vector3d(Id)>& position,
                        int threads, const std::function<double(const TetMesh::Tuple&)>& priority) {
  ExecutePass<TetMesh> pass;
  pass.num_threads = threads;
  pass.position = position;
  pass.operations["swap23"] = [](TetMesh& m, const TetMesh::Tuple& t) { return m.swap_face_23(t); };
  pass.operations["swap32"] = [](TetMesh& m, const TetMesh::Tuple& t) { return m.swap_edge_32(t); };
  pass.operations["swap44"] = [](TetMesh& m, const TetMesh::Tuple& t) { return m.swap_edge_44(t); };
  // 2-3 flips lock the three face vertices and their one-rings.
  pass.lock_vertices = [](TetMesh& m, const ExecutePass<TetMesh>::Work& w) {
    if (w.first == "swap23") {
      const auto f = m.face_vertices(w.second);
      return m.try_lock_region(std::span<const Id>(f.data(), 3), 1);
    }
    const auto e = m.lock_seeds(w.second);
    return m.try_lock_region(std::span<const Id>(e.data(), 2), 1);
  };
  if (priority)
    pass.priority = [priority](const TetMesh&, const std::string&, const TetMesh::Tuple& t) {
      return priority(t);
    };
  auto work_of = [&mesh](const std::vector<Id>& tets) {
    std::vector<ExecutePass<TetMesh>::Work> work;
    for (const auto& f : mesh.faces_of_tets(tets)) work.emplace_back("swap23", f);
    for (const auto& e : mesh.edges_of_tets(tets)) {
      work.emplace_back("swap32", e);
      work.emplace_back("swap44", e);
      work.emplace_back("swap44", mesh.switch_face(e));  // the other diagonal
    }
    return work;
  };
  pass.renew_neighbor_tuples = [&mesh, work_of](const TetMesh&, const std::string&,
                                                const TetMesh::Tuple&) {
    return work_of(mesh.operation_record().new_cells);
  };
  return pass.run(mesh, work_of(mesh.live_cells()));
}

}  // namespace curvefem::meshing::editing
