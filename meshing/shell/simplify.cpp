#include "meshing/shell/simplify.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <unordered_map>

#include "meshing/core/error.hpp"
#include "meshing/core/lagrange_nodes.hpp"
#include "meshing/core/log.hpp"
#include "meshing/editing/refusal_memo.hpp"
#include "meshing/editing/thread_slot.hpp"
#include "meshing/editing/tri_mesh.hpp"
#include "meshing/shell/extrusion_direction.hpp"
#include "meshing/shell/local_sheets.hpp"
#include "meshing/shell/prism_location.hpp"
#include "meshing/shell/prism_positivity.hpp"
#include "meshing/shell/shell_geometry.hpp"
#include "meshing/shell/shell_intersection.hpp"

namespace curvefem::meshing::shell {

namespace {

using editing::Attribute;
using editing::Id;
using editing::OperationRecord;
using editing::TriMesh;

class ShellMesh : public TriMesh {
 public:
  // SimplifyOptions::cancel, checked before every operation.
  const std::atomic<bool>* cancel = nullptr;
  void stop_if_cancelled() const {
    if (cancel && cancel->load(std::memory_order_relaxed)) throw SimplifyCancelled();
  }
  Attribute<Eigen::Vector3d> base{*this, 0, Eigen::Vector3d::Zero()};
  Attribute<Eigen::Vector3d> mid{*this, 0, Eigen::Vector3d::Zero()};
  Attribute<Eigen::Vector3d> top{*this, 0, Eigen::Vector3d::Zero()};
  Attribute<char> singular{*this, 0, 0};
  Attribute<int> input_vertex{*this, 0, -1};
  // The distortion bound of the vertex's pillar where it is below section_cos
  // (SimplifyOptions::section_cos_relative), else negative.
  Attribute<double> lean_bound{*this, 0, -1.0};
  Attribute<std::vector<int>> track{*this, 2, {}};  // input faces touching the prism
  // Distance points located in the prism: input vertex x, or extra point x - #input V.
  Attribute<std::vector<int>> owned{*this, 2, {}};
  // Per owned point, in the same order: (u, v) in the face and the distance to its linear middle
  // triangle there (owned_place), kept with `owned` by rehome_owned.
  Attribute<std::vector<Eigen::Vector3d>> place{*this, 2, {}};
  const std::vector<Eigen::Vector3d>* extra_points = nullptr;
  Eigen::Vector3d distance_point(int x) const {
    const int nv = int(input->V().rows());
    return x < nv ? Eigen::Vector3d(input->V().row(x).transpose()) : (*extra_points)[x - nv];
  }
  bool is_input_vertex(int x) const { return x < int(input->V().rows()); }
  // SimplifyOptions::distance_scale: every distance of point x is measured in units of its own
  // bound, d / scale(x), so every comparison with a bound below stays a comparison of numbers.
  const std::vector<double>* distance_scale = nullptr;
  double scale(int x) const {
    return distance_scale && !distance_scale->empty() ? (*distance_scale)[std::size_t(x)] : 1.0;
  }
  const InputSurfaceIndex* input = nullptr;
  // A locally injective shell (Shell::local_sheets): I2 and I3 against each new prism's local
  // sheet (local_sheets.hpp), reached from the tracks of the prisms it replaces.
  const LocalSheets* sheets = nullptr;
  // Feature chains (SimplifyOptions::collapse_chains). A coarse feature edge carries the input
  // vertices strictly inside it, in order from its end on the smaller input vertex id; they are
  // snapped in `reference` (the same index as `input`, written only by the one-thread chain
  // passes).
  struct ChainEdge {
    bool feature = false;
    std::vector<int> interior;
    bool operator==(const ChainEdge&) const = default;
  };
  Attribute<ChainEdge> chain{*this, 1, {}};
  InputSurfaceIndex* reference = nullptr;
  std::vector<char> chain_vertex;   // input vertex with exactly two input feature edges
  std::vector<char> on_chain;       // input vertex inside a coarse feature edge (snapped)
  bool chain_mode = false;          // collapses are chain collapses (one thread)
  bool chain_full_recheck = false;  // SimplifyOptions::chain_full_recheck
  bool use_chain_grid = true;       // SimplifyOptions::chain_grid
  long long chain_prisms_tested = 0, chain_prisms_live = 0;  // SimplifyStats
  // The boxes of the prisms during a chain pass, by cell id with the corners they were computed
  // for: a chain collapse moves no vertex, so a cell's box is fixed by its corners until the pass
  // ends (cleared then; ids a refused or later operation reuses are recomputed).
  struct CachedBox {
    Cell corners{editing::k_no_id, editing::k_no_id, editing::k_no_id};
    Eigen::AlignedBox3d box;
  };
  std::vector<CachedBox> chain_boxes;
  // The live cells during a chain pass, ascending (built at the pass's first scan; an accepted
  // chain collapse replaces its old cells by its new ones, chain_invariants being the last
  // check): the cell capacity grows with every operation tried, so scanning it visits mostly
  // dead ids.
  std::vector<Id> chain_live;
  bool chain_live_ready = false;
  // A uniform grid over the boxes of the chain pass's prisms (built with chain_live, given the
  // new cells of every accepted chain collapse; entries of removed prisms stay and are filtered
  // out), so a chain collapse finds the prisms near its moved faces without testing the box of
  // every live prism: that scan made the chain pass quadratic (cheese: 10 s of chain collapses,
  // an eighth of it comparing cached boxes). Boxes spanning more than k_chain_grid_span grid
  // cells are kept in a list every query returns.
  static constexpr double k_chain_grid_span = 512;
  double chain_grid_h = 0;
  Eigen::Vector3d chain_grid_lo = Eigen::Vector3d::Zero();
  std::unordered_map<std::int64_t, std::vector<Id>> chain_grid;
  std::vector<Id> chain_grid_big;
  std::array<std::int64_t, 6> chain_grid_range(const Eigen::AlignedBox3d& b) const {
    std::array<std::int64_t, 6> r{};
    for (int k = 0; k < 3; ++k) {
      r[std::size_t(k)] = std::int64_t(std::floor((b.min()[k] - chain_grid_lo[k]) / chain_grid_h));
      r[std::size_t(k + 3)] =
          std::int64_t(std::floor((b.max()[k] - chain_grid_lo[k]) / chain_grid_h));
    }
    return r;
  }
  static double chain_grid_cells(const std::array<std::int64_t, 6>& r) {
    double n = 1;
    for (int k = 0; k < 3; ++k) n *= double(r[std::size_t(k + 3)] - r[std::size_t(k)] + 1);
    return n;
  }
  static std::int64_t chain_grid_key(std::int64_t i, std::int64_t j, std::int64_t k) {
    constexpr std::int64_t bias = std::int64_t(1) << 20, mask = (std::int64_t(1) << 21) - 1;
    return ((i + bias) & mask) | (((j + bias) & mask) << 21) | (((k + bias) & mask) << 42);
  }
  void chain_grid_insert(Id f) {
    const Eigen::AlignedBox3d& b = prism_box(f);
    const auto r = chain_grid_range(b);
    if (b.isEmpty() || !(chain_grid_cells(r) <= k_chain_grid_span)) {
      chain_grid_big.push_back(f);
      return;
    }
    for (std::int64_t i = r[0]; i <= r[3]; ++i)
      for (std::int64_t j = r[1]; j <= r[4]; ++j)
        for (std::int64_t k = r[2]; k <= r[5]; ++k)
          chain_grid[chain_grid_key(i, j, k)].push_back(f);
  }
  // The live prisms (members of chain_live, ascending) whose grid cells meet box b: a superset
  // of those whose boxes meet it.
  std::vector<Id> chain_grid_near(const Eigen::AlignedBox3d& b) const {
    const auto r = chain_grid_range(b);
    if (b.isEmpty() || !(chain_grid_cells(r) <= 64 * k_chain_grid_span)) return chain_live;
    std::vector<Id> out = chain_grid_big;
    for (std::int64_t i = r[0]; i <= r[3]; ++i)
      for (std::int64_t j = r[1]; j <= r[4]; ++j)
        for (std::int64_t k = r[2]; k <= r[5]; ++k)
          if (const auto it = chain_grid.find(chain_grid_key(i, j, k)); it != chain_grid.end())
            out.insert(out.end(), it->second.begin(), it->second.end());
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    out.erase(std::remove_if(out.begin(), out.end(),
                             [&](Id f) {
                               return !std::binary_search(chain_live.begin(), chain_live.end(), f);
                             }),
              out.end());
    return out;
  }
  const Eigen::AlignedBox3d& prism_box(Id f) {
    if (chain_boxes.size() <= std::size_t(f)) chain_boxes.resize(std::size_t(f) + 1);
    CachedBox& c = chain_boxes[std::size_t(f)];
    const Cell& cv = cell(f);
    if (c.corners != cv) {
      c.corners = cv;
      c.box.setEmpty();
      for (Id v : cv) {
        c.box.extend(base[v]);
        c.box.extend(mid[v]);
        c.box.extend(top[v]);
      }
    }
    return c.box;
  }
  struct PendingChain {
    Id w = editing::k_no_id, u = editing::k_no_id;
    int x = -1;
    std::vector<int> path;  // input vertices inside the new edge, from w to u
  } pending;
  double section_cos = 0;
  double pillar_bound(Id v) const { return lean_bound[v] < 0 ? section_cos : lean_bound[v]; }
  // A new vertex between a and b (splits): the smaller of their bounds.
  void inherit_bound(Id v, Id a, Id b) {
    lean_bound.set(v, lean_bound[a] < 0   ? lean_bound[b]
                      : lean_bound[b] < 0 ? lean_bound[a]
                                          : std::min(lean_bound[a], lean_bound[b]));
  }
  double min_reference_area_ratio = 0;
  double max_distance = 0;
  // Curved-aware bound (SimplifyOptions::curved_order): an input vertex not in `strict` may lie
  // up to relaxed_distance from the linear middle triangle when the order-curved_order
  // interpolant of P at its face's lattice nodes passes within curved_distance of it.
  int curved_order = 0;
  double relaxed_distance = 0, curved_distance = 0;
  double curved_min_area_ratio = 0;  // SimplifyOptions::curved_min_area_ratio
  const std::vector<char>* strict = nullptr;
  const decltype(SimplifyOptions::curved_slab_ok)* curved_slab_ok = nullptr;
  double bound_of(int x) const {
    if (curved_order < 2 || !is_input_vertex(x) ||
        (strict && std::size_t(x) < strict->size() && (*strict)[std::size_t(x)]))
      return max_distance;
    return relaxed_distance;
  }
  // Repair mode (SimplifyOptions::repair): a point at distance d beyond max_distance whose bound
  // is max_distance (every point without the curved-aware bound, else a strict input vertex),
  // which the repair splits toward the bound. Never true otherwise (a point beyond its bound is
  // refused by every operation).
  bool repair = false;
  // Repair mode: coarse edges that may be feature edges, as sorted pairs of input vertices (the
  // input's feature edges and the ends of every coarse feature edge a chain collapse made).
  std::set<std::pair<int, int>> feature_pairs;
  bool violating(int x, double d) const {
    if (!repair || !(d > max_distance)) return false;
    if (curved_order < 2) return true;
    return strict && is_input_vertex(x) && std::size_t(x) < strict->size() &&
           (*strict)[std::size_t(x)];
  }
  double max_mips = 0;
  double shape_slack = 0;
  double max_edge_per_thickness = 0;
  std::vector<double> thickness;  // per input vertex (thickness guard)
  // Worst edge length / local thickness over the cell's edges (0 without thickness data).
  double thickness_ratio(Id f) const {
    const Cell& c = cell(f);
    double worst = 0;
    for (int k = 0; k < 3; ++k) {
      const int a = input_vertex[c[k]], b = input_vertex[c[(k + 1) % 3]];
      if (a < 0 || b < 0) continue;  // pinch points
      const double t = std::min(thickness[std::size_t(a)], thickness[std::size_t(b)]);
      if (!(t < HUGE_VAL)) continue;
      worst = std::max(worst, (mid[c[k]] - mid[c[(k + 1) % 3]]).norm() / t);
    }
    return worst;
  }
  bool thickness_ok(const OperationRecord& r) const {
    double before = max_edge_per_thickness, after = 0;
    for (Id f : r.old_cells) before = std::max(before, thickness_ratio(f));
    for (Id f : r.new_cells) after = std::max(after, thickness_ratio(f));
    return after <= before;
  }
  const std::vector<char>* frozen = nullptr;
  enum class Smoothing { rotate, zoom, pan };
  Smoothing smoothing_mode = Smoothing::rotate;
  double max_half_thickness = 0, zoom_ray_fraction = 0.45, zoom_pinned = 0;
  int zoom_pass = 0;                                  // which zoom pass of the round runs
  const std::vector<std::vector<int>>* vf = nullptr;  // input vertex -> incident input faces
  std::array<std::vector<char>, 3> revisit;           // per smoothing kind: vertices to visit next
  // Pan passes (one thread): input vertex -> 1 if a middle vertex sits or sat on it this pass.
  std::vector<char> taken;
  // Split passes: input vertex -> 1 if a middle vertex sits on it. Set from the live vertices
  // before the pass; a split claims its input vertex, which only it can see (the vertex is owned
  // by one of its two locked faces), and gives it back if the invariants refuse the split.
  std::unique_ptr<std::atomic<char>[]> occupied;
  // Why operations were refused, counted while `count_rejections` is set (the collapse passes).
  enum Reject {
    none,
    shape,
    distance,
    positivity,
    intersection,
    section,
    coverage,
    curved,
    thin,
    n_reasons
  };
  std::array<std::atomic<long>, n_reasons> rejections{};
  bool count_rejections = false;
  Reject note(Reject why) {
    if (count_rejections && why != none) rejections[why].fetch_add(1, std::memory_order_relaxed);
    if (why != none) last_reason.local() = why;
    return why;
  }
  editing::PerThread<Reject> last_reason;

