#include "meshing/shell/nested_cages.hpp"

#include <tbb/parallel_for.h>

#include <limits>
#include <optional>
#include <set>
#include <string>

#include "meshing/check/self_intersections.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/prism_split.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/shell/bevel.hpp"

namespace curvefem::meshing::shell {
namespace {

std::vector<std::pair<int, int>> top_pairs(const Shell& shell) {
  const auto degenerate = check::exactly_degenerate_faces(shell.top, shell.F);
  return check::find_self_intersections(shell.top, shell.F, degenerate, true).pairs;
}

/// Shortens the top pillars of the faces in self-intersecting pairs of the top surface, round by
/// round, each round verified; "" when the top surface ends free of self-intersections, else why
/// not (shell left as it was before the failing round).
std::string shrink_top(Shell& shell, CageLayer& layer, const NestedCageOptions& options) {
  auto pairs = top_pairs(shell);
  layer.self_intersecting_pairs_before = int(pairs.size());
  layer.shrink_rounds = 0;
  std::set<int> shrunk;
  while (!pairs.empty()) {
    if (layer.shrink_rounds == options.max_shrink_rounds)
      return "the top surface still has " + std::to_string(pairs.size()) +
             " self-intersecting face pairs after " + std::to_string(layer.shrink_rounds) +
             " shrink rounds";
    Shell trial = shell;
    std::set<int> vertices;
    for (const auto& [f, g] : pairs)
      for (int c = 0; c < 3; ++c) {
        vertices.insert(shell.F(f, c));
        vertices.insert(shell.F(g, c));
      }
    for (int v : vertices)
      trial.top.row(v) = shell.mid.row(v) + options.shrink * (shell.top.row(v) - shell.mid.row(v));
    const ShellVerification check = verify_shell(trial, layer.surface);
    if (!check.positive() || !check.separated() || !check.section())
      return "shortening the top pillars of " + std::to_string(vertices.size()) +
             " vertices to remove " + std::to_string(pairs.size()) +
             " self-intersecting pairs of the top surface breaks the shell (" +
             std::to_string(check.non_positive_faces) + " prisms not positive, " +
             std::to_string(check.intersecting_input_faces) + " faces meeting it, " +
             std::to_string(check.non_section_faces) + " not a section)";
    shrunk.insert(vertices.begin(), vertices.end());
    layer.verification = check;  // of the shell kept: no need to verify it again
    shell = std::move(trial);
    ++layer.shrink_rounds;
    pairs = top_pairs(shell);
  }
  layer.shrunk_pillars = int(shrunk.size());
  return "";
}

}  // namespace

NestedCages build_nested_cages(const SurfaceMesh& input, const NestedCageOptions& options,
                               const ProgressFn& progress) {
  if (options.layers < 1) throw InputError("nested cages: at least one layer");
  if (!(options.shrink > 0 && options.shrink < 1))
    throw InputError("nested cages: the shrink factor must be in (0, 1)");
  NestedCages out;
  out.input = input;
  SurfaceMesh current = input;
  for (int k = 0; k < options.layers; ++k) {
    if (progress) progress("nested cages", double(k) / options.layers);
    Stopwatch clock;
    CageLayer layer;
    // Attempts, coarsest first: simplified with thickness growth, simplified without it, the
    // same on a shell of a quarter of the thickness (thinner tops meet less across concave
    // parts), and the shell as built (its middle surface is the layer inside, which shrinking
    // cannot cross).
    struct Attempt {
      std::string name;
      double zoom;       // < 0: no simplification
      double thickness;  // factor on options.shell.max_thickness_rel
    };
    std::vector<Attempt> attempts;
    if (options.simplify) {
      attempts.push_back({"simplified", options.zoom_rel, 1.0});
      if (options.zoom_rel > 0) attempts.push_back({"simplified without growth", 0.0, 1.0});
      attempts.push_back({"simplified, thinner", 0.0, 0.25});
    }
    attempts.push_back({"not simplified", -1.0, 1.0});
    std::string why;
    Shell shell;
    std::unique_ptr<BeveledShell> beveled;
    double built_thickness = -1;
    for (std::size_t a = 0; a < attempts.size(); ++a) {
      if (attempts[a].thickness != built_thickness) {
        ShellOptions so = options.shell;
        so.threads = options.threads;
        so.max_thickness_rel *= attempts[a].thickness;
        ShellStats stats;
        beveled = std::make_unique<BeveledShell>(build_beveled_shell(current, so, stats));
        built_thickness = attempts[a].thickness;
        layer.surface = beveled->surface.mesh;
        layer.surface_face_parent = beveled->surface.face_parent;
        layer.surface_corner_bary = beveled->surface.corner_bary;
        layer.singular_vertices = stats.singular_vertices;
      }
      shell = beveled->shell;
      if (attempts[a].zoom >= 0) {
        SimplifyOptions simplify;
        simplify.threads = options.threads;
        simplify.zoom = attempts[a].zoom * bbox_longest_edge(current.V);
        SimplifyStats ss;
        shell = simplify_shell(shell, layer.surface, simplify, ss);
      }
      layer.attempt = attempts[a].name;
      why = shrink_top(shell, layer, options);
      if (why.empty()) break;
      log::info("nested cages: layer ", k + 1, ", ", attempts[a].name, ": ", why);
      if (a + 1 == attempts.size())
        throw MeshingError("nested cages: layer " + std::to_string(k + 1) + ": " + why);
    }
    if (layer.shrink_rounds == 0) layer.verification = verify_shell(shell, layer.surface);
    layer.cage.V = shell.top;
    layer.cage.F = shell.F;
    layer.shell = std::move(shell);
    layer.seconds = clock.seconds();
    log::info("nested cages: layer ", k + 1, ": ", layer.cage.num_faces(), " faces, ",
              layer.self_intersecting_pairs_before, " self-intersecting pairs removed in ",
              layer.shrink_rounds, " rounds (", layer.shrunk_pillars, " pillars), ", layer.seconds,
              " s");
    current = layer.cage;
    out.layers.push_back(std::move(layer));
  }
  for (const CageLayer& layer : out.layers)
    out.projections.push_back(std::make_unique<ShellProjection>(layer.shell, layer.surface));
  if (progress) progress("nested cages", 1.0);
  return out;
}

namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

template <class Step>
Eigen::MatrixXd walk(const Eigen::MatrixXd& points, int* failures, const Step& step) {
  Eigen::MatrixXd out(points.rows(), 3);
  std::vector<char> failed(std::size_t(points.rows()), 0);
  tbb::parallel_for(Eigen::Index(0), points.rows(), [&](Eigen::Index i) {
    const auto x = step(Eigen::Vector3d(points.row(i)));
    if (x) {
      out.row(i) = x->transpose();
    } else {
      out.row(i).setConstant(k_nan);
      failed[std::size_t(i)] = 1;
    }
  });
  if (failures) *failures = int(std::count(failed.begin(), failed.end(), 1));
  return out;
}

}  // namespace

