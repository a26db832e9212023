#include "meshing/shell/nested_cages.hpp"

#include <tbb/parallel_for.h>

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <string>

#include "meshing/check/self_intersections.hpp"
#include "meshing/check/surface_distance.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/prism_split.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/shell/bevel.hpp"
#include "meshing/shell/boolean.hpp"
#include "meshing/shell/prism_positivity.hpp"
#include "meshing/shell/shell_intersection.hpp"

namespace curvefem::meshing::shell {
namespace {

/// Exactly self-intersecting face pairs of the shell's top (or base) surface.
std::vector<std::pair<int, int>> side_pairs(const Shell& shell, bool top) {
  const Eigen::MatrixXd& m = top ? shell.top : shell.base;
  const auto degenerate = check::exactly_degenerate_faces(m, shell.F);
  return check::find_self_intersections(m, shell.F, degenerate, true).pairs;
}

/// The prisms around moved pillar ends alone: positive (both halves), and their top and base
/// triangles off `surface` (contact at pinch points only). A cheap screen before verify_shell.
class LocalCheck {
 public:
  LocalCheck(const Shell& shell, const SurfaceMesh& surface)
      : faces_of_(static_cast<std::size_t>(shell.top.rows())),
        index_(surface.V, surface.F, shell.reference) {
    for (int f = 0; f < int(shell.F.rows()); ++f)
      for (int c = 0; c < 3; ++c) faces_of_[std::size_t(shell.F(f, c))].push_back(f);
  }
  bool ok(const Shell& trial, const std::set<int>& moved) const {
    std::set<int> faces;
    for (int v : moved)
      faces.insert(faces_of_[std::size_t(v)].begin(), faces_of_[std::size_t(v)].end());
    for (int f : faces) {
      std::array<Eigen::Vector3d, 3> b, m, t;
      std::array<bool, 3> sing{};
      Eigen::Vector3i ids;
      for (int k = 0; k < 3; ++k) {
        const int v = trial.F(f, k);
        b[std::size_t(k)] = trial.base.row(v);
        m[std::size_t(k)] = trial.mid.row(v);
        t[std::size_t(k)] = trial.top.row(v);
        sing[std::size_t(k)] = trial.singular[std::size_t(v)];
        ids[k] = sing[std::size_t(k)] ? trial.input_vertex[std::size_t(v)] : -1;
      }
      if (!shell_face_positive(b, m, t, sing)) return false;
      if (index_.triangle_intersects(t, sing, ids) || index_.triangle_intersects(b, sing, ids))
        return false;
    }
    return true;
  }