  // Refused collapses, remembered while `memo_active` (the collapse rounds). The invariants of a
  // collapse v -> w read only the cells around v and w and the cells across their edges: the
  // positions, pillars, owned points and tracks of those cells, the fixed input and the fixed
  // options (an edge's faces are the cells of two vertices of the closed one-rings of v and w).
  // Every accepted operation stamps the vertices of the cells it creates or changes with a
  // fresh clock value (editing::RefusalMemo), so when no vertex of the closed one-rings of v and w
  // has a stamp later than the refusal, the invariants would refuse again for the same reason and
  // the refusal is replayed without running them: the same rejection counted and the same
  // vertices flagged for smoothing. A chain collapse moves the reference copy, which other
  // prisms read, so it forgets every refusal. Used on one thread only (the memo is not locked).
  struct Refusal {
    bool shape = false;  // Check::shape (else Check::shell)
    Reject why = none;
    std::vector<Id> flagged;  // the vertices of the refused collapse's old cells
  };
  bool memo_active = false;
  editing::RefusalMemo<TriMesh, Refusal> memo{*this};
  bool replay_refusal(Id v, Id w) {
    const Refusal* x = memo.replay(v, w);
    if (!x) return false;
    note(x->why);
    for (Id u : x->flagged)
      if (x->shape)
        revisit[2][u] = 1;
      else
        for (auto& flags : revisit) flags[u] = 1;
    return true;
  }
  void remember_refusal(const OperationRecord& r, bool shape) {
    Refusal x{shape, last_reason.local(), {}};
    for (Id f : r.old_cells)
      for (Id u : cell(f)) x.flagged.push_back(u);
    memo.remember(r.v0, r.v1, x);
  }

  double mips(Id f) const {
    const Cell& c = cell(f);
    return mips(mid[c[0]], mid[c[1]], mid[c[2]]);
  }
  static double mips(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& d) {
    const double area2 = (b - a).cross(d - a).norm();  // twice the area
    if (!(area2 > 0)) return HUGE_VAL;
    return ((b - a).squaredNorm() + (d - b).squaredNorm() + (a - d).squaredNorm()) /
           (std::sqrt(3.0) * area2);
  }
  bool shape_ok(const OperationRecord& r) const {
    double before = max_mips, after = 0;
    for (Id f : r.old_cells) before = std::max(before, mips(f));
    for (Id f : r.new_cells) after = std::max(after, mips(f));
    // The slack only where the removed triangles are already worse than the bound (needles):
    // elsewhere it would let every collapse nudge triangles past the bound itself.
    return after <= (before > max_mips ? before * (1.0 + shape_slack) : before);
  }

  // Prism coordinates of distance point x in face f and its scaled distance to the linear middle
  // triangle there.
  std::optional<double> owned_distance(Id f, int x) const {
    const auto q = owned_place(f, x);
    if (!q) return std::nullopt;
    return (*q)[2];
  }
  // (u, v) of distance point x in face f (rotated to its smallest id) and the distance to the
  // linear middle triangle there, divided by scale(x).
  std::optional<Eigen::Vector3d> owned_place(Id f, int point) const {
    return Placer(*this, f).place(*this, point);
  }
  // owned_place for many points in one face: its prism's locator built once.
  struct Placer {
    std::array<Eigen::Vector3d, 3> m;
    int r = 0;
    PrismLocator locator;
    Placer(const ShellMesh& s, Id f) : Placer(s, s.cell(f)) {}
    std::optional<Eigen::Vector3d> place(const ShellMesh& s, int point) const {
      const Eigen::Vector3d x = s.distance_point(point);
      const auto q = locator.locate(x);
      if (!q) return std::nullopt;
      const Eigen::Vector3d p =
          (1 - q->u - q->v) * m[r] + q->u * m[(r + 1) % 3] + q->v * m[(r + 2) % 3];
      return Eigen::Vector3d(q->u, q->v, (p - x).norm() / s.scale(point));
    }

   private:
    Placer(const ShellMesh& s, const Cell& c)
        : m{s.mid[c[0]], s.mid[c[1]], s.mid[c[2]]},
          r(min_rotation(Eigen::Vector3i{int(c[0]), int(c[1]), int(c[2])})),
          locator(Eigen::Vector3i{int(c[0]), int(c[1]), int(c[2])},
                  {s.base[c[0]], s.base[c[1]], s.base[c[2]]}, m,
                  {s.top[c[0]], s.top[c[1]], s.top[c[2]]}) {}
  };

  // The curved-aware bound. A face is *needed* when it owns a point farther than max_distance
  // from its linear middle triangle; its fully curved patch is the order-curved_order Lagrange
  // triangle through the middle corners and, at every other lattice node, the input point P
  // gives on the node's fiber (what the curved mesher builds at full curving; an edge's nodes
  // depend on its two pillars only). On `cells`, and on the faces across their edges:
  //   - a needed face's patch passes within curved_distance of every point it owns, and its
  //     bottom slab with that patch is valid (curved_slab_ok);
  //   - any other face's bottom slab is valid with the edges it shares with needed faces curved
  //     and the rest of its nodes linear (the mesher's fallback for it, edge_alpha there).
  // A face outside `cells` has the same vertices, pillars and nodes as before, so only the first
  // kind of change (a neighbour becoming needed) can touch it. A fiber missing the input
  // (rounding near a pinch) or a singular corner refuses.
  bool needed(Id f) const {
    for (std::size_t j = 0; j < place[f].size(); ++j) {
      const double d = place[f][j][2];
      if (d > max_distance && !violating(owned[f][j], d)) return true;
    }
    return false;
  }
  // The rotated corners of f.
  std::array<Id, 3> rotated_corners(Id f) const {
    const Cell& c = cell(f);
    const int r = min_rotation(Eigen::Vector3i{int(c[0]), int(c[1]), int(c[2])});
    return {c[r], c[(r + 1) % 3], c[(r + 2) % 3]};
  }
  // The other face on edge (a, b) of f, or k_no_id.
  Id across(Id f, Id a, Id b) const {
    for (Id g : vertex_cells(a))
      if (g != f) {
        const Cell& c = cell(g);
        if (std::find(c.begin(), c.end(), b) != c.end()) return g;
      }
    return editing::k_no_id;
  }
  // The fully curved patch of f: node positions in canonical lattice order of its rotated
  // corners; false when a corner is singular or a fiber misses the input.
  bool patch_nodes(Id f, std::vector<Eigen::Vector3d>& node) const {
    const auto& lattice = lagrange_lattice(CellKind::triangle, curved_order);
    const Cell& c = cell(f);
    const bool type_a = is_type_a(Eigen::Vector3i{int(c[0]), int(c[1]), int(c[2])});
    const std::array<Id, 3> v = rotated_corners(f);
    for (Id u : v)
      if (singular[u]) return false;
    node.assign(lattice.size(), Eigen::Vector3d::Zero());
    for (std::size_t n = 0; n < lattice.size(); ++n) {
      const auto& a = lattice[n];
      const int nonzero = (a[0] > 0) + (a[1] > 0) + (a[2] > 0);
      if (nonzero == 1) {
        node[n] = mid[v[a[0] > 0 ? 0 : a[1] > 0 ? 1 : 2]];
        continue;
      }
      const double w[3] = {double(a[0]) / curved_order, double(a[1]) / curved_order,
                           double(a[2]) / curved_order};
      const auto fiber = fiber_points(type_a, {w[0], w[1], w[2]}, [&](int half, int j) {
        const Id u = v[j % 3];
        return Eigen::Vector3d(half == 0 ? (j >= 3 ? mid[u] : base[u])
                                         : (j >= 3 ? top[u] : mid[u]));
      });
      int g = -1;
      Eigen::Vector3d bary;
      for (const auto& seg : k_fiber_walk)
        if ((g = input->segment_hit(fiber[seg[0]], fiber[seg[1]], bary)) >= 0) break;
      if (g < 0) return false;
      for (int k = 0; k < 3; ++k) node[n] += bary[k] * input->V().row(input->F()(g, k)).transpose();
    }
    return true;
  }
  // Does the patch with these nodes (canonical lattice order) pass within `bound` of every point
  // f owns?
  bool patch_within(Id f, const std::vector<Eigen::Vector3d>& node, double bound) const {
    for (std::size_t j = 0; j < owned[f].size(); ++j) {
      const Eigen::Vector3d& q = place[f][j];
      if (violating(owned[f][j], q[2])) continue;  // being repaired toward the linear bound
      const Eigen::VectorXd phi =
          lagrange_shape_values(CellKind::triangle, curved_order, Eigen::Vector3d(q[0], q[1], 0));
      Eigen::Vector3d p = Eigen::Vector3d::Zero();
      for (std::size_t n = 0; n < node.size(); ++n) p += phi[Eigen::Index(n)] * node[n];
      if (!((p - distance_point(owned[f][j])).norm() / scale(owned[f][j]) <= bound)) return false;
    }
    return true;
  }
  // Is the patch with these nodes (canonical lattice order) parametrically sound: its area
  // element |x_u × x_v| over the order-4k lattice nowhere below curved_min_area_ratio of its
  // largest, nor turned against the plane of its corners? The curved mesher lowers the curving
  // of other faces where it is not (curve_distortion_floor); a needed face cannot be lowered.
  bool patch_shape_ok(const std::vector<Eigen::Vector3d>& node) const {
    return !(curved_min_area_ratio > 0) ||
           triangle_area_element_ratio(curved_order, node) >= curved_min_area_ratio;
  }
  // Is f's bottom slab valid with its nodes `node` where `keep` says so (corners always) and
  // linear elsewhere?
  bool slab_ok(Id f, const std::vector<Eigen::Vector3d>& node,
               const std::function<bool(const std::array<int, 4>&)>& keep) const {
    if (!curved_slab_ok || !*curved_slab_ok) return true;
    const auto& lattice = lagrange_lattice(CellKind::triangle, curved_order);
    const Cell& c = cell(f);
    const bool type_a = is_type_a(Eigen::Vector3i{int(c[0]), int(c[1]), int(c[2])});
    const std::array<Id, 3> v = rotated_corners(f);
    std::array<Eigen::Vector3d, 3> b, mc, t;
    for (int k = 0; k < 3; ++k) {
      b[k] = base[v[k]];
      mc[k] = mid[v[k]];
      t[k] = top[v[k]];
    }
    std::vector<Eigen::Vector3d> d(node.size(), Eigen::Vector3d::Zero());
    for (std::size_t n = 0; n < node.size(); ++n)
      if (keep(lattice[n]))
        d[n] = node[n] - (double(lattice[n][0]) * mc[0] + double(lattice[n][1]) * mc[1] +
                          double(lattice[n][2]) * mc[2]) /
                             double(curved_order);
    return (*curved_slab_ok)(b, mc, t, type_a, d);
  }
  // f's slab with the edges it shares with needed faces curved (need_of: neededness by face).
  bool fallback_slab_ok(Id f, const std::function<bool(Id)>& need_of) const {
    const std::array<Id, 3> v = rotated_corners(f);
    std::array<bool, 3> curved_edge{};  // edge opposite local vertex i (a[i] == 0)
    bool any = false;
    for (int i = 0; i < 3; ++i) {
      const Id g = across(f, v[(i + 1) % 3], v[(i + 2) % 3]);
      if (g == editing::k_no_id) continue;
      curved_edge[std::size_t(i)] = need_of(g);
      any = any || curved_edge[std::size_t(i)];
    }
    if (!any) return true;
    std::vector<Eigen::Vector3d> node;
    if (!patch_nodes(f, node)) return false;
    const auto& lattice = lagrange_lattice(CellKind::triangle, curved_order);
    auto keep = [&](const std::array<int, 4>& a) {
      const int nonzero = (a[0] > 0) + (a[1] > 0) + (a[2] > 0);
      if (nonzero != 2) return false;
      const int zero = a[0] == 0 ? 0 : a[1] == 0 ? 1 : 2;
      return curved_edge[std::size_t(zero)];
    };
    // Within the bound with those edges curved and the rest linear, too.
    std::vector<Eigen::Vector3d> patch = node;
    for (std::size_t n = 0; n < node.size(); ++n)
      if (!keep(lattice[n]) && (lattice[n][0] > 0) + (lattice[n][1] > 0) + (lattice[n][2] > 0) > 1)
        patch[n] = (double(lattice[n][0]) * node[0] + double(lattice[n][1]) * node[1] +
                    double(lattice[n][2]) * node[2]) /
                   double(curved_order);
    return patch_within(f, patch, max_distance) && slab_ok(f, node, keep);
  }
  bool curved_ok(const std::vector<Id>& cells) const {
    if (curved_order < 2) return true;
    std::vector<char> need(cells.size(), 0);
    for (std::size_t i = 0; i < cells.size(); ++i) need[i] = needed(cells[i]);
    if (std::find(need.begin(), need.end(), 1) == need.end()) return true;
    auto need_of = [&](Id g) {
      const auto it = std::find(cells.begin(), cells.end(), g);
      return it != cells.end() ? need[std::size_t(it - cells.begin())] != 0 : needed(g);
    };
    std::vector<Id> outside;
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const Id f = cells[i];
      if (!need[i]) {
        if (!fallback_slab_ok(f, need_of)) return false;
        continue;
      }
      std::vector<Eigen::Vector3d> node;
      if (!patch_nodes(f, node) || !patch_within(f, node, curved_distance) ||
          !patch_shape_ok(node) ||
          !slab_ok(f, node, [](const std::array<int, 4>&) { return true; }))
        return false;
      const std::array<Id, 3> v = rotated_corners(f);
      for (int e = 0; e < 3; ++e) {
        const Id g = across(f, v[e], v[(e + 1) % 3]);
        if (g != editing::k_no_id && std::find(cells.begin(), cells.end(), g) == cells.end())
          outside.push_back(g);
      }
    }
    std::sort(outside.begin(), outside.end());
    outside.erase(std::unique(outside.begin(), outside.end()), outside.end());
    for (Id g : outside)
      if (!needed(g) && !fallback_slab_ok(g, need_of)) return false;
    return true;
  }

