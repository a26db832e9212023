#include "meshing/shell/section_remesh.hpp"

#include <chrono>
#include <limits>

#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"

namespace curvefem::meshing::shell {

namespace {

using editing::Attribute;
using editing::Id;
using editing::OperationRecord;

class SectionMesh : public editing::IsotropicMesh {
 public:
  Attribute<int> pinch{*this, 0, -1};  // the singular shell vertex a frozen vertex sits on
  const ShellProjection* projection = nullptr;
  const SectionChecker* checker = nullptr;

  // P(p): the input point on the fiber through p; NaN outside the shell (rejects the operation).
  Eigen::Vector3d snap(const Eigen::Vector3d& p) const {
    if (const auto s = projection->project(p)) return s->position;
    return Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  }

 protected:
  Eigen::Vector3d place_on_surface(const Eigen::Vector3d& p) const override { return snap(p); }
  Eigen::Vector3d collapse_position(Id removed, Id kept) const override {
    return snap(0.5 * (position[removed] + position[kept]));
  }
  bool split_edge_after(const OperationRecord& r) override {
    if (!IsotropicMesh::split_edge_after(r)) return false;
    position.set(r.new_vertex, snap(position[r.new_vertex]));
    return position[r.new_vertex].allFinite();
  }
  bool invariants(const OperationRecord& r) override {
    if (!IsotropicMesh::invariants(r)) return false;
    for (Id f : r.affected_cells) {
      const Cell& c = cell(f);
      const SectionChecker::Triangle t{position[c[0]], position[c[1]], position[c[2]]};
      if (!checker->triangle_ok(t, {pinch[c[0]], pinch[c[1]], pinch[c[2]]})) return false;
    }
    return true;
  }
};

}  // namespace

SectionRemeshResult remesh_section(const ShellProjection& projection,
                                   const SectionRemeshOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!(options.target_edge > 0))
    throw InputError("section remeshing needs a positive target edge length");
  const Shell& shell = projection.shell();
  const SectionChecker checker(projection);
  SurfaceMesh middle;
  middle.V = shell.mid;
  middle.F = shell.F;
  SectionRemeshResult result;
  result.start = checker.check(middle);
  if (!result.start.is_section())
    throw MeshingError(log::cat("section remeshing: the shell's middle surface is not a section (",
                                result.start.manifold ? "" : "not a closed oriented manifold; ",
                                result.start.vertices_outside, " vertices outside, ",
                                result.start.faces_crossing_cage, " faces crossing base/top, ",
                                result.start.faces_not_transversal, " faces not transversal, ",
                                result.start.degree_failures, " degree failures)"));

  SectionMesh m;
  m.projection = &projection;
  m.checker = &checker;
  m.load(middle);
  for (int v = 0; v < middle.num_vertices(); ++v)
    if (shell.singular[std::size_t(v)]) {
      m.frozen.set(Id(v), 1);
      m.pinch.set(Id(v), v);
    }
  editing::isotropic_remeshing(m, options.target_edge, options.iterations, options.threads,
                               result.passes);
  for (const auto& [name, stats] : result.passes)
    log::debug("section remesh ", name, ": ", stats.summary());
  result.mesh = m.extract();
  result.result = checker.check(result.mesh);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  log::info("section remesh: ", middle.num_faces(), " -> ", result.mesh.num_faces(),
            " faces (target edge ", options.target_edge, "), section ",
            result.result.is_section() ? "yes" : "NO", ", ", result.seconds, " s");
  return result;
}

}  // namespace curvefem::meshing::shell