 private:
  std::vector<std::vector<int>> faces_of_;
  InputSurfaceIndex index_;
};

/// One round of shortenings. The items (pinch points, self-intersecting pairs) are tried
/// together: the pillar ends `vertices_of(group)` on the top (base) side move to fraction `shrink`
/// of their distance from the middle surface, and `accept(trial, vertices)` decides. A refused
/// group is split in halves, each tried alone (when `split`); `refused(group)` is called for a
/// group refused and not split. Returns whether a change was kept (`shell` holds all of them).
template <class Item, class VerticesOf, class Accept, class Refused>
bool shorten_in_halves(Shell& shell, bool top, double shrink, std::vector<Item> items, bool split,
                       const VerticesOf& vertices_of, const Accept& accept,
                       const Refused& refused) {
  std::vector<std::vector<Item>> groups{std::move(items)};
  bool changed = false;
  while (!groups.empty()) {
    const std::vector<Item> group = std::move(groups.back());
    groups.pop_back();
    const std::set<int> vertices = vertices_of(group);
    Shell trial = shell;
    Eigen::MatrixXd& to = top ? trial.top : trial.base;
    const Eigen::MatrixXd& from = top ? shell.top : shell.base;
    for (int v : vertices) to.row(v) = shell.mid.row(v) + shrink * (from.row(v) - shell.mid.row(v));
    if (accept(trial, vertices)) {
      shell = std::move(trial);
      changed = true;
    } else if (split && group.size() > 1) {
      const auto half = group.begin() + std::ptrdiff_t(group.size() / 2);
      groups.emplace_back(group.begin(), half);
      groups.emplace_back(half, group.end());
    } else {
      refused(group);
    }
  }
  return changed;
}

/// shrink_top: separate_shell_side on the top, with the layer's counts.
std::string shrink_top(Shell& shell, CageLayer& layer, const NestedCageOptions& options) {
  SeparationStats stats;
  const std::string why = separate_shell_side(shell, layer.surface, true, options.shrink,
                                              options.max_shrink_rounds, stats);
  layer.self_intersecting_pairs_before = stats.pairs_before;
  layer.shrink_rounds = stats.rounds;
  if (stats.rounds > 0) layer.verification = stats.verification;
  if (why.empty()) layer.shrunk_pillars = stats.shortened_pillars;
  return why;
}

/// Vertices of the top surface that the next layer's shell would pinch: no direction sees all
/// their faces (extrusion_directions with the shell's tolerance). Zero-length top pillars are
/// left out when they will be filled (make_cage): the next layer is built on the filled cage.
std::vector<int> pinch_points(const Shell& shell, const NestedCageOptions& options) {
  const ExtrusionDirections d =
      extrusion_directions(shell.top, shell.F, options.shell.singularity_tolerance);
  std::vector<int> out;
  for (int v = 0; v < int(d.singular.size()); ++v)
    if (d.singular[std::size_t(v)] && !(options.fill && shell.top.row(v) == shell.mid.row(v)))
      out.push_back(v);
  return out;
}

/// Shortens the top pillars at and around the top surface's pinch points (each pinch point's
/// and its neighbours', kept fraction `shrink` per round), round by round. A round's change is
/// kept only when the prisms it changes stay positive and their top triangles meet neither the
/// layer inside nor, anywhere, the rest of the top surface; when it is refused, the round's
/// pinch points are split in halves and each half tried alone, down to single points, and a
/// single point that cannot be shortened is not tried again. The whole shell is verified at the
/// end (verify_shell: positivity, separation, section, roundtrip); if that fails, the rounds are
/// redone with every round verified whole and not split (a refused round ends the shortening of
/// its points). A shell left with more pinch points than it started with is given back as it
/// was. Returns the pinch points left.
int unpinch_top(Shell& shell, CageLayer& layer, const NestedCageOptions& options,
                bool verify_each) {
  const Shell start = shell;
  const ShellVerification start_verification = layer.verification;
  std::vector<int> pinched = pinch_points(shell, options);
  layer.top_pinch_points_before = int(pinched.size());
  layer.unpinch_rounds = 0;
  if (!verify_each) layer.unpinch_trials = 0;
  if (pinched.empty()) return 0;
  const int nv = int(shell.top.rows());
  std::vector<std::vector<int>> ring(static_cast<std::size_t>(nv));
  for (int f = 0; f < int(shell.F.rows()); ++f)
    for (int c = 0; c < 3; ++c)
      for (int e = 1; e < 3; ++e)
        ring[std::size_t(shell.F(f, c))].push_back(shell.F(f, (c + e) % 3));
  const LocalCheck local(shell, layer.surface);
  std::set<int> stuck;
  int stalled = 0;
  for (int round = 0; round < options.max_shrink_rounds; ++round) {
    std::vector<int> active;
    for (int v : pinched)
      if (!stuck.count(v)) active.push_back(v);
    if (active.empty()) break;
    const bool changed = shorten_in_halves(
        shell, true, options.shrink, active, !verify_each,
        [&](const std::vector<int>& group) {
          std::set<int> vertices(group.begin(), group.end());
          for (int v : group)
            vertices.insert(ring[std::size_t(v)].begin(), ring[std::size_t(v)].end());
          return vertices;
        },
        [&](const Shell& trial, const std::set<int>& vertices) {
          ++layer.unpinch_trials;
          if (!local.ok(trial, vertices) || !side_pairs(trial, true).empty()) return false;
          if (!verify_each) return true;
          const ShellVerification check = verify_shell(trial, layer.surface);
          if (check.valid()) layer.verification = check;
          return check.valid();
        },
        [&](const std::vector<int>& group) { stuck.insert(group.begin(), group.end()); });
    if (!changed) continue;
    ++layer.unpinch_rounds;
    const std::vector<int> left = pinch_points(shell, options);
    stalled = left.size() < pinched.size() ? 0 : stalled + 1;
    pinched = left;
    if (pinched.empty() || stalled == options.max_shrink_rounds / 2) break;
  }
  if (int(pinched.size()) > layer.top_pinch_points_before) {  // worse than before: undo
    shell = start;
    layer.verification = start_verification;
    layer.unpinch_rounds = 0;
    return layer.top_pinch_points_before;
  }
  if (layer.unpinch_rounds > 0 && !verify_each) {
    const ShellVerification check = verify_shell(shell, layer.surface);
    if (!check.valid()) {
      log::info(
          "nested cages: the unpinched shell does not verify; unpinching again with every "
          "change verified");
      shell = start;
      layer.verification = start_verification;
      return unpinch_top(shell, layer, options, true);
    }
    layer.verification = check;
  }
  return int(pinched.size());
}

/// The cage of a finished layer: its shell's top surface, filled around zero-length top pillars
/// (nested_cages.hpp): the union with a regular tetrahedron centred on each, by CGAL's exact
/// corefinement, each result face's parent the top face or the tetrahedron it lies in.
void make_cage(const Shell& shell, CageLayer& layer, const NestedCageOptions& options) {
  layer.cage.V = shell.top;
  layer.cage.F = shell.F;
  layer.cage_face_parent.clear();
  layer.cage_corner_bary.clear();
  layer.cage_face_on_fill.clear();
  layer.filled_points = layer.unfilled_points = 0;
  layer.fill_size = 0;
  std::vector<int> points;
  for (int v = 0; v < int(shell.top.rows()); ++v)
    if (shell.top.row(v) == shell.mid.row(v)) points.push_back(v);
  if (points.empty() || !options.fill) {
    layer.unfilled_points = int(points.size());
    return;
  }
  const int nv = int(shell.top.rows());
  std::vector<std::vector<int>> ring(static_cast<std::size_t>(nv));
  std::vector<int> a_face(static_cast<std::size_t>(nv), -1);
  std::vector<char> at_point(static_cast<std::size_t>(nv), 0);
  for (int p : points) at_point[std::size_t(p)] = 1;
  std::vector<int> away;  // top faces at no filled point
  for (int f = 0; f < int(shell.F.rows()); ++f) {
    bool at = false;
    for (int c = 0; c < 3; ++c) {
      const int v = shell.F(f, c);
      a_face[std::size_t(v)] = f;
      at = at || at_point[std::size_t(v)];
      for (int e = 1; e < 3; ++e) ring[std::size_t(v)].push_back(shell.F(f, (c + e) % 3));
    }
    if (!at) away.push_back(f);
  }
  Eigen::MatrixXd centres(Eigen::Index(points.size()), 3);
  for (std::size_t i = 0; i < points.size(); ++i)
    centres.row(Eigen::Index(i)) = shell.top.row(points[i]);
  Eigen::VectorXd clearance = Eigen::VectorXd::Constant(centres.rows(), HUGE_VAL);
  if (!away.empty()) {
    Eigen::MatrixXi F(Eigen::Index(away.size()), 3);
    for (std::size_t i = 0; i < away.size(); ++i) F.row(Eigen::Index(i)) = shell.F.row(away[i]);
    clearance = check::distances_to_surface(centres, shell.top, F);
  }
  // A regular tetrahedron of circumradius 1 around the origin, faces outward.
  const double s3 = 1 / std::sqrt(3.0);
  const Eigen::Matrix<double, 4, 3> unit =
      (Eigen::Matrix<double, 4, 3>() << 1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1).finished() * s3;
  const int tet_faces[4][3] = {{1, 3, 2}, {0, 2, 3}, {0, 3, 1}, {0, 1, 2}};
  SurfaceMesh tets;
  std::vector<int> filled;  // the point of each tetrahedron
  std::vector<Eigen::RowVector3d> corners;
  std::vector<Eigen::Vector3i> faces;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const int p = points[i];
    double r = clearance[Eigen::Index(i)];
    for (int w : ring[std::size_t(p)]) {
      r = std::min(r, 0.5 * (shell.top.row(w) - shell.top.row(p)).norm());
      const double h = (shell.top.row(w) - shell.mid.row(w)).norm();
      if (h > 0) r = std::min(r, h);
    }
    for (std::size_t j = 0; j < points.size(); ++j)
      if (j != i)
        r = std::min(r, 0.4 * (centres.row(Eigen::Index(j)) - centres.row(Eigen::Index(i))).norm());
    r *= options.fill_size;
    if (!(r > 0) || !std::isfinite(r)) {
      ++layer.unfilled_points;
      continue;
    }
    const int base = int(corners.size());
    for (int c = 0; c < 4; ++c) corners.push_back(shell.top.row(p) + r * unit.row(c));
    for (const auto& t : tet_faces) faces.emplace_back(base + t[0], base + t[1], base + t[2]);
    filled.push_back(p);
    layer.fill_size = std::max(layer.fill_size, r);
  }
  if (filled.empty()) return;
  tets.V.resize(Eigen::Index(corners.size()), 3);
  for (std::size_t i = 0; i < corners.size(); ++i) tets.V.row(Eigen::Index(i)) = corners[i];
  tets.F.resize(Eigen::Index(faces.size()), 3);
  for (std::size_t i = 0; i < faces.size(); ++i) tets.F.row(Eigen::Index(i)) = faces[i];
  const SurfaceMesh top{shell.top, shell.F};
  BooleanResult u;
  try {
    u = corefine_boolean(top, tets, BooleanOperation::union_of);
  } catch (const MeshingError& e) {
    throw MeshingError("nested cages: filling the cage at " + std::to_string(filled.size()) +
                       " points of zero thickness: " + e.what());
  }
  const int nf = u.mesh.num_faces();
  // Every corner's barycentric coordinates in its face's origin (a top face, or a tetrahedron's).
  Eigen::MatrixXd corner_points(3 * Eigen::Index(nf), 3);
  std::vector<int> corner_faces(3 * std::size_t(nf));
  for (int g = 0; g < nf; ++g)
    for (int k = 0; k < 3; ++k) {
      corner_points.row(3 * g + k) = u.mesh.V.row(u.mesh.F(g, k));
      corner_faces[3 * std::size_t(g) + std::size_t(k)] = g;
    }
  const std::vector<OperandPoint> at =
      locate_in_operands(top, tets, u, corner_points, corner_faces);
  layer.cage_face_parent.resize(std::size_t(nf));
  layer.cage_corner_bary.resize(std::size_t(nf));
  layer.cage_face_on_fill.assign(std::size_t(nf), 0);
  for (int g = 0; g < nf; ++g) {
    Eigen::Matrix3d bary;
    int parent;
    if (u.operand[std::size_t(g)] == 0) {
      parent = u.operand_face[std::size_t(g)];
      for (int k = 0; k < 3; ++k) {  // rounding can put a corner just outside its face
        const Eigen::Vector3d w = at[3 * std::size_t(g) + std::size_t(k)].bary.cwiseMax(0.0);
        bary.col(k) = w / w.sum();
      }
    } else {  // on a tetrahedron: every corner at its point
      const int p = filled[std::size_t(u.operand_face[std::size_t(g)] / 4)];
      parent = a_face[std::size_t(p)];
      Eigen::Vector3d w = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k)
        if (shell.F(parent, k) == p) w[k] = 1;
      bary.colwise() = w;
      layer.cage_face_on_fill[std::size_t(g)] = 1;
    }
    layer.cage_face_parent[std::size_t(g)] = parent;
    layer.cage_corner_bary[std::size_t(g)] = bary;
  }
  layer.cage = std::move(u.mesh);
  layer.filled_points = int(filled.size());
}