  // Re-homes the input vertices owned by the old cells (the changed cells of a smoothing) into
  // the new ones under the bound.
  bool rehome_owned(const OperationRecord& r) {
    const std::vector<Id>& from = r.old_cells.empty() ? r.new_cells : r.old_cells;
    std::vector<int> points;
    double worst = 0;  // repair mode: the farthest violating point of the old cells
    for (Id f : from) {
      points.insert(points.end(), owned[f].begin(), owned[f].end());
      for (std::size_t j = 0; j < place[f].size(); ++j)
        if (violating(owned[f][j], place[f][j][2])) worst = std::max(worst, place[f][j][2]);
    }
    std::vector<std::vector<int>> next(r.new_cells.size());
    std::vector<std::vector<Eigen::Vector3d>> where(r.new_cells.size());
    std::vector<std::optional<Placer>> placers(r.new_cells.size());  // built when first asked
    for (std::size_t j = 0; j < points.size(); ++j) {
      const int x = points[j];
      if (!on_chain.empty() && is_input_vertex(x) && on_chain[std::size_t(x)]) continue;
      bool placed = false;
      for (std::size_t i = 0; i < r.new_cells.size() && !placed; ++i) {
        if (!placers[i]) placers[i].emplace(*this, r.new_cells[i]);
        const auto q = placers[i]->place(*this, x);
        if (!q) continue;
        // Repair mode: a violating point may stay beyond the bound, no farther than the
        // farthest one was.
        if ((*q)[2] > bound_of(x) && !(violating(x, (*q)[2]) && (*q)[2] <= worst)) return false;
        next[i].push_back(x);
        where[i].push_back(*q);
        placed = true;
      }
      if (!placed) return false;
    }
    for (std::size_t i = 0; i < r.new_cells.size(); ++i) {
      owned.set(r.new_cells[i], next[i]);
      place.set(r.new_cells[i], where[i]);
    }
    return true;
  }

  // Input faces touching the 6 canonical split tets of face f; the first invariant a prism half
  // fails, or `none`.
  // A prism's corners and the non-degenerate tets it splits into (both halves).
  struct PrismShape {
    std::array<Eigen::Vector3d, 3> b, m, t;
    std::array<bool, 3> s;
    std::array<double, 3> bound;  // the corners' distortion bounds (pillar_bound)
    Eigen::Vector3i ids;          // input vertices of the corners
    std::vector<std::array<Eigen::Vector3d, 4>> tets;
  };
  // The prism's corners alone (no split tets): enough for I1.
  PrismShape prism_corners(Id f) const {
    const Cell& c = cell(f);
    PrismShape p;
    for (int k = 0; k < 3; ++k) {
      p.b[k] = base[c[k]];
      p.m[k] = mid[c[k]];
      p.t[k] = top[c[k]];
      p.s[k] = singular[c[k]];
      p.bound[k] = pillar_bound(c[k]);
      p.ids[k] = input_vertex[c[k]];
    }
    return p;
  }
  PrismShape prism_shape(Id f) const {
    const Cell& c = cell(f);
    PrismShape p = prism_corners(f);
    const Eigen::Vector3i F{int(c[0]), int(c[1]), int(c[2])};
    const int rot = min_rotation(F);
    for (int half = 0; half < 2; ++half)
      for (const auto& tet : split_tets(is_type_a(F))) {
        std::array<Eigen::Vector3d, 4> q;
        for (int k = 0; k < 4; ++k) {
          const int local = (rot + tet[k] % 3) % 3;
          q[k] = tet[k] < 3 ? (half == 0 ? p.b[local] : p.m[local])
                            : (half == 0 ? p.m[local] : p.t[local]);
        }
        if ((q[1] - q[0]).cross(q[2] - q[0]).dot(q[3] - q[0]) == 0) continue;
        p.tets.push_back(q);
      }
    return p;
  }
  // I2 for one touching face x: a face failing the pillar test rejects the prism only if it is
  // in section contact with a split tet (meets the open tet, or lies in a facet plane and meets
  // the facet's relative interior; the argument is in shell_intersection.cpp).
  bool section_ok(const PrismShape& p, int x) const {
    const auto tri = input->face_triangle(x);
    const Eigen::Vector3d n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
    // The cosine bound on each half-pillar (floating point, as verify_shell measures it), and
    // the exact sign on both, as the verifier checks it.
    auto leans_within = [&](const Eigen::Vector3d& half, double bound) {
      const double d = n.dot(half);
      return d > 0 && d * d >= bound * bound * n.squaredNorm() * half.squaredNorm();
    };
    bool seen = true;
    for (int k = 0; k < 3 && seen; ++k) {
      if (p.s[k]) continue;
      seen = leans_within(p.m[k] - p.b[k], p.bound[k]) &&
             leans_within(p.t[k] - p.m[k], p.bound[k]) &&
             input->face_normal_dot_sign(x, p.b[k], p.m[k]) > 0 &&
             input->face_normal_dot_sign(x, p.m[k], p.t[k]) > 0;
    }
    return seen || !in_section_contact(p, x);
  }
  // Is input face x in section contact with p (meets one of its split tets)?
  bool in_section_contact(const PrismShape& p, int x) const {
    for (const auto& q : p.tets)
      if (input->face_section_contact(x, q)) return true;
    return false;
  }
  // The input faces at the input vertices f owns: each such vertex lies in a closed split tet of
  // f's prism (owned_place located it there with exact predicates), so its faces touch the prism.
  // Vertices on a collapsed feature chain are left out (snapped, the reference copy moved them).
  std::vector<int> faces_at_owned(Id f) const {
    std::vector<int> out;
    if (!vf || !(max_distance > 0) || owned[f].empty() || place[f].size() != owned[f].size())
      return out;
    for (std::size_t j = 0; j < owned[f].size(); ++j) {
      const int x = owned[f][j];
      // Located points only: a resumed shell's points that were not found in their prism are
      // kept with an infinite distance (simplify_shell's set-up).
      if (!std::isfinite(place[f][j][2])) continue;
      if (!is_input_vertex(x) || (!on_chain.empty() && on_chain[std::size_t(x)])) continue;
      out.insert(out.end(), (*vf)[std::size_t(x)].begin(), (*vf)[std::size_t(x)].end());
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }
  // `seeds` (local sheets only; sorted): input faces of the prism's sheet, e.g. the tracks of the
  // prisms it replaces.
  // `positive`: I1 is known to hold (prisms_keep_coverage tests it first for every prism).
  Reject prism_check(Id f, std::vector<int>& touching, const std::vector<int>* seeds = nullptr,
                     bool positive = false) const {
    const PrismShape p = prism_shape(f);
    if (!positive && !shell_face_positive(p.b, p.m, p.t, p.s)) return positivity;  // I1
    if (sheets) return local_prism_check(f, p, touching, seeds ? *seeds : std::vector<int>{});
    if (input->triangle_intersects(p.b, p.s, p.ids) || input->triangle_intersects(p.t, p.s, p.ids))
      return intersection;  // I3
    // I2 for every touching face; the track keeps every touching face.
    touching = input->faces_touching_tets(p.tets, faces_at_owned(f));
    for (int x : touching)
      if (!section_ok(p, x)) return section;
    return touching.empty() ? coverage : none;
  }
  // I2 and I3 of a locally injective shell: against the sheet reached from the first seed that
  // touches the prism (the prism's own sheet; P and the verifier reach the same one from the
  // track's first face, Shell::face_parent), which must hold every seed touching the prism.
  Reject local_prism_check(Id f, const PrismShape& p, std::vector<int>& touching,
                           const std::vector<int>& seeds) const {
    const std::vector<int> all = input->faces_touching_tets(p.tets, faces_at_owned(f));
    auto seed_of = [&](int x) { return std::binary_search(seeds.begin(), seeds.end(), x); };
    const auto first = std::find_if(all.begin(), all.end(), seed_of);
    if (first == all.end()) return coverage;
    Eigen::AlignedBox3d box;
    for (const auto* side : {&p.b, &p.m, &p.t})
      for (const auto& c : *side) box.extend(c);
    const std::vector<int> sheet = sheets->sheet({*first}, box);
    touching.clear();
    std::set_intersection(all.begin(), all.end(), sheet.begin(), sheet.end(),
                          std::back_inserter(touching));
    for (int x : all)
      if (seed_of(x) && !std::binary_search(sheet.begin(), sheet.end(), x)) return section;
    if (input->triangle_intersects(p.b, p.s, p.ids, &sheet) ||
        input->triangle_intersects(p.t, p.s, p.ids, &sheet))
      return intersection;  // I3
    for (int x : touching)
      if (!section_ok(p, x)) return section;
    return none;
  }
  // prism_check of a prism that has not changed since its track was set, while the input faces
  // `moved` (sorted) of the reference copy have: I1 and its verdicts on the other faces stand,
  // so only the moved faces are tested (I3, touching, I2) and the track updated for them. A chain
  // collapse re-checks every prism near the faces it snaps; most of them are such prisms
  // (cheese: 226k of 256k checks, 84% of their time). `face_boxes`: the moved faces' boxes, padded
  // (a snapped face's rounded corners are within an ulp of its exact ones), in their order.
  Reject prism_recheck(Id f, const std::vector<int>& moved,
                       const std::vector<Eigen::AlignedBox3d>& face_boxes,
                       std::vector<int>& touching) const {
    const PrismShape p = prism_shape(f);
    // Boxes first: the exact tests of snapped faces are costly and most pairs are far apart.
    auto box_of = [](const auto& points) {
      Eigen::AlignedBox3d b;
      for (const auto& q : points) b.extend(q);
      return b;
    };
    const Eigen::AlignedBox3d base_box = box_of(p.b), top_box = box_of(p.t);
    std::vector<Eigen::AlignedBox3d> tet_boxes;
    for (const auto& q : p.tets) tet_boxes.push_back(box_of(q));
    for (std::size_t i = 0; i < moved.size(); ++i)
      if ((face_boxes[i].intersects(base_box) &&
           input->triangle_meets_face(p.b, p.s, p.ids, moved[i])) ||
          (face_boxes[i].intersects(top_box) &&
           input->triangle_meets_face(p.t, p.s, p.ids, moved[i])))
        return intersection;  // I3
    touching.clear();
    std::set_difference(track[f].begin(), track[f].end(), moved.begin(), moved.end(),
                        std::back_inserter(touching));
    for (std::size_t i = 0; i < moved.size(); ++i) {
      bool touches = false;
      for (std::size_t j = 0; j < p.tets.size() && !touches; ++j)
        touches =
            face_boxes[i].intersects(tet_boxes[j]) && input->face_touches_tet(moved[i], p.tets[j]);
      if (!touches) continue;
      if (!section_ok(p, moved[i])) return section;
      touching.insert(std::lower_bound(touching.begin(), touching.end(), moved[i]), moved[i]);
    }
    return touching.empty() ? coverage : none;
  }

 protected:
  bool frozen_vertex(Id v) const {
    const int x = input_vertex[v];
    return frozen && x >= 0 && std::size_t(x) < frozen->size() && (*frozen)[x];
  }
  bool collapse_edge_before(const Tuple& t) override {
    stop_if_cancelled();
    if (chain_mode) return chain_before(t);
    if (singular[t.vid] || frozen_vertex(t.vid)) return false;
    return !(memo_active && replay_refusal(t.vid, other_vertex(t)));
  }

  // A chain collapse removes v (on a chain vertex x) along its coarse feature edge to w; v's
  // other coarse feature edge goes to u, and the new edge w–u holds the input vertices of both
  // edges and x.
  bool chain_before(const Tuple& t) {
    const Id v = t.vid, w = other_vertex(t);
    const int x = input_vertex[v];
    if (singular[v] || singular[w] || x < 0 || !chain_vertex[std::size_t(x)] ||
        input_vertex[w] < 0 || !get_edge(chain, t).feature)
      return false;
    std::optional<Tuple> other;
    int n = 0;
    for (const Tuple& e : vertex_edges(v))
      if (get_edge(chain, e).feature) {
        ++n;
        if (other_vertex(e) != w) other = e;
      }
    if (n != 2 || !other) return false;
    const Id u = other_vertex(*other);
    if (singular[u] || input_vertex[u] < 0) return false;
    // w–u already a coarse feature edge (a loop of three): the collapse would merge two chains.
    if (const auto wu = edge_tuple(w, u); wu && get_edge(chain, *wu).feature) return false;
    std::vector<int> wv = get_edge(chain, t).interior, vu = get_edge(chain, *other).interior;
    if (input_vertex[w] > x) std::reverse(wv.begin(), wv.end());
    if (x > input_vertex[u]) std::reverse(vu.begin(), vu.end());
    pending.w = w;
    pending.u = u;
    pending.x = x;
    pending.path = std::move(wv);
    pending.path.push_back(x);
    pending.path.insert(pending.path.end(), vu.begin(), vu.end());
    return true;
  }
  bool collapse_edge_after(const OperationRecord&) override {
    if (!chain_mode) return true;
    const auto e = edge_tuple(pending.w, pending.u);
    if (!e) return false;
    std::vector<int> interior = pending.path;
    if (input_vertex[pending.w] > input_vertex[pending.u])
      std::reverse(interior.begin(), interior.end());
    set_edge(chain, *e, ChainEdge{true, std::move(interior)});
    return true;
  }

  // I1–I3 for each of `cells` (their tracks updated), and every input face in `old_union` (the
  // tracks of the prisms they replace) still touched by one of them; the first failure noted.
  // With `moved` (and their boxes), the cells from index `changed` on have not changed and only
  // the moved input faces are tested for them (prism_recheck).
  bool prisms_keep_coverage(const std::vector<Id>& cells, std::vector<int> old_union,
                            std::size_t changed = SIZE_MAX, const std::vector<int>* moved = nullptr,
                            const std::vector<Eigen::AlignedBox3d>* moved_boxes = nullptr) {
    std::vector<int> new_union, touching;
    auto sort_old_union = [&] {
      std::sort(old_union.begin(), old_union.end());
      old_union.erase(std::unique(old_union.begin(), old_union.end()), old_union.end());
    };
    if (sheets) sort_old_union();  // the local checks' seeds; else only once every cell passed
    // I1 of every changed prism before the costlier I2 and I3 of any: most refused thickness
    // growths fail I1 on one prism of the star (cheese: 8,657 of 8,940), after the others had
    // passed their contact tests. (The refusal is then counted as positivity.)
    for (std::size_t i = 0; i < std::min(changed, cells.size()); ++i) {
      const PrismShape p = prism_corners(cells[i]);
      if (!shell_face_positive(p.b, p.m, p.t, p.s)) {
        note(positivity);
        return false;
      }
    }
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const Id f = cells[i];
      const Reject why = moved && i >= changed ? prism_recheck(f, *moved, *moved_boxes, touching)
                                               : prism_check(f, touching, &old_union, true);
      if (note(why) != none) return false;
      track.set(f, touching);
      new_union.insert(new_union.end(), touching.begin(), touching.end());
    }
    if (!sheets) sort_old_union();
    std::sort(new_union.begin(), new_union.end());
    new_union.erase(std::unique(new_union.begin(), new_union.end()), new_union.end());
    if (!std::includes(new_union.begin(), new_union.end(), old_union.begin(), old_union.end())) {
      note(coverage);
      return false;
    }
    return true;
  }