Eigen::MatrixXd cage_to_input(const NestedCages& cages, int k, const std::vector<MeshPoint>& points,
                              int* failures) {
  CF_VERIFY(k >= 0 && k < int(cages.layers.size()), "cage_to_input: no such layer");
  Eigen::MatrixXd out(Eigen::Index(points.size()), 3);
  std::vector<char> failed(points.size(), 0);
  tbb::parallel_for(std::size_t(0), points.size(), [&](std::size_t i) {
    MeshPoint p = points[i];
    std::optional<SurfacePoint> s;
    for (int j = k; j >= 0; --j) {
      const CageLayer& layer = cages.layers[std::size_t(j)];
      // (face, bary) of the top surface = the prism point (face, u, v, 1), rotated order.
      const Eigen::Vector3i F = layer.shell.F.row(p.face);
      const int r = min_rotation(F);
      PrismPoint q;
      q.face = p.face;
      q.u = p.bary[(r + 1) % 3];
      q.v = p.bary[(r + 2) % 3];
      q.h = 1;
      s = cages.projections[std::size_t(j)]->project(q);
      if (!s) break;
      // The surface's face in the layer inside (the cage below, or the input).
      p.face = layer.surface_face_parent.empty() ? s->face
                                                 : layer.surface_face_parent[std::size_t(s->face)];
      p.bary = layer.surface_corner_bary.empty()
                   ? s->bary
                   : Eigen::Vector3d(layer.surface_corner_bary[std::size_t(s->face)] * s->bary);
    }
    if (s) {
      out.row(Eigen::Index(i)) = s->position.transpose();
    } else {
      out.row(Eigen::Index(i)).setConstant(k_nan);
      failed[i] = 1;
    }
  });
  if (failures) *failures = int(std::count(failed.begin(), failed.end(), 1));
  return out;
}

Eigen::MatrixXd input_to_cage(const NestedCages& cages, int k, const Eigen::MatrixXd& points,
                              int* failures) {
  CF_VERIFY(k >= 0 && k < int(cages.layers.size()), "input_to_cage: no such layer");
  return walk(points, failures, [&](Eigen::Vector3d x) -> std::optional<Eigen::Vector3d> {
    for (int j = 0; j <= k; ++j) {
      const ShellProjection& p = *cages.projections[std::size_t(j)];
      auto q = p.unproject(x);
      if (!q) return std::nullopt;
      q->h = 1;
      x = p.point(*q);
    }
    return x;
  });
}

}  // namespace curvefem::meshing::shell