std::string separate_side(Shell& shell, const SurfaceMesh& surface, bool top, double shrink,
                          int max_rounds, SeparationStats& stats, bool verify_each) {
  const Shell start = shell;
  const LocalCheck local(shell, surface);
  const char* name = top ? "top" : "base";
  auto pairs = side_pairs(shell, top);
  stats = SeparationStats{};
  stats.pairs_before = int(pairs.size());
  std::set<int> shortened;
  std::string why;
  while (!pairs.empty()) {
    if (stats.rounds == max_rounds) {
      why = std::string("the ") + name + " surface still has " + std::to_string(pairs.size()) +
            " self-intersecting face pairs after " + std::to_string(stats.rounds) +
            " shrink rounds";
      break;
    }
    // The round's pairs together; a refused group is split in halves, each tried alone, so a
    // pair whose shortening breaks the shell does not hold back the others.
    std::string refused;
    ShellVerification check;  // of the last change tried
    const bool changed = shorten_in_halves(
        shell, top, shrink, pairs, !verify_each,
        [&](const std::vector<std::pair<int, int>>& group) {
          std::set<int> vertices;
          for (const auto& [f, g] : group)
            for (int c = 0; c < 3; ++c) {
              vertices.insert(shell.F(f, c));
              vertices.insert(shell.F(g, c));
            }
          return vertices;
        },
        [&](const Shell& trial, const std::set<int>& vertices) {
          check = ShellVerification{};
          check.non_positive_faces = -1;  // not verified: the local screen refused it
          if (!local.ok(trial, vertices)) return false;
          if (verify_each) {
            check = verify_shell(trial, surface);
            if (!(check.positive() && check.separated() && check.section())) return false;
            stats.verification = check;  // of the shell kept: no need to verify it again
          }
          shortened.insert(vertices.begin(), vertices.end());
          return true;
        },
        [&](const std::vector<std::pair<int, int>>& group) {
          if (!refused.empty()) return;
          refused =
              std::string("shortening the ") + name + " pillars of " +
              (group.size() == 1 ? "faces " + std::to_string(group[0].first) + " and " +
                                       std::to_string(group[0].second) +
                                       " (a self-intersecting pair of the " + name + " surface)"
                                 : "the faces of " + std::to_string(group.size()) +
                                       " self-intersecting pairs of the " + name + " surface") +
              " breaks the shell (" +
              (check.non_positive_faces < 0
                   ? std::string("a prism around them not positive, or meeting the surface")
                   : std::to_string(check.non_positive_faces) + " prisms not positive, " +
                         std::to_string(check.intersecting_input_faces) + " faces meeting it, " +
                         std::to_string(check.non_section_faces) + " not a section") +
              ")";
        });
    if (!changed) {
      why = refused;
      break;
    }
    ++stats.rounds;
    pairs = side_pairs(shell, top);
  }
  stats.shortened_pillars = int(shortened.size());
  // Changes were kept (also within a round that then stopped) on the local screen alone: the
  // whole shell is verified once, and on failure everything is redone with each change verified.
  if (!verify_each && !shortened.empty()) {
    const ShellVerification check = verify_shell(shell, surface);
    if (!(check.positive() && check.separated() && check.section())) {
      shell = start;
      return separate_side(shell, surface, top, shrink, max_rounds, stats, true);
    }
    stats.verification = check;
  }
  return why;
}

}  // namespace