  // The chain collapse's invariants: the triangle shape; the chain's input vertices snapped by
  // arc length onto the straight edge w–u, each within the distance bound of its snapped point;
  // no reference face made degenerate; the owned points re-homed; every prism of w and u (the
  // only ones next to the moved reference faces' chain) passing I1–I3 on the reference copy,
  // with the coverage kept. The snaps are undone if anything fails.
  bool chain_invariants(const OperationRecord& r) {
    if (max_mips > 0 && !shape_ok(r)) {
      note(shape);
      return false;
    }
    const int iw = input_vertex[pending.w], iu = input_vertex[pending.u];
    const Eigen::Vector3d W = input->V().row(iw).transpose(), U = input->V().row(iu).transpose();
    std::vector<double> at;
    double total = 0;
    Eigen::Vector3d prev = W;
    for (int y : pending.path) {
      const Eigen::Vector3d q = input->V().row(y).transpose();
      total += (q - prev).norm();
      at.push_back(total);
      prev = q;
    }
    total += (U - prev).norm();
    if (!(total > 0)) return false;
    double last = 0;
    for (double& a : at) {
      a /= total;
      if (!(a > last && a < 1)) return false;
      last = a;
    }
    for (std::size_t i = 0; i < at.size(); ++i) {
      const Eigen::Vector3d q = W + at[i] * (U - W);
      if ((input->V().row(pending.path[i]).transpose() - q).norm() / scale(pending.path[i]) >
          max_distance) {
        note(distance);
        return false;
      }
    }
    std::vector<std::pair<int, std::optional<SnappedVertex>>> saved;
    for (std::size_t i = 0; i < at.size(); ++i) {
      const int y = pending.path[i];
      const SnappedVertex* old = reference->snap_of(y);
      saved.emplace_back(y, old ? std::optional<SnappedVertex>(*old) : std::nullopt);
      reference->snap_vertex({y, iw, iu, at[i]});
    }
    on_chain[std::size_t(pending.x)] = 1;
    const bool ok = chain_geometry_ok(r);
    if (ok && chain_live_ready) {  // the last check: the collapse is accepted
      for (Id f : r.old_cells) {
        const auto at = std::lower_bound(chain_live.begin(), chain_live.end(), f);
        if (at != chain_live.end() && *at == f) chain_live.erase(at);
      }
      for (Id f : r.new_cells) {
        const auto at = std::lower_bound(chain_live.begin(), chain_live.end(), f);
        if (at == chain_live.end() || *at != f) chain_live.insert(at, f);
        if (chain_grid_h > 0) chain_grid_insert(f);
      }
    }
    if (!ok) {
      for (auto it = saved.rbegin(); it != saved.rend(); ++it)
        if (it->second)
          reference->snap_vertex(*it->second);
        else
          reference->unsnap_vertex(it->first);
      on_chain[std::size_t(pending.x)] = 0;
    }
    return ok;
  }
  bool chain_geometry_ok(const OperationRecord& r) {
    std::vector<int> moved;
    for (int y : pending.path) moved.insert(moved.end(), (*vf)[y].begin(), (*vf)[y].end());
    std::sort(moved.begin(), moved.end());
    moved.erase(std::unique(moved.begin(), moved.end()), moved.end());
    // The reference copy stays embedded (the section argument needs a closed embedded
    // surface; snapping can fold faces next to the chain over their neighbours).
    // Nor collapses a face: a snapped vertex and a rounded one (a bisection point of a refined
    // input) collinear up to rounding with the chain make a face of the copy that is not
    // exactly degenerate but 1e-14 of its input face's area (CGAL's part.off, shape-refined: a
    // 3e-3-high cap under a feature chain; P then sent the chain vertex 3.1e-3 away).
    for (int g : moved)
      if (reference->face_degenerate(g) || reference->face_self_intersects(g) ||
          reference->face_area_ratio(g) < min_reference_area_ratio) {
        note(section);
        return false;
      }
    if (max_distance > 0 && !rehome_owned(r)) {
      note(distance);
      return false;
    }
    std::vector<Id> cells = r.new_cells;
    std::vector<int> old_union;
    for (Id f : r.old_cells) old_union.insert(old_union.end(), track[f].begin(), track[f].end());
    // Every other live prism whose box meets a moved reference face is checked again too (the
    // faces move by up to the bound, possibly into prisms away from w and u). One thread runs
    // chain collapses, so reading any prism is safe.
    std::vector<Eigen::AlignedBox3d> boxes;
    Eigen::AlignedBox3d all;
    for (int g : moved) {
      Eigen::AlignedBox3d b;
      for (const auto& p : input->face_triangle(g)) b.extend(p);
      const double pad = 1e-12 * (b.max().cwiseAbs().maxCoeff() + b.min().cwiseAbs().maxCoeff());
      b.min().array() -= pad;  // the rounded corners are within an ulp of the exact ones
      b.max().array() += pad;
      boxes.push_back(b);
      all.extend(b);
    }
    if (!chain_live_ready) {
      chain_live.clear();
      for (Id f = 0; f < Id(cell_capacity()); ++f)
        if (!is_cell_removed(f)) chain_live.push_back(f);
      chain_live_ready = true;
      // The grid's spacing: the median largest extent of the live prisms' boxes.
      std::vector<double> extent;
      Eigen::AlignedBox3d span;
      for (Id f : chain_live) {
        const Eigen::AlignedBox3d& b = prism_box(f);
        extent.push_back((b.max() - b.min()).maxCoeff());
        span.extend(b);
      }
      chain_grid.clear();
      chain_grid_big.clear();
      chain_grid_h = 0;
      if (use_chain_grid && !extent.empty()) {
        std::nth_element(extent.begin(), extent.begin() + std::ptrdiff_t(extent.size() / 2),
                         extent.end());
        chain_grid_h = extent[extent.size() / 2];
        chain_grid_lo = span.min();
      }
      if (chain_grid_h > 0)
        for (Id f : chain_live) chain_grid_insert(f);
    }
    // The prisms to test: the live ones near `all` (every live one without a grid).
    const std::vector<Id> near_all = chain_grid_h > 0 ? chain_grid_near(all) : chain_live;
    chain_prisms_tested += (long long)(near_all.size());
    chain_prisms_live += (long long)(chain_live.size());
    for (Id f : near_all) {
      // The operation's own old cells are removed now but come back if it is refused.
      if (is_cell_removed(f)) continue;
      const Eigen::AlignedBox3d& prism = prism_box(f);
      if (!prism.intersects(all) || std::find(cells.begin(), cells.end(), f) != cells.end())
        continue;
      bool near = false;
      for (const auto& b : boxes) near = near || prism.intersects(b);
      if (!near) continue;
      cells.push_back(f);
      old_union.insert(old_union.end(), track[f].begin(), track[f].end());
    }
    if (!prisms_keep_coverage(cells, std::move(old_union),
                              chain_full_recheck ? cells.size() : r.new_cells.size(), &moved,
                              &boxes))
      return false;
    if (!curved_ok(cells)) {
      note(curved);
      return false;
    }
    return true;
  }

