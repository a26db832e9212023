// Validation, the run and its exact checks (see the header).
#include "meshing/param/deform.hpp"

#include <algorithm>
#include <string>

#include "meshing/check/self_intersections.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/timer.hpp"

namespace curvefem::meshing::param {

DeformOutcome deform_checked(const SurfaceMesh& surface, DeformRequest request) {
  if (request.untangle && (!request.targets.empty() || request.options.grow != 1.0))
    throw InputError(
        "deform: untangle takes no targets or grow (its targets are the input's vertices)");
  if (!request.untangle && !request.untangle_options.way_back_targets)
    throw InputError("deform: the way back without targets is an untangle option");
  if (!request.untangle && request.targets.empty() && request.options.grow == 1.0)
    throw InputError("deform: nothing to do: give targets, grow (!= 1) or untangle");
  DeformOutcome out;
  Stopwatch watch;
  out.input_pairs = check::count_self_intersecting_pairs(surface.V, surface.F);
  if (!request.untangle && out.input_pairs > 0)
    throw InputError("deform: the input surface intersects itself (" +
                     std::to_string(out.input_pairs) +
                     " face pairs; meshing/check): the scaffold needs an embedded surface "
                     "(untangle removes the intersections of a genus-0 surface)");
  // The targets applied as they are: what a deformation without the scaffold could do.
  out.naive_pairs = out.input_pairs;
  if (!request.targets.empty()) {
    Eigen::MatrixXd naive = surface.V;
    for (const PositionTarget& t : request.targets) naive.row(t.vertex) = t.target.transpose();
    out.naive_pairs = check::count_self_intersecting_pairs(naive, surface.F);
  }
  out.check_seconds = watch.seconds();
  Deform3dOptions options = request.options;
  options.on_iteration = [&](const Deform3dIteration& st, const Eigen::MatrixXd& V) {
    Stopwatch c;
    const int pairs = check::count_self_intersecting_pairs(V, surface.F);
    out.check_seconds += c.seconds();
    out.max_pairs_over_iterations = std::max(out.max_pairs_over_iterations, pairs);
    if (request.observe) request.observe(st, V, pairs);
  };
  if (request.untangle) {
    UntangleOptions u = request.untangle_options;
    u.deform = options;
    out.untangle = untangle_surface(surface, u);
    out.result = std::move(out.untangle->back);
    out.untangle->back = {};
  } else {
    out.result = scaf3d_deform(surface, request.targets, options);
  }
  watch.reset();
  out.tiling = verify_scaf3d(surface, out.result);
  out.final_pairs = check::count_self_intersecting_pairs(out.result.V, surface.F);
  out.check_seconds += watch.seconds();
  return out;
}

}  // namespace curvefem::meshing::param