std::string separate_shell_side(Shell& shell, const SurfaceMesh& surface, bool top, double shrink,
                                int max_rounds, SeparationStats& stats) {
  return separate_side(shell, surface, top, shrink, max_rounds, stats, false);
}

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
    std::optional<std::pair<CageLayer, Shell>> best;  // fewest pinch points left so far
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
      if (why.empty()) {
        if (k + 1 == options.layers || !options.unpinch) break;
        // The next layer's shell is pinched (zero thickness) wherever this cage has a pinch
        // point, so the next cage would touch this one there: unpinch, and when points are left
        // try the next, less coarsened attempt (its middle surface is closer to the layer
        // inside); the attempt with the fewest points left is kept, the coarsest on a tie.
        layer.top_pinch_points = unpinch_top(shell, layer, options, false);
        if (!best || layer.top_pinch_points < best->first.top_pinch_points)
          best.emplace(layer, shell);
        if (layer.top_pinch_points == 0) break;
        log::info("nested cages: layer ", k + 1, ", ", attempts[a].name, ": ",
                  layer.top_pinch_points, " pinch points of the cage left");
        continue;
      }
      log::info("nested cages: layer ", k + 1, ", ", attempts[a].name, ": ", why);
      if (a + 1 == attempts.size()) {
        if (best) break;
        throw MeshingError("nested cages: layer " + std::to_string(k + 1) + ": " + why);
      }
    }
    if (best && (!why.empty() || layer.top_pinch_points > 0)) {
      layer = std::move(best->first);
      shell = std::move(best->second);
    }
    if (layer.shrink_rounds == 0 && layer.unpinch_rounds == 0)
      layer.verification = verify_shell(shell, layer.surface);
    make_cage(shell, layer, options);
    layer.shell = std::move(shell);
    layer.seconds = clock.seconds();
    log::info("nested cages: layer ", k + 1, ": ", layer.cage.num_faces(), " faces, ",
              layer.self_intersecting_pairs_before, " self-intersecting pairs removed in ",
              layer.shrink_rounds, " rounds (", layer.shrunk_pillars, " pillars), pinch points ",
              layer.top_pinch_points_before, " -> ", layer.top_pinch_points, " in ",
              layer.unpinch_rounds, " rounds (", layer.unpinch_trials, " trials), ", layer.seconds,
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
                              int* failures, std::vector<char>* on_fill) {
  CF_VERIFY(k >= 0 && k < int(cages.layers.size()), "cage_to_input: no such layer");
  Eigen::MatrixXd out(Eigen::Index(points.size()), 3);
  std::vector<char> failed(points.size(), 0);
  if (on_fill) on_fill->assign(points.size(), 0);
  tbb::parallel_for(std::size_t(0), points.size(), [&](std::size_t i) {
    MeshPoint p = points[i];
    std::optional<SurfacePoint> s;
    for (int j = k; j >= 0; --j) {
      const CageLayer& layer = cages.layers[std::size_t(j)];
      if (!layer.cage_face_parent.empty()) {  // a filled cage's face to the top surface's
        if (on_fill && layer.cage_face_on_fill[std::size_t(p.face)]) (*on_fill)[i] = 1;
        p.bary = layer.cage_corner_bary[std::size_t(p.face)] * p.bary;
        p.face = layer.cage_face_parent[std::size_t(p.face)];
      }
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