  // Flips: no singular vertex in the two faces (a face may hold one at most), never a feature
  // edge, and a strictly lower worst MIPS. With feature chains the coarse feature edges are
  // marked (`chain`), so an edge between two frozen vertices that is not one of them may flip:
  // that removes the caps whose three corners lie on one chain (three consecutive chain vertices
  // of a short chain segment, a sliver of 0.07° on abc_00000008). Without chains a feature edge is
  // only known as an edge between two frozen vertices, and none of those flips.
  bool swap_edge_before(const Tuple& t) override {
    stop_if_cancelled();
    const Id a = t.vid, b = other_vertex(t);
    if (chain_vertex.empty() ? frozen_vertex(a) && frozen_vertex(b) : get_edge(chain, t).feature)
      return false;
    for (Id f : vertex_cells(a))
      for (Id v : cell(f))
        if (singular[v]) return false;
    for (Id f : vertex_cells(b))
      for (Id v : cell(f))
        if (singular[v]) return false;
    return true;
  }
  bool swap_edge_after(const OperationRecord& r) override {
    double before = 0, after = 0;
    for (Id f : r.old_cells) before = std::max(before, mips(f));
    for (Id f : r.new_cells) after = std::max(after, mips(f));
    return after < (1 - 1e-3) * before;
  }

  // Split (thesis §4.3.2, Fig. 4.12; with the boundary map in mind, §5.3: "the new vertex is
  // queried among the pre-image of the current edge, as an existing vertex of the input"): the
  // new middle vertex sits on the input vertex owned by the two old prisms that is nearest to the
  // edge's midpoint, within a quarter of the edge length; its pillar is the normalized sum of the
  // two end pillars' directions, each half as long as the shorter of the two ends' halves.
  // Accepted only if the worst MIPS of the new middle triangles is strictly below that of the
  // old ones (a split is a shape repair here) and the invariants hold.
  bool split_edge_before(const Tuple& t) override {
    stop_if_cancelled();
    return occupied && !singular[t.vid] && !singular[other_vertex(t)] &&
           !get_edge(chain, t).feature && !(repair && repair_feature_edge(t));
  }
  bool split_edge_after(const OperationRecord& r) override {
    if (repair) return repair_split_after(r);
    const Id a = r.v0, b = r.v1, v = r.new_vertex;
    const Eigen::Vector3d ma = mid[a], mb = mid[b], centre = 0.5 * (ma + mb);
    int best = -1;
    double best_d = 0.25 * (mb - ma).norm();
    for (Id f : r.old_cells)
      for (int x : owned[f]) {
        if (!is_input_vertex(x) || occupied[std::size_t(x)].load(std::memory_order_relaxed))
          continue;
        const double d = (input->V().row(x).transpose() - centre).norm();
        if (d < best_d) {
          best_d = d;
          best = x;
        }
      }
    if (best < 0) return false;
    const Eigen::Vector3d p = input->V().row(best).transpose();
    double before = 0, after = 0;
    for (Id f : r.old_cells) before = std::max(before, mips(f));
    for (Id f : r.new_cells) {
      const Cell& c = cell(f);
      std::array<Eigen::Vector3d, 3> q;
      for (int j = 0; j < 3; ++j) q[j] = c[j] == v ? p : Eigen::Vector3d(mid[c[j]]);
      after = std::max(after, mips(q[0], q[1], q[2]));
    }
    if (!(after < (1 - 1e-3) * before)) return false;
    const Eigen::Vector3d da = top[a] - base[a], db = top[b] - base[b];
    if (!(da.norm() > 0) || !(db.norm() > 0)) return false;
    const Eigen::Vector3d d = (da.normalized() + db.normalized()).normalized();
    if (!std::isfinite(d.squaredNorm())) return false;
    const double lt = std::min((top[a] - ma).norm(), (top[b] - mb).norm());
    const double lb = std::min((ma - base[a]).norm(), (mb - base[b]).norm());
    mid.set(v, p);
    top.set(v, p + lt * d);
    base.set(v, p - lb * d);
    singular.set(v, 0);
    inherit_bound(v, a, b);
    input_vertex.set(v, best);
    occupied[std::size_t(best)].store(1, std::memory_order_relaxed);
    return true;
  }
  bool repair_feature_edge(const Tuple& t) const {
    const int a = input_vertex[t.vid], b = input_vertex[other_vertex(t)];
    return a >= 0 && b >= 0 && feature_pairs.count({std::min(a, b), std::max(a, b)}) > 0;
  }
  // A repair split (SimplifyOptions::repair) is not a shape repair: check() applies the shape
  // guard (max_mips) instead of asking for a better triangle. The long, tilted pillars of a
  // coarse shell can leave a new prism inverted, so it tries the unoccupied input vertices its
  // two prisms own within a third of the edge length of the midpoint (nearest first, at most 8,
  // none snapped onto a feature chain), then their violating points, and, for each, the pillar
  // directions: the ends' mean, the
  // input's vertex normal there, the new middle triangles' mean normal; for each, halves of the
  // ends' shorter length times 1, 1/2, ... 1/8. The first whose new prisms all pass the exact
  // positivity test (I1, which the invariants check again) and keeps the triangle shape, the
  // thickness guard and the owned points' bounds is taken.
  bool repair_split_after(const OperationRecord& r) {
    const Id a = r.v0, b = r.v1, v = r.new_vertex;
    const Eigen::Vector3d ma = mid[a], mb = mid[b], centre = 0.5 * (ma + mb);
    const double radius = (mb - ma).norm() / 3;
    // One pass over the owned points, each ranked by its distance to the midpoint into: near the
    // midpoint (at most 8); the violating points farther away (on them, their distance becomes
    // 0); any other input vertex farther away (up to 24 candidates in all). Only unoccupied input
    // vertices not snapped onto a feature chain.
    std::vector<std::pair<double, int>> near, far, rest;
    for (Id f : r.old_cells)
      for (std::size_t j = 0; j < owned[f].size(); ++j) {
        const int x = owned[f][j];
        if (!is_input_vertex(x) || occupied[std::size_t(x)].load(std::memory_order_relaxed) ||
            reference->snap_of(x))
          continue;
        const double d = (input->V().row(x).transpose() - centre).norm();
        auto& list = d < radius ? near : violating(x, place[f][j][2]) ? far : rest;
        list.emplace_back(d, x);
      }
    std::sort(near.begin(), near.end());
    std::sort(far.begin(), far.end());
    std::sort(rest.begin(), rest.end());
    if (near.size() > 8) near.resize(8);
    std::vector<std::pair<double, int>> candidates = std::move(near);
    candidates.insert(candidates.end(), far.begin(), far.end());
    for (std::size_t i = 0; i < rest.size() && candidates.size() < 24; ++i)
      candidates.push_back(rest[i]);
    const Eigen::Vector3d da = top[a] - base[a], db = top[b] - base[b];
    if (!(da.norm() > 0) || !(db.norm() > 0)) return false;
    const double lt = std::min((top[a] - ma).norm(), (top[b] - mb).norm());
    const double lb = std::min((ma - base[a]).norm(), (mb - base[b]).norm());
    for (const auto& [dist, x] : candidates) {
      const Eigen::Vector3d p = input->V().row(x).transpose();
      auto positive = [&](const Eigen::Vector3d& dir, double scale) {
        for (Id f : r.new_cells) {
          const Cell& c = cell(f);
          std::array<Eigen::Vector3d, 3> pb, pm, pt;
          std::array<bool, 3> ps;
          for (int j = 0; j < 3; ++j) {
            const bool here = c[j] == v;
            pm[j] = here ? p : Eigen::Vector3d(mid[c[j]]);
            pb[j] = here ? Eigen::Vector3d(p - scale * lb * dir) : Eigen::Vector3d(base[c[j]]);
            pt[j] = here ? Eigen::Vector3d(p + scale * lt * dir) : Eigen::Vector3d(top[c[j]]);
            ps[j] = !here && singular[c[j]];
          }
          if (!shell_face_positive(pb, pm, pt, ps)) return false;
        }
        return true;
      };
      std::vector<Eigen::Vector3d> dirs{da.normalized() + db.normalized()};
      Eigen::Vector3d n = Eigen::Vector3d::Zero(), t = Eigen::Vector3d::Zero();
      for (int g : (*vf)[std::size_t(x)]) {
        const auto tri = input->face_triangle(g);
        n += (tri[1] - tri[0]).cross(tri[2] - tri[0]);
      }
      for (Id f : r.new_cells) {
        const Cell& c = cell(f);
        std::array<Eigen::Vector3d, 3> q;
        for (int j = 0; j < 3; ++j) q[j] = c[j] == v ? p : Eigen::Vector3d(mid[c[j]]);
        t += (q[1] - q[0]).cross(q[2] - q[0]).normalized();
      }
      dirs.push_back(n);
      dirs.push_back(t);
      for (Eigen::Vector3d dir : dirs) {
        if (!(dir.norm() > 0) || !std::isfinite(dir.squaredNorm())) continue;
        dir.normalize();
        for (double scale = 1; scale >= 1.0 / 8; scale /= 2) {
          if (!positive(dir, scale)) continue;
          mid.set(v, p);
          top.set(v, p + scale * lt * dir);
          base.set(v, p - scale * lb * dir);
          singular.set(v, 0);
          inherit_bound(v, a, b);
          input_vertex.set(v, x);
          // The guards the invariants apply first, so that a refused choice tries the next one.
          if (max_mips > 0 && !shape_ok(r)) break;
          if (max_edge_per_thickness > 0 && !thickness_ok(r)) break;
          if (!rehome_owned(r)) continue;
          occupied[std::size_t(x)].store(1, std::memory_order_relaxed);
          return true;
        }
      }
    }
    return false;
  }

  // Smoothing is one of two moves of vertex r.v0's pillar, chosen by `smoothing_mode`.
  bool smooth_before(const Tuple& t) override {
    stop_if_cancelled();
    return !singular[t.vid];
  }
  bool smooth_after(const OperationRecord& r) override {
    const Id v = r.v0;
    const Eigen::Vector3d m = mid[v];
    const Eigen::Vector3d up = top[v] - m, down = m - base[v];
    const double lt = up.norm(), lb = down.norm();
    if (!(lt > 0) || !(lb > 0)) return false;
    const Eigen::Vector3d d = up / lt;
    if (smoothing_mode == Smoothing::pan) {
      // Move the middle vertex to a neighbouring input vertex (the boundary map needs coarse
      // corners on input vertices) where the star's worst triangle is better shaped; pillar
      // direction and lengths kept. The invariants re-check the star's prisms, re-home the owned
      // input vertices under the distance bound and keep the tracked faces covered.
      const int x = input_vertex[v];
      if (x < 0 || frozen_vertex(v) || taken.empty()) return false;
      double now = 0;
      for (Id f : r.new_cells) now = std::max(now, mips(f));
      double best = (1 - 1e-2) * now;
      int best_y = -1;
      for (int g : (*vf)[x])
        for (int k = 0; k < 3; ++k) {
          const int y = input->F()(g, k);
          if (y == x || taken[y]) continue;
          const Eigen::Vector3d p = input->V().row(y).transpose();
          double worst = 0;
          for (Id f : r.new_cells) {
            const Cell& c = cell(f);
            std::array<Eigen::Vector3d, 3> q;
            for (int j = 0; j < 3; ++j) q[j] = c[j] == v ? p : Eigen::Vector3d(mid[c[j]]);
            worst = std::max(worst, mips(q[0], q[1], q[2]));
          }
          if (worst < best) {
            best = worst;
            best_y = y;
          }
        }
      if (best_y < 0) return false;
      const Eigen::Vector3d p = input->V().row(best_y).transpose();
      taken[best_y] = 1;  // conservative: stays taken even if the invariants refuse the move
      mid.set(v, p);
      top.set(v, p + lt * d);
      base.set(v, p - lb * d);
      input_vertex.set(v, best_y);
      return true;
    }
    if (smoothing_mode == Smoothing::rotate) {
      std::vector<Eigen::Vector3d> normals;
      for (Id f : r.new_cells) {
        const Cell& c = cell(f);
        const Eigen::Vector3d n = (mid[c[1]] - mid[c[0]]).cross(mid[c[2]] - mid[c[0]]);
        if (!(n.norm() > 0)) return false;
        normals.push_back(n.normalized());
        for (int x : track[f]) {
          const auto tri = input->face_triangle(x);
          const Eigen::Vector3d nx = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
          if (nx.norm() > 0) normals.push_back(nx.normalized());
        }
      }
      std::sort(normals.begin(), normals.end(), [](const auto& x, const auto& y) {
        return std::lexicographical_compare(x.data(), x.data() + 3, y.data(), y.data() + 3);
      });
      normals.erase(std::unique(normals.begin(), normals.end()), normals.end());
      // The floating-point active set only: the exact fallback (CGAL's QP on Gmpzf) can take
      // minutes on a nearly degenerate star, and the direction needs no proof here — the
      // invariants check the rotated prisms exactly.
      Eigen::Vector3d e;
      if (detail::most_visible_direction_fast(normals, 1e-2, e) != detail::FastOutcome::direction)
        return false;
      if (e.dot(d) > std::cos(1e-3)) return false;  // already there
      // A turned pillar keeps its lengths, within the growth's ray cap along the new direction:
      // a half-pillar grown where its ray missed the input may now aim at a nearby part of it,
      // whose own shell may grow toward it (the invariants only keep base and top off the input).
      double nt = lt, nb = lb;
      const int x = input_vertex[v];
      if (max_half_thickness > 0 && x >= 0) {
        nt = std::min(nt, zoom_ray_fraction * input->ray_distance(m, e, (*vf)[x]));
        nb = std::min(nb, zoom_ray_fraction * input->ray_distance(m, -e, (*vf)[x]));
      }
      top.set(v, m + nt * e);
      base.set(v, m - nb * e);
      return true;
    }
    // Zoom: double both halves within the caps.
    const int x = input_vertex[v];
    if (x < 0) return false;
    // The extra passes of a round only for pillars pinned thin: shorter than zoom_pinned × the
    // mean length of the star's edges. Elsewhere a shell grown faster than the faces coarsen
    // turns small pillar differences into inverted prisms (spot, bunny at K = 3: 356 -> 526 and
    // 590 -> 716 coarse faces with four passes for every pillar).
    if (zoom_pass > 0) {
      double sum = 0;
      int n = 0;
      for (Id f : r.new_cells)
        for (Id u : cell(f))
          if (u != v) sum += (mid[u] - m).norm(), ++n;
      if (!(n > 0) || !(std::max(lt, lb) < zoom_pinned * sum / n)) {
        revisit[1][v] = 1;  // not pinned: keep its visit for the next round's first pass
        return false;
      }
    }
    const double cap_t =
        std::min(max_half_thickness, zoom_ray_fraction * input->ray_distance(m, d, (*vf)[x]));
    const double cap_b =
        std::min(max_half_thickness, zoom_ray_fraction * input->ray_distance(m, -d, (*vf)[x]));
    const double nt = std::min(2 * lt, cap_t), nb = std::min(2 * lb, cap_b);
    if (!(nt > 1.01 * lt) && !(nb > 1.01 * lb)) return false;
    top.set(v, m + std::max(nt, lt) * d);
    base.set(v, m - std::max(nb, lb) * d);
    return true;
  }

  // Smoothing cannot change the middle surface's shape, so only the other failures ask for it.
  enum class Check { ok, shape, shell };
  Check check(const OperationRecord& r) {
    // The distance bound first: a few orientation tests per input vertex, far cheaper than the
    // prism checks, and the reason most collapses fail once the surface is coarse.
    if (max_mips > 0 && !r.old_cells.empty() && !shape_ok(r)) {
      note(shape);
      return Check::shape;
    }
    if (max_edge_per_thickness > 0 && !r.old_cells.empty() && !thickness_ok(r)) {
      note(thin);
      return Check::shape;
    }
    if (max_distance > 0 && !rehome_owned(r)) {
      note(distance);
      return Check::shell;
    }
    std::vector<int> old_union;
    for (Id f : r.old_cells.empty() ? r.new_cells : r.old_cells)
      old_union.insert(old_union.end(), track[f].begin(), track[f].end());
    if (!prisms_keep_coverage(r.new_cells, std::move(old_union))) return Check::shell;
    if (!curved_ok(r.new_cells)) {
      note(curved);
      return Check::shell;
    }
    return Check::ok;
  }
  bool invariants(const OperationRecord& r) override {
    const Check c = chain_mode ? (chain_invariants(r) ? Check::ok : Check::shell) : check(r);
    if (c != Check::ok && r.new_vertex != editing::k_no_id && occupied) {
      const int x = input_vertex[r.new_vertex];
      if (x >= 0) occupied[std::size_t(x)].store(0, std::memory_order_relaxed);
    }
    // Worth a smoothing visit: the vertices whose prisms changed, and those of a collapse or
    // flip the shell refused (a thicker or re-aimed pillar may let it through next round). They
    // are locked by this operation, so each flag is written by one thread.
    const std::vector<Id>* cells = c == Check::ok                              ? &r.new_cells
                                   : c == Check::shell && !r.old_cells.empty() ? &r.old_cells
                                                                               : nullptr;
    if (cells)
      for (Id f : *cells)
        for (Id v : cell(f))
          for (auto& flags : revisit) flags[v] = 1;
    // A collapse refused for the triangle shape asks for a pan (better-shaped stars).
    if (c == Check::shape)
      for (Id f : r.old_cells)
        for (Id v : cell(f)) revisit[2][v] = 1;
    if (c == Check::ok) {
      memo.stamp({&r.new_cells, &r.old_cells, &r.affected_cells});
      if (chain_mode) memo.forget_all();
    } else if (memo_active && !chain_mode && r.v0 != editing::k_no_id && r.v1 != editing::k_no_id &&
               !r.old_cells.empty()) {
      remember_refusal(r, c == Check::shape);
    }
    return c == Check::ok;
  }
};

}  // namespace

Shell simplify_shell(const Shell& shell, const SurfaceMesh& input, const SimplifyOptions& options,
                     SimplifyStats& stats) {
  const auto t0 = std::chrono::steady_clock::now();
  InputSurfaceIndex index(input.V, input.F, shell.reference);
  ShellMesh m;
  m.input = &index;
  m.reference = &index;
  m.section_cos = options.section_cos;
  m.min_reference_area_ratio = options.min_reference_area_ratio;
  m.chain_full_recheck = options.chain_full_recheck;
  m.use_chain_grid = options.chain_grid;
  m.max_distance = options.max_distance;
  m.cancel = options.cancel;
  if (!options.distance_scale.empty()) {
    const std::size_t np = std::size_t(input.num_vertices()) + options.extra_points.size();
    if (options.distance_scale.size() != np)
      throw MeshingError("simplify: distance_scale has " +
                         std::to_string(options.distance_scale.size()) + " entries for " +
                         std::to_string(np) + " distance points");
    for (std::size_t x = 0; x < np; ++x)
      if (!(options.distance_scale[x] > 0 && options.distance_scale[x] <= 1))
        throw MeshingError("simplify: distance_scale of point " + std::to_string(x) +
                           " is not in (0, 1]");
    m.distance_scale = &options.distance_scale;
  }
  m.max_mips = options.max_mips;
  if (!(options.shape_slack >= 0 && options.shape_slack < 1))
    throw MeshingError("simplify: shape_slack must be in [0, 1)");
  m.shape_slack = options.shape_slack;
  if (options.curved_order >= 2) {
    if (!(options.max_distance > 0))
      throw MeshingError(
          "simplify: the curved-aware bound needs the distance bound (max_distance)");
    if (options.curved_order > k_max_order)
      throw MeshingError("simplify: curved_order " + std::to_string(options.curved_order) +
                         " is not in 2.." + std::to_string(k_max_order));
    m.curved_order = options.curved_order;
    m.relaxed_distance = std::max(options.relaxed_distance, options.max_distance);
    m.curved_distance =
        options.curved_distance > 0 ? options.curved_distance : options.max_distance;
    m.curved_min_area_ratio = options.curved_min_area_ratio;
    if (!options.strict_input_vertices.empty()) m.strict = &options.strict_input_vertices;
    if (options.curved_slab_ok) m.curved_slab_ok = &options.curved_slab_ok;
  }
  if (!options.frozen_input_vertices.empty()) m.frozen = &options.frozen_input_vertices;
  const int nv = int(shell.mid.rows()), nf = int(shell.F.rows());
  std::vector<TriMesh::Cell> cells(nf);
  for (int f = 0; f < nf; ++f) cells[f] = {Id(shell.F(f, 0)), Id(shell.F(f, 1)), Id(shell.F(f, 2))};
  m.initialize(std::size_t(nv), cells);
  for (int v = 0; v < nv; ++v) {
    m.base.set(Id(v), shell.base.row(v).transpose());
    m.mid.set(Id(v), shell.mid.row(v).transpose());
    m.top.set(Id(v), shell.top.row(v).transpose());
    m.singular.set(Id(v), shell.singular[v]);
    m.input_vertex.set(Id(v), shell.input_vertex[v]);
  }
  std::optional<LocalSheets> sheets;
  if (shell.local_sheets) {
    if (options.collapse_chains || options.max_distance > 0 || !shell.reference.empty())
      throw MeshingError(
          "simplify: a locally injective shell (local sheets) is simplified without feature "
          "chains, distance bound or reference copy");
    sheets.emplace(index);
    m.sheets = &*sheets;
  }
  std::vector<int> touching;
  for (int f = 0; f < nf; ++f) {
    const std::vector<int> seed{shell.face_parent[std::size_t(f)]};
    m.prism_check(Id(f), touching, &seed);
    m.track.set(Id(f), touching);
  }
  stats.min_section_bound = options.section_cos;
  if (options.section_cos > 0 && options.section_cos_relative > 0) {
    // Each pillar's smallest cosine with the input faces in section contact with its prisms in
    // the starting shell, where that is below the bound: a knife edge's pillar is as tangent to
    // both sides as the edge's wedge makes it.
    std::vector<double> own(std::size_t(nv), std::numeric_limits<double>::infinity());
    for (int f = 0; f < nf; ++f) {
      const auto& tr = m.track[Id(f)];
      if (tr.empty()) continue;
      const auto p = m.prism_shape(Id(f));
      const auto& c = m.cell(Id(f));
      for (int x : tr) {
        const auto tri = index.face_triangle(x);
        const Eigen::Vector3d n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalized();
        int contact = -1;  // unknown
        for (int k = 0; k < 3; ++k) {
          if (p.s[k]) continue;
          const double ck = std::min(n.dot((p.m[k] - p.b[k]).normalized()),
                                     n.dot((p.t[k] - p.m[k]).normalized()));
          if (!(ck < options.section_cos) || !(ck < own[std::size_t(c[k])])) continue;
          if (contact < 0) contact = m.in_section_contact(p, x) ? 1 : 0;
          if (contact == 1) own[std::size_t(c[k])] = ck;
        }
      }
    }
    for (int v = 0; v < nv; ++v) {
      if (!(own[std::size_t(v)] < options.section_cos)) continue;
      const double b = std::max(0.0, options.section_cos_relative * own[std::size_t(v)]);
      m.lean_bound.set(Id(v), b);
      ++stats.relaxed_pillars;
      stats.min_section_bound = std::min(stats.min_section_bound, b);
    }
  }
  if (options.collapse_chains) {
    if (!(options.max_distance > 0))
      throw MeshingError("simplify: chain collapses need the distance bound (max_distance)");
    if (!options.extra_points.empty())
      throw MeshingError("simplify: chain collapses with extra distance points are not supported");
    if (!shell.reference.empty() && !options.resume)
      throw MeshingError("simplify: chain collapses on a shell with a reference copy");
    const int ni = input.num_vertices();
    std::vector<int> degree(std::size_t(ni), 0);
    std::vector<int> middle_of(std::size_t(ni), -1);
    for (int v = 0; v < nv; ++v)
      if (shell.input_vertex[v] >= 0) middle_of[std::size_t(shell.input_vertex[v])] = v;
    for (const auto& e : options.feature_edges) {
      if (e[0] < 0 || e[0] >= ni || e[1] < 0 || e[1] >= ni || e[0] == e[1])
        throw MeshingError("simplify: feature edge (" + std::to_string(e[0]) + ", " +
                           std::to_string(e[1]) + ") is not an edge of the input");
      ++degree[std::size_t(e[0])];
      ++degree[std::size_t(e[1])];
      const int a = middle_of[std::size_t(e[0])], b = middle_of[std::size_t(e[1])];
      if (a < 0 || b < 0) continue;
      if (const auto t = m.edge_tuple(Id(a), Id(b))) m.set_edge(m.chain, *t, {true, {}});
    }
    m.chain_vertex.assign(std::size_t(ni), 0);
    for (int x = 0; x < ni; ++x) m.chain_vertex[std::size_t(x)] = degree[std::size_t(x)] == 2;
    m.on_chain.assign(std::size_t(ni), 0);
    // Resume: the coarse feature edges of the earlier run's chain collapses, from the reference
    // copy; each edge's interior in order from its end on the smaller input vertex id.
    std::map<std::pair<int, int>, std::vector<std::pair<double, int>>> inside;
    for (const SnappedVertex& q : shell.reference) {
      const int lo = std::min(q.a, q.b), hi = std::max(q.a, q.b);
      inside[{lo, hi}].push_back({q.a == lo ? q.s : 1 - q.s, q.vertex});
      if (q.vertex >= 0 && q.vertex < ni) m.on_chain[std::size_t(q.vertex)] = 1;
    }
    for (auto& [ends, along] : inside) {
      const int a = middle_of[std::size_t(ends.first)], b = middle_of[std::size_t(ends.second)];
      const auto t = a >= 0 && b >= 0 ? m.edge_tuple(Id(a), Id(b)) : std::nullopt;
      if (!t)
        throw MeshingError("simplify: resume: input vertices snapped between input vertices " +
                           std::to_string(ends.first) + " and " + std::to_string(ends.second) +
                           ", which are not the ends of a coarse edge");
      std::sort(along.begin(), along.end());
      ShellMesh::ChainEdge edge{true, {}};
      for (const auto& [s, x] : along) edge.interior.push_back(x);
      m.set_edge(m.chain, *t, std::move(edge));
    }
  }
  stats.faces_before = nf;
  if (options.repair && options.resume)
    throw MeshingError("simplify: repair and resume modes are exclusive");
  if (options.repair || options.resume) {
    const std::string mode = options.repair ? "repair" : "resume";
    if (!(m.max_distance > 0))
      throw MeshingError("simplify: " + mode + " mode needs the distance bound (max_distance)");
    if (int(options.owned_points.size()) != nf)
      throw MeshingError("simplify: " + mode + " mode needs owned_points for each of the " +
                         std::to_string(nf) + " shell faces (got " +
                         std::to_string(options.owned_points.size()) + ")");
    if (options.repair && options.collapse_chains)
      throw MeshingError("simplify: repair mode does not collapse feature chains");
    m.repair = true;
    for (const auto& e : options.feature_edges)
      m.feature_pairs.insert({std::min(e[0], e[1]), std::max(e[0], e[1])});
    for (const SnappedVertex& q : shell.reference)
      m.feature_pairs.insert({std::min(q.a, q.b), std::max(q.a, q.b)});
  }
  if (m.max_distance > 0 &&
      (options.repair || options.resume)) {  // the points where the earlier run left them
    m.extra_points = &options.extra_points;
    const int np = input.num_vertices() + int(options.extra_points.size());
    for (int f = 0; f < nf; ++f) {
      std::vector<Eigen::Vector3d> where;
      const ShellMesh::Placer placer(m, Id(f));
      for (int x : options.owned_points[std::size_t(f)]) {
        if (x < 0 || x >= np)
          throw MeshingError("simplify: owned point " + std::to_string(x) + " of shell face " +
                             std::to_string(f) + " is not an input vertex or extra point");
        const auto q = placer.place(m, x);
        where.push_back(q ? *q : Eigen::Vector3d(0, 0, HUGE_VAL));
      }
      m.owned.set(Id(f), options.owned_points[std::size_t(f)]);
      m.place.set(Id(f), where);
    }
  } else if (m.max_distance > 0) {  // every input vertex starts in a prism of its middle vertex
    std::vector<char> seen(input.num_vertices(), 0);
    std::vector<std::vector<int>> own(nf);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        const int x = shell.input_vertex[shell.F(f, k)];
        if (x >= 0 && !seen[x]) {
          seen[x] = 1;
          own[f].push_back(x);
        }
      }
    // Extra distance points, each in the prism of the shell face the caller gives or of a face
    // sharing a vertex with it (a point on a face's edge may round into the neighbour).
    if (options.extra_points.size() != options.extra_point_faces.size())
      throw MeshingError("simplify: extra_points and extra_point_faces differ in length");
    m.extra_points = &options.extra_points;
    for (std::size_t i = 0; i < options.extra_points.size(); ++i) {
      const int f = options.extra_point_faces[i];
      if (f < 0 || f >= nf)
        throw MeshingError("simplify: extra distance point " + std::to_string(i) +
                           " names shell face " + std::to_string(f) + ", not a face");
      const int p = input.num_vertices() + int(i);
      int home = -1;
      if (const auto d = m.owned_distance(Id(f), p); d && *d <= m.max_distance) home = f;
      for (int k = 0; k < 3 && home < 0; ++k)
        for (Id g : m.vertex_cells(Id(shell.F(f, k))))
          if (const auto d = m.owned_distance(g, p); d && *d <= m.max_distance) {
            home = int(g);
            break;
          }
      if (home < 0)
        throw MeshingError("simplify: extra distance point " + std::to_string(i) +
                           " is not within the bound in the prism of shell face " +
                           std::to_string(f) + " or of a face next to it");
      own[home].push_back(input.num_vertices() + int(i));
    }
    for (int f = 0; f < nf; ++f) {
      m.owned.set(Id(f), own[f]);
      std::vector<Eigen::Vector3d> where;
      const ShellMesh::Placer placer(m, Id(f));
      for (int x : own[f]) {
        const auto q = placer.place(m, x);
        where.push_back(q ? *q : Eigen::Vector3d(0, 0, HUGE_VAL));
      }
      m.place.set(Id(f), where);
    }
  }

  std::vector<std::vector<int>> vf(input.num_vertices());
  for (int f = 0; f < input.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) vf[input.F(f, k)].push_back(f);
  m.vf = &vf;
  if (options.max_edge_per_thickness > 0) {
    m.max_edge_per_thickness = options.max_edge_per_thickness;
    m.thickness.assign(std::size_t(input.num_vertices()), HUGE_VAL);
    tbb::parallel_for(0, input.num_vertices(), [&](int x) {
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      for (int f : vf[std::size_t(x)]) {
        const Eigen::Vector3d a = input.V.row(input.F(f, 0)), b = input.V.row(input.F(f, 1)),
                              c = input.V.row(input.F(f, 2));
        n += (b - a).cross(c - a);
      }
      if (!(n.norm() > 0)) return;
      m.thickness[std::size_t(x)] =
          index.ray_distance(input.V.row(x).transpose(), -n.normalized(), vf[std::size_t(x)]);
    });
  }
  m.max_half_thickness = options.zoom;
  m.zoom_ray_fraction = options.zoom_ray_fraction;
  m.zoom_pinned = options.zoom_pinned;

  using Pass = editing::ExecutePass<TriMesh>;
  auto length2 = [&m](const TriMesh::Tuple& t) {
    return (m.mid[t.vid] - m.mid[m.other_vertex(t)]).squaredNorm();
  };
  auto edge_work = [&m](const std::string& op, const std::vector<TriMesh::Tuple>& edges,
                        bool both_ways) {
    std::vector<Pass::Work> work;
    for (const auto& e : edges) {
      work.emplace_back(op, e);
      if (both_ways) work.emplace_back(op, m.switch_vertex(e));
    }
    return work;
  };
  auto run = [&](const std::string& name, Pass& pass, const std::vector<Pass::Work>& work) {
    pass.num_threads = options.threads;
    pass.position = [&m](Id v) { return m.mid[v]; };
    const editing::PassStats s = pass.run(m, work);
    stats.passes.emplace_back(name, s);
    log::debug("simplify: ", name, ": ", s.summary());
    return int(s.succeeded);
  };
  // Collapses (ordinary or chain), shortest edge first; a success renews the edges around the
  // kept vertex.
  auto shortest_first_collapses = [&](const std::string& name) {
    Pass pass;
    pass.operations[name] = [&m](TriMesh&, const TriMesh::Tuple& t) { return m.collapse_edge(t); };
    pass.priority = [length2](const TriMesh&, const std::string&, const TriMesh::Tuple& t) {
      return -length2(t);
    };
    pass.should_process = [length2](const TriMesh&, const Pass::Work& w, double p) {
      return -length2(w.second) == p;
    };
    pass.renew_neighbor_tuples = [&, name](const TriMesh&, const std::string&,
                                           const TriMesh::Tuple& kept) {
      return edge_work(name, m.edges_of_faces(m.vertex_cells(kept.vid)), true);
    };
    return pass;
  };
  auto collapse_pass = [&] {
    m.count_rejections = true;
    m.memo_active = options.threads <= 1 && options.replay_refusals;
    struct Off {
      ShellMesh& m;
      ~Off() {
        m.count_rejections = false;
        m.memo_active = false;
      }
    } off{m};
    Pass pass = shortest_first_collapses("collapse");
    return run("collapse", pass, edge_work("collapse", m.get_edges(), true));
  };
  // Flips, worst pair of faces first; a success renews the edges of the two new faces.
  auto worst = [&m](const TriMesh::Tuple& t) {
    double w = m.mips(t.fid);
    if (const auto o = m.switch_face(t)) w = std::max(w, m.mips(o->fid));
    return w;
  };
  auto flip_pass = [&] {
    Pass pass;
    pass.operations["flip"] = [&m](TriMesh&, const TriMesh::Tuple& t) { return m.swap_edge(t); };
    pass.priority = [worst](const TriMesh&, const std::string&, const TriMesh::Tuple& t) {
      return worst(t);
    };
    pass.should_process = [worst](const TriMesh&, const Pass::Work& w, double p) {
      return worst(w.second) == p;
    };
    pass.renew_neighbor_tuples = [&](const TriMesh&, const std::string&, const TriMesh::Tuple& t) {
      const Id e[2] = {t.vid, m.other_vertex(t)};
      return edge_work("flip", m.edges_of_faces(m.cells_containing(std::span<const Id>(e, 2))),
                       false);
    };
    return run("flip", pass, edge_work("flip", m.get_edges(), false));
  };
  // Splits of the longest edge of every face with a positive score (the middle triangle's MIPS
  // above split_mips; in repair mode the worst distance beyond the bound of a violating point),
  // worst first, no renewal. New vertices get flags slots first (the invariants flag the changed
  // vertices).
  auto split_pass = [&](const std::function<double(Id)>& score, int rank) {
    std::vector<std::pair<double, TriMesh::Tuple>> bad;
    for (const auto& t : m.get_faces()) {
      const double q = score(t.fid);
      if (!(q > 0)) continue;
      TriMesh::Tuple e = t, longest = t;
      std::array<TriMesh::Tuple, 3> edges{t, t, t};
      for (int k = 0; k < 3; ++k) {
        edges[std::size_t(k)] = e;
        if (length2(e) > length2(longest)) longest = e;
        e = m.switch_vertex(m.switch_edge(e));
      }
      if (rank == 0) {
        bad.emplace_back(q, longest);
        continue;
      }
      // The rank-th longest edge (a repair's second and third tries).
      std::stable_sort(edges.begin(), edges.end(),
                       [&](const auto& x, const auto& y) { return length2(x) > length2(y); });
      bad.emplace_back(q, edges[std::size_t(rank)]);
    }
    if (bad.empty()) return 0;
    std::stable_sort(bad.begin(), bad.end(),
                     [](const auto& x, const auto& y) { return x.first > y.first; });
    std::vector<Pass::Work> work;
    for (const auto& [q, e] : bad) work.emplace_back("split", e);
    for (auto& flags : m.revisit) flags.resize(m.vertex_capacity() + work.size(), 0);
    m.occupied = std::make_unique<std::atomic<char>[]>(std::size_t(input.num_vertices()));
    for (const auto& v : m.get_vertices())
      if (m.input_vertex[v.vid] >= 0)
        m.occupied[std::size_t(m.input_vertex[v.vid])].store(1, std::memory_order_relaxed);
    Pass pass;
    pass.operations["split"] = [&m](TriMesh&, const TriMesh::Tuple& t) { return m.split_edge(t); };
    pass.priority = [](const TriMesh&, const std::string&, const TriMesh::Tuple&) { return 0.0; };
    const int n = run("split", pass, work);
    m.occupied.reset();
    return n;
  };
  // One smoothing move per vertex, no renewal (the next round re-seeds).
  // Only vertices flagged since the last pass of this kind (see ShellMesh::invariants).
  for (auto& flags : m.revisit) flags.assign(m.vertex_capacity(), 0);
  auto smooth_pass = [&](const std::string& name, ShellMesh::Smoothing mode) {
    m.smoothing_mode = mode;
    std::vector<char>& flags = m.revisit[mode == ShellMesh::Smoothing::rotate ? 0
                                         : mode == ShellMesh::Smoothing::zoom ? 1
                                                                              : 2];
    Pass pass;
    pass.operations[name] = [&m](TriMesh&, const TriMesh::Tuple& t) { return m.smooth_vertex(t); };
    pass.priority = [](const TriMesh&, const std::string&, const TriMesh::Tuple&) { return 0.0; };
    std::vector<Pass::Work> work;
    for (const auto& v : m.get_vertices())
      if (flags[v.vid]) work.emplace_back(name, v);
    std::fill(flags.begin(), flags.end(), 0);
    const bool pan = mode == ShellMesh::Smoothing::pan;
    const bool levels = options.threads <= 1 && options.smoothing_threads > 1;
    if (!pan && !levels) return run(name, pass, work);
    if (levels) {
      // Ordered levels, the same shell as one thread: a rotation or growth of v reads and writes
      // only the data of v's closed one-ring and of cells within it, the data of the cells
      // across its star's edges and of their corners (curved_ok) — written only by operations
      // on vertices within two edges of v, whose regions meet v's — and the fixed input; the
      // smoothing flags and memo stamps it sets are on its one-ring (no other operation of the
      // pass reads them; a stamp only has to be later than any refusal before the pass). A pan
      // also reads and writes `taken` of the input vertices around v's input vertex (it moves v
      // to one of them), named by ids from the vertex capacity on.
      const std::size_t cap = m.vertex_capacity();
      pass.level_region = [&m, cap, pan](const TriMesh& mesh, const TriMesh::Tuple& t,
                                         std::vector<Id>& out) {
        out = mesh.one_ring(t.vid);
        out.push_back(t.vid);
        const int x = m.input_vertex[t.vid];
        if (!pan || x < 0) return;
        out.push_back(Id(cap + std::size_t(x)));
        for (int g : (*m.vf)[std::size_t(x)])
          for (int k = 0; k < 3; ++k) out.push_back(Id(cap + std::size_t(m.input->F()(g, k))));
      };
      pass.reverse_levels = options.smoothing_levels_reversed;
    }
    // Pans run on one thread, or as ordered levels: `taken` is shared by moves whose stars do
    // not overlap.
    if (pan) {
      m.taken.assign(std::size_t(input.num_vertices()), 0);
      for (const auto& v : m.get_vertices())
        if (m.input_vertex[v.vid] >= 0) m.taken[std::size_t(m.input_vertex[v.vid])] = 1;
      for (std::size_t x = 0; x < m.on_chain.size(); ++x)
        if (m.on_chain[x]) m.taken[x] = 1;
    }
    pass.num_threads = levels ? options.smoothing_threads : 1;
    pass.position = [&m](Id v) { return m.mid[v]; };
    const editing::PassStats st = pass.run(m, work);
    stats.passes.emplace_back(name, st);
    log::debug("simplify: ", name, ": ", st.summary());
    m.taken.clear();
    return int(st.succeeded);
  };

  // Chain collapses on one thread, shortest coarse feature edge first.
  auto chain_pass = [&] {
    std::vector<TriMesh::Tuple> feature;
    for (const auto& e : m.get_edges())
      if (m.get_edge(m.chain, e).feature) feature.push_back(e);
    Pass pass = shortest_first_collapses("chain");
    pass.num_threads = 1;
    pass.position = [&m](Id v) { return m.mid[v]; };
    m.chain_mode = true;
    struct Off {
      ShellMesh& m;
      ~Off() {
        m.chain_mode = false;
        m.chain_boxes.clear();
        m.chain_live.clear();
        m.chain_live_ready = false;
        m.chain_grid.clear();
        m.chain_grid_big.clear();
        m.chain_grid_h = 0;
      }
    } off{m};
    const editing::PassStats st = pass.run(m, edge_work("chain", feature, true));
    stats.passes.emplace_back("chain", st);
    return int(st.succeeded);
  };

  // Repair: the worst excess of a violating point over the bound, per face.
  auto excess = [&m](Id f) {
    double worst = 0;
    for (std::size_t j = 0; j < m.place[f].size(); ++j)
      if (m.violating(m.owned[f][j], m.place[f][j][2]))
        worst = std::max(worst, m.place[f][j][2] - m.max_distance);
    return worst;
  };
  for (int pass = 0; (options.repair || options.resume) && pass < options.repair_passes; ++pass) {
    bool any = false;
    for (const auto& t : m.get_faces()) any = any || excess(t.fid) > 0;
    if (!any) break;
    ++stats.repair_passes;
    // The longest edge of every face with a violating point; where that was refused, the
    // second longest, then the shortest.
    int sp = 0;
    for (int rank = 0; rank < 3; ++rank) sp += split_pass(excess, rank);
    if (options.flips) stats.flips += flip_pass();
    stats.splits += sp;
    if (sp == 0) break;
  }
  // Resume: the collapse rounds only once every point is within its bound.
  bool rounds = !options.repair;
  if (options.resume) {
    for (const auto& t : m.get_faces()) rounds = rounds && !(excess(t.fid) > 0);
    if (rounds) m.repair = false;
  }
  log::debug("simplify: set-up and repair ",
             std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), " s");
  for (int round = 0; rounds && round < options.rounds; ++round) {
    m.stop_if_cancelled();
    int changed = 0;
    int collapsed = collapse_pass();
    stats.collapses += collapsed;
    if (options.collapse_chains) {
      const int c = chain_pass();
      stats.chain_collapses += c;
      collapsed += c;
    }
    changed += collapsed;
    if (options.split_mips > 0 && m.max_distance > 0) {
      const int sp =
          split_pass([&](Id f) { return m.mips(f) > options.split_mips ? m.mips(f) : 0.0; }, 0);
      stats.splits += sp;
      changed += sp;
    }
    if (options.pan) {
      const int p = smooth_pass("pan", ShellMesh::Smoothing::pan);
      stats.pans += p;
      changed += p;
    }
    // Each zoom pass doubles a half-pillar at most, and its successes flag their stars again:
    // up to zoom_passes of them a round let a pillar pinned thin (by a sliver, until the
    // coarsening removed it) grow 2^zoom_passes a round instead of 2.
    for (int pass = 0; options.zoom > 0 && pass < std::max(1, options.zoom_passes); ++pass) {
      m.zoom_pass = pass;
      const int z = smooth_pass("zoom", ShellMesh::Smoothing::zoom);
      stats.zooms += z;
      changed += z;
      if (z == 0) break;
    }
    if (options.rotate) {
      const int r = smooth_pass("rotate", ShellMesh::Smoothing::rotate);
      stats.rotations += r;
      changed += r;
    }
    if (options.flips) {
      const int f = flip_pass();
      stats.flips += f;
      changed += f;
    }
    if (collapsed == 0 && (round > 0 || changed == 0)) break;
  }

  stats.replayed_refusals = m.memo.replayed();
  stats.chain_prisms_tested = m.chain_prisms_tested;
  stats.chain_prisms_live = m.chain_prisms_live;
  log::debug("simplify: collapse refusals replayed: ", stats.replayed_refusals);
  auto& why = stats.collapse_rejections;
  why.shape = m.rejections[ShellMesh::shape];
  why.distance = m.rejections[ShellMesh::distance];
  why.positivity = m.rejections[ShellMesh::positivity];
  why.intersection = m.rejections[ShellMesh::intersection];
  why.section = m.rejections[ShellMesh::section];
  why.coverage = m.rejections[ShellMesh::coverage];
  why.curved = m.rejections[ShellMesh::curved];
  why.thickness = m.rejections[ShellMesh::thin];

  log::debug("simplify: rounds done at ",
             std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), " s");
  m.consolidate();
  Shell out;
  const int mv = int(m.vertex_capacity());
  out.base.resize(mv, 3);
  out.mid.resize(mv, 3);
  out.top.resize(mv, 3);
  out.singular.resize(mv);
  out.input_vertex.resize(mv);
  for (int v = 0; v < mv; ++v) {
    out.base.row(v) = m.base[Id(v)].transpose();
    out.mid.row(v) = m.mid[Id(v)].transpose();
    out.top.row(v) = m.top[Id(v)].transpose();
    out.singular[v] = m.singular[Id(v)];
    out.input_vertex[v] = m.input_vertex[Id(v)];
  }
  out.reference = index.snaps();
  out.local_sheets = shell.local_sheets;
  stats.snapped_vertices = int(out.reference.size());
  for (const SnappedVertex& q : out.reference) {
    const Eigen::Vector3d a = input.V.row(q.a).transpose(), b = input.V.row(q.b).transpose();
    stats.chain_max_distance = std::max(
        stats.chain_max_distance, (input.V.row(q.vertex).transpose() - (a + q.s * (b - a))).norm());
  }
  const auto faces = m.cells_array();
  out.F.resize(int(faces.size()), 3);
  out.face_parent.resize(faces.size());
  for (std::size_t f = 0; f < faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) out.F(int(f), k) = int(faces[f][k]);
    const auto& tr = m.track[Id(f)];
    out.face_parent[f] = tr.empty() ? -1 : tr.front();
  }
  stats.faces_after = int(faces.size());
  std::vector<double> thick;
  for (int v = 0; v < mv; ++v)
    if (!out.singular[v] && m.vertex_cells(Id(v)).size() > 0)
      thick.push_back(std::min((out.top.row(v) - out.mid.row(v)).norm(),
                               (out.mid.row(v) - out.base.row(v)).norm()));
  if (!thick.empty()) {
    std::sort(thick.begin(), thick.end());
    stats.min_half_thickness = thick.front();
    stats.median_half_thickness = thick[thick.size() / 2];
    stats.max_half_thickness = thick.back();
  }
  if (m.max_distance > 0) {
    stats.owned_points.resize(faces.size());
    for (std::size_t f = 0; f < faces.size(); ++f) {
      stats.owned_points[f] = m.owned[Id(f)];
      const ShellMesh::Placer placer(m, Id(f));
      for (int x : m.owned[Id(f)]) {
        const auto q = placer.place(m, x);
        const auto d = q ? std::optional<double>((*q)[2]) : std::nullopt;
        stats.max_distance = std::max(stats.max_distance, d ? *d : HUGE_VAL);
        const bool bad = m.violating(x, d ? *d : HUGE_VAL);
        stats.violating_points += bad;
        if (bad && log::enabled(log::Level::debug)) {
          const auto& c = faces[f];
          double longest = 0, shortest = HUGE_VAL, corner = HUGE_VAL;
          for (int k = 0; k < 3; ++k) {
            const Eigen::Vector3d a = out.mid.row(int(c[std::size_t(k)])).transpose(),
                                  b = out.mid.row(int(c[std::size_t((k + 1) % 3)])).transpose();
            longest = std::max(longest, (a - b).norm());
            shortest = std::min(shortest, (a - b).norm());
            corner = std::min(corner, (a - input.V.row(x).transpose()).norm());
          }
          log::debug("simplify: input vertex ", x, " left at ", d ? *d : HUGE_VAL, " (bound ",
                     m.max_distance, ") in coarse face ", f, ": MIPS ", m.mips(Id(f)), ", edges ",
                     shortest, "..", longest, ", nearest corner ", corner);
        }
      }
    }
  }
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace curvefem::meshing::shell
