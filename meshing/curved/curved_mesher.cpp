#include "meshing/curved/curved_mesher.hpp"

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <optional>
#include <set>
#include <thread>
#include <unordered_map>

#include "meshing/check/self_intersections.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/fiber_projection.hpp"
#include "meshing/core/lagrange_nodes.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/curved/curved_edit.hpp"
#include "meshing/curved/features.hpp"
#include "meshing/curved/jacobian_certificate.hpp"
#include "meshing/curved/node_key.hpp"
#include "meshing/curved/slab_nodes.hpp"
#include "meshing/editing/algorithms/tet_flips.hpp"
#include "meshing/shell/bevel.hpp"
#include "meshing/shell/fibers_of.hpp"
#include "meshing/shell/projection.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/shell_geometry.hpp"
#include "meshing/shell/shell_intersection.hpp"
#include "meshing/shell/simplify.hpp"
#include "meshing/shell/thin_refine.hpp"
#include "meshing/shell/verify.hpp"
#include "meshing/tetfill/tetfill.hpp"

namespace curvefem::meshing::curved {

namespace {

namespace sh = meshing::shell;

using NodeKey = curved::NodeKey<int>;
using NodeKeyHash = curved::NodeKeyHash<int>;

struct Owned {
  int vertex;
  double u, v;
};

// One straight or curved tet before stitching: its corner ids and the positions of its nodes.
struct TetNodes {
  std::array<int, 4> gid;
  Eigen::MatrixXd nodes;  // #lattice × 3, canonical order
};

// Are the 3 bottom (with `upper`: top) slab tets of a prism (rotated corners, no pinch) with
// its middle triangle displaced by d certified positive with the full shear (slab_nodes.hpp)?
// `far`: the base (top) corners. The curved-aware coarsening asks this of the faces it lets
// beyond ε: the full shear is what the mesher can always fall back to for such a face (with its
// side quads; a neighbour then follows if it must), whereas accepting the low-degree nodes here
// too let the coarsening place faces whose slabs then missed after the thickening (the elephant,
// K = 3: 5 discarded attempts and the linear bound, 888 faces, against 2 attempts and 800 faces).
bool slab_certified(int k, const std::array<Eigen::Vector3d, 3>& far,
                    const std::array<Eigen::Vector3d, 3>& mid, bool upper, bool type_a,
                    const std::vector<Eigen::Vector3d>& d) {
  const SlabBlend shear{false, {false, false, false}};
  for (const auto& tet : sh::split_tets(type_a)) {
    Eigen::Vector3d P[4];
    int lv[4], on_mid[4];
    for (int j = 0; j < 4; ++j) {
      lv[j] = tet[j] % 3;
      on_mid[j] = (tet[j] >= 3) != upper;
      P[j] = on_mid[j] ? mid[std::size_t(lv[j])] : far[std::size_t(lv[j])];
    }
    if (certify_tet_jacobian(k, slab_tet_nodes(k, P, lv, on_mid, d, shear)).verdict !=
        JacobianVerdict::positive)
      return false;
  }
  return true;
}

class Builder {
 public:
  Builder(const sh::Shell& shell, const SurfaceMesh& input, int order)
      : s(shell),
        in(input),
        k(order),
        nv(int(shell.mid.rows())),
        nf(int(shell.F.rows())),
        projection(shell, input),
        tri_lattice(lagrange_lattice(CellKind::triangle, order)),
        tet_lattice(lagrange_lattice(CellKind::tetrahedron, order)),
        inner(shell.base),
        outer(shell.top),
        certified_slabs(std::make_unique<CertifiedSlab[]>(2 * std::size_t(nf))) {
    for (int f = 0; f < nf; ++f)
      for (int e = 0; e < 3; ++e) {
        const int a = s.F(f, e), b = s.F(f, (e + 1) % 3);
        edge_faces[{std::min(a, b), std::max(a, b)}].push_back(f);
      }
  }

  const sh::Shell& s;
  const SurfaceMesh& in;
  const int k, nv, nf;
  sh::ShellProjection projection;
  const std::vector<std::array<int, 4>>& tri_lattice;
  const std::vector<std::array<int, 4>>& tet_lattice;
  std::map<std::pair<int, int>, std::vector<int>> edge_faces;
  std::vector<std::vector<Eigen::Vector3d>>
      raw;  // per face, per triangle node: fiber target - linear
  std::vector<double> alpha;
  // Per face: the low-degree slab nodes (1) or the full shear t · d (0), slab_nodes.hpp; all 0
  // unless CurvedMeshOptions::low_degree_slabs.
  std::vector<char> smooth;
  bool low_degree = false;
  std::vector<std::vector<Owned>> owned;
  int fiber_misses = 0;

  int rotated(int f, int local) const {
    const int r = sh::min_rotation(Eigen::Vector3i(s.F.row(f)));
    return s.F(f, (r + local) % 3);
  }
  int gid_base(int v) const { return s.singular[v] ? nv + v : v; }
  int gid_mid(int v) const { return nv + v; }
  int gid_top(int v) const { return s.singular[v] ? nv + v : 2 * nv + v; }
  Eigen::Vector3d top(int v) const { return outer.row(v).transpose(); }
  bool exterior = false;  // also the top half-prisms (outer slab layer)
  Eigen::Vector3d mid(int v) const { return s.mid.row(v).transpose(); }
  Eigen::Vector3d base(int v) const { return inner.row(v).transpose(); }
  std::vector<char> pulled_above;  // #V: inner vertex left above the shell's base by thicken()
  Eigen::MatrixXd inner;  // the inner surface of the slab layer (starts as the shell's base)
  Eigen::MatrixXd outer;  // the outer surface of the outer slab layer (starts as the shell's top)
  Eigen::Vector3d linear_mid(int f, double u, double v) const {
    return (1 - u - v) * mid(rotated(f, 0)) + u * mid(rotated(f, 1)) + v * mid(rotated(f, 2));
  }

  // Fiber targets of every curved node (edge nodes computed once per edge, so both faces agree).
  void compute_targets(const ProgressFn& progress) {
    raw.assign(nf, std::vector<Eigen::Vector3d>(tri_lattice.size(), Eigen::Vector3d::Zero()));
    if (k == 1) return;
    std::map<std::array<int, 3>, Eigen::Vector3d> edge_cache;  // (lo, hi, steps from lo)
    for (int f = 0; f < nf; ++f) {
      for (std::size_t i = 0; i < tri_lattice.size(); ++i) {
        const auto& a = tri_lattice[i];
        const int nonzero = (a[0] > 0) + (a[1] > 0) + (a[2] > 0);
        if (nonzero == 1) continue;  // corners sit on the input
        std::array<int, 3> edge_key{-1, -1, -1};
        if (nonzero == 2) {
          const int p = a[0] == 0 ? 1 : 0, q = a[2] == 0 ? 1 : 2;
          const int vp = rotated(f, p), vq = rotated(f, q);
          edge_key = vp < vq ? std::array<int, 3>{vp, vq, a[q]} : std::array<int, 3>{vq, vp, a[p]};
          if (auto it = edge_cache.find(edge_key); it != edge_cache.end()) {
            raw[f][i] = it->second;
            continue;
          }
        }
        const double u = double(a[1]) / k, v = double(a[2]) / k;
        const auto hit = projection.project(sh::PrismPoint{f, u, v, 0.0});
        Eigen::Vector3d d = Eigen::Vector3d::Zero();
        if (hit)
          d = hit->position - linear_mid(f, u, v);
        else
          ++fiber_misses;
        raw[f][i] = d;
        if (nonzero == 2) edge_cache[edge_key] = d;
      }
      if (progress && f % 256 == 0) progress("curve: fiber targets", double(f) / nf);
    }
  }

  // Faces owning a point farther than ε from their linear triangle (curved-aware coarsening).
  std::vector<char> needs_full;
  void find_needs_full(double eps) {
    needs_full.assign(nf, 0);
    for (int f = 0; f < nf; ++f)
      for (const Owned& o : owned[f])
        if (!((linear_mid(f, o.u, o.v) - point(o.vertex)).norm() <= eps * scale(o.vertex)))
          needs_full[f] = 1;
  }
  // Spatially varying ε: the factor of every distance point (empty: 1 everywhere).
  const std::vector<double>* point_scale = nullptr;
  double scale(int x) const {
    return point_scale && !point_scale->empty() ? (*point_scale)[std::size_t(x)] : 1.0;
  }

  // Distance points besides the vertices of `in`: index #V + i in `owned`.
  std::vector<Eigen::Vector3d> extra;
  Eigen::Vector3d point(int x) const {
    return x < in.num_vertices() ? Eigen::Vector3d(in.V.row(x).transpose())
                                 : extra[std::size_t(x - in.num_vertices())];
  }

  void locate_input(const ProgressFn& progress) {
    owned.assign(nf, {});
    std::vector<char> referenced(in.num_vertices(), 0);
    for (int f = 0; f < in.num_faces(); ++f)
      for (int c = 0; c < 3; ++c) referenced[in.F(f, c)] = 1;
    std::vector<std::optional<sh::PrismPoint>> where(in.num_vertices());
    tbb::parallel_for(0, in.num_vertices(), [&](int x) {
      // The vertex's point of the shell's reference copy (the input vertex itself unless a
      // feature chain snapped it).
      if (referenced[x])
        where[x] = projection.locate(projection.reference_vertices().row(x).transpose());
    });
    // A vertex a feature chain snapped is a + s (b − a) on the coarse edge between the middle
    // vertices on a and b: its (u, v) are exact there (barycentrics 1 − s, s, 0). Located, its
    // rounding lands up to ~1e-9 off the edge in a thin coarse triangle, and the validator would
    // then see a feature edge off the boundary's edges (cheese, K = 3: 9 features).
    if (!s.reference.empty()) {
      std::vector<int> middle_of(std::size_t(in.num_vertices()), -1);
      for (int v = 0; v < nv; ++v)
        if (s.input_vertex[v] >= 0 && s.input_vertex[v] < in.num_vertices())
          middle_of[std::size_t(s.input_vertex[v])] = v;
      for (const sh::SnappedVertex& q : s.reference) {
        if (q.vertex < 0 || q.vertex >= in.num_vertices() || !where[q.vertex] || q.a < 0 ||
            q.b < 0 || q.a >= in.num_vertices() || q.b >= in.num_vertices())
          continue;
        const int va = middle_of[std::size_t(q.a)], vb = middle_of[std::size_t(q.b)];
        const auto it = edge_faces.find({std::min(va, vb), std::max(va, vb)});
        if (va < 0 || vb < 0 || it == edge_faces.end()) continue;
        const std::vector<int>& faces = it->second;
        const int f = std::find(faces.begin(), faces.end(), where[q.vertex]->face) != faces.end()
                          ? where[q.vertex]->face
                          : faces.front();
        double l[3] = {0, 0, 0};
        for (int c = 0; c < 3; ++c) {
          if (rotated(f, c) == va) l[c] = 1 - q.s;
          if (rotated(f, c) == vb) l[c] = q.s;
        }
        where[q.vertex] = sh::PrismPoint{f, l[1], l[2], 0.0};
      }
    }
    for (int x = 0; x < in.num_vertices(); ++x) {
      if (!referenced[x]) continue;
      if (!where[x])
        throw MeshingError("curve: input vertex is outside the coarse shell", {.vertex = x});
      owned[where[x]->face].push_back({x, where[x]->u, where[x]->v});
    }
    std::vector<std::optional<sh::PrismPoint>> at(extra.size());
    tbb::parallel_for(std::size_t(0), extra.size(),
                      [&](std::size_t i) { at[i] = projection.locate(extra[i]); });
    for (std::size_t i = 0; i < extra.size(); ++i) {
      if (!at[i])
        throw MeshingError("curve: distance point " + std::to_string(i) +
                           " is outside the coarse shell");
      owned[at[i]->face].push_back({in.num_vertices() + int(i), at[i]->u, at[i]->v});
    }
    if (progress) progress("curve: locate input", 1.0);
  }

  // The blend schedule of a face: 1, 1/2, ..., 1/64, then 0 (linear).
  void lower_alpha(int f) { alpha[f] = alpha[f] > 1.0 / 64 ? alpha[f] / 2 : 0.0; }
  // Lowers f's α; at α = 0, the α of the faces across its edges that need full curving (their
  // edges are not lowered by f, edge_alpha). Returns the faces lowered (none: nothing could be).
  std::vector<int> lower_for(int f) {
    if (alpha[f] > 0) {
      lower_alpha(f);
      return {f};
    }
    std::vector<int> lowered;
    for (int g : across(f))
      if (!needs_full.empty() && needs_full[g] && alpha[g] > 0) {
        lower_alpha(g);
        lowered.push_back(g);
      }
    return lowered;
  }
  // The faces sharing an edge with f, and f.
  std::vector<int> across(int f) const {
    std::vector<int> out;
    for (int e = 0; e < 3; ++e) {
      const int p = s.F(f, e), q = s.F(f, (e + 1) % 3);
      for (int g : edge_faces.at({std::min(p, q), std::max(p, q)})) out.push_back(g);
    }
    return out;
  }

  // An edge's nodes use the smallest α of its faces, leaving out, on an edge of a face that needs
  // full curving (needs_full), the faces that do not: lowering their α must not pass a distance
  // miss on to that face.
  double edge_alpha(int a, int b) const {
    const auto& faces = edge_faces.at({std::min(a, b), std::max(a, b)});
    bool full = false;
    if (!needs_full.empty())
      for (int g : faces) full = full || needs_full[g];
    double out = 1;
    for (int g : faces)
      if (!full || needs_full[g]) out = std::min(out, alpha[g]);
    return out;
  }
  // Blended displacement of every node of face f.
  std::vector<Eigen::Vector3d> node_displacements(int f) const {
    std::vector<Eigen::Vector3d> d(tri_lattice.size(), Eigen::Vector3d::Zero());
    for (std::size_t i = 0; i < tri_lattice.size(); ++i) {
      const auto& a = tri_lattice[i];
      const int nonzero = (a[0] > 0) + (a[1] > 0) + (a[2] > 0);
      if (nonzero == 1) continue;
      double w = alpha[f];
      if (nonzero == 2) {
        const int p = a[0] == 0 ? 1 : 0, q = a[2] == 0 ? 1 : 2;
        w = edge_alpha(rotated(f, p), rotated(f, q));
      }
      d[i] = w * raw[f][i];
    }
    return d;
  }
  // Is every point face f owns within eps of its patch at the current α?
  bool meets_eps(int f, double eps) const {
    const auto d = node_displacements(f);
    for (const Owned& o : owned[f])
      if (!((linear_mid(f, o.u, o.v) + patch_displacement(d, k, o.u, o.v) - point(o.vertex))
                .norm() <= eps * scale(o.vertex)))
        return false;
    return true;
  }

  // The bottom (or, with `upper`, the top) half-prism of face f as order-k tets (pinched tets
  // dropped). A node is its linear point plus its share of the middle corners times the curved
  // displacement, so both layers meet the curved middle surface node for node.
  std::vector<TetNodes> slab_tets(int f, const std::vector<Eigen::Vector3d>& d,
                                  bool upper = false) const {
    const bool type_a = sh::is_type_a(Eigen::Vector3i(s.F.row(f)));
    std::vector<TetNodes> out;
    for (const auto& tet : sh::split_tets(type_a)) {
      TetNodes t;
      Eigen::Vector3d P[4];
      int lv[4], on_mid[4];
      for (int j = 0; j < 4; ++j) {
        lv[j] = tet[j] % 3;
        const bool high = tet[j] >= 3;
        const int v = rotated(f, lv[j]);
        if (!upper) {
          t.gid[j] = high ? gid_mid(v) : gid_base(v);
          P[j] = high ? mid(v) : base(v);
          on_mid[j] = high;
        } else {
          t.gid[j] = high ? gid_top(v) : gid_mid(v);
          P[j] = high ? top(v) : mid(v);
          on_mid[j] = !high;
        }
      }
      bool repeated = false;
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) repeated |= t.gid[i] == t.gid[j];
      if (repeated) continue;
      unsigned pinched = 0;
      for (int j = 0; j < 4; ++j)
        if (s.singular[rotated(f, lv[j])]) pinched |= 1u << j;
      t.nodes = slab_tet_nodes(k, P, lv, on_mid, d, blend_of(f), pinched);
      out.push_back(std::move(t));
    }
    return out;
  }

  // Face f's slab construction: its own inside, the side quad over each edge low-degree only
  // when every face on that edge is.
  SlabBlend blend_of(int f) const {
    SlabBlend b;
    if (smooth.empty() || k < 3) return b;
    b.face = smooth[f] != 0;
    for (int i = 0; i < 3; ++i) {
      const int p = rotated(f, (i + 1) % 3), q = rotated(f, (i + 2) % 3);
      bool all = true;
      for (int g : edge_faces.at({std::min(p, q), std::max(p, q)})) all = all && smooth[g];
      b.edge[i] = all;
    }
    return b;
  }
  // Faces on the full shear try the low-degree slab again (after the thickening deepened the
  // slabs), kept when their slabs and those of the faces across their edges certify.
  void raise_smooth(double eps) {
    if (k < 3 || !low_degree) return;
    for (int f = 0; f < nf; ++f) {
      if (smooth[f]) continue;
      smooth[f] = 1;
      bool ok = face_check(f, eps) == 0;
      for (int g : across(f)) ok = ok && face_check(g, eps) == 0;
      if (!ok) smooth[f] = 0;
    }
  }
  int shear_faces() const { return int(std::count(smooth.begin(), smooth.end(), 0)); }

  // Every tet of face f's bottom (upper = false) or top half-prism slab certified positive.
  bool layer_certified(int f, bool upper) const {
    const auto d = node_displacements(f);
    // The verdict is a function of the slab's corners, d and the blend (everything else slab_tets
    // reads is fixed for the builder): the thickening, the recurving and the embedding repair
    // re-check every face in every round, most of them unchanged since their last check.
    std::vector<double> key;
    key.reserve(18 + 3 * d.size() + 4);
    for (int c = 0; c < 3; ++c) {
      const int v = rotated(f, c);
      for (const Eigen::Vector3d& p : {upper ? mid(v) : base(v), upper ? top(v) : mid(v)})
        key.insert(key.end(), p.data(), p.data() + 3);
    }
    for (const Eigen::Vector3d& x : d) key.insert(key.end(), x.data(), x.data() + 3);
    const SlabBlend blend = blend_of(f);
    key.push_back(blend.face);
    for (const bool e : blend.edge) key.push_back(e);
    CertifiedSlab& memo = certified_slabs[std::size_t(2 * f + (upper ? 1 : 0))];
    {
      const std::lock_guard<std::mutex> lock(memo.mutex);
      if (memo.key.size() == key.size() &&
          std::memcmp(memo.key.data(), key.data(), sizeof(double) * key.size()) == 0)
        return memo.verdict;
    }
    bool verdict = true;
    for (const auto& t : slab_tets(f, d, upper))
      if (certify_tet_jacobian(k, t.nodes).verdict != JacobianVerdict::positive) {
        verdict = false;
        break;
      }
    const std::lock_guard<std::mutex> lock(memo.mutex);
    memo.key = std::move(key);
    memo.verdict = verdict;
    return verdict;
  }
  // layer_certified's last verdict per face and layer with what it was computed from. The face
  // checks run in parallel over distinct faces; the lock keeps the memo safe for any caller.
  struct CertifiedSlab {
    std::mutex mutex;
    std::vector<double> key;
    bool verdict = false;
  };
  mutable std::unique_ptr<CertifiedSlab[]> certified_slabs;
  bool slabs_certified(int f) const {
    return layer_certified(f, false) && (!exterior || layer_certified(f, true));
  }

  // Deepens the inner surface (and, with an exterior, raises the outer one) along the pillars:
  // slabs as thin as the shell make needle tets. Target depth beta × mean coarse edge length at v
  // (never shallower than the shell's base / top); a vertex of a face whose slabs are not
  // certified, or of a triangle of that surface in a self-intersecting pair, moves halfway back
  // to the shell's base / top, for a few rounds, then all the way, then toward the middle surface
  // (the shell's base and top are only guaranteed to be separated from the input: they can
  // self-intersect in thin parts and near contacts). Returns the inner vertices deepened.
  int thicken(double beta, double eps) {
    const int layers = exterior ? 2 : 1;
    std::vector<double> length(nv, 0);
    std::vector<int> count(nv, 0);
    for (int f = 0; f < nf; ++f)
      for (int e = 0; e < 3; ++e) {
        const int a = s.F(f, e), b = s.F(f, (e + 1) % 3);
        const double l = (mid(a) - mid(b)).norm();
        length[a] += l;
        length[b] += l;
        ++count[a];
        ++count[b];
      }
    // Direction: the area-weighted normal of the coarse middle surface (better-shaped slabs than
    // the pillars), unless it leans more than 60° from the pillar.
    std::vector<Eigen::Vector3d> normal(nv, Eigen::Vector3d::Zero());
    for (int f = 0; f < nf; ++f) {
      const Eigen::Vector3d n =
          (mid(s.F(f, 1)) - mid(s.F(f, 0))).cross(mid(s.F(f, 2)) - mid(s.F(f, 0)));
      for (int c = 0; c < 3; ++c) normal[s.F(f, c)] += n;
    }
    // Per layer: 0 = the inner surface (below the middle surface, from the shell's base), 1 = the
    // outer one (above it, from the shell's top). Depths are distances from the middle surface.
    struct Layer {
      Eigen::MatrixXd* surface;
      const Eigen::MatrixXd* shell_end;
      double side;  // -1 below the middle surface, +1 above
      std::vector<double> shell_depth, depth;
      std::vector<Eigen::Vector3d> dir, pillar;
    };
    std::vector<Layer> L;
    L.push_back({&inner, &s.base, -1.0, {}, {}, {}, {}});
    if (exterior) L.push_back({&outer, &s.top, 1.0, {}, {}, {}, {}});
    for (Layer& l : L) {
      l.shell_depth.assign(nv, 0);
      l.depth.assign(nv, 0);
      l.dir.assign(nv, Eigen::Vector3d::Zero());
      l.pillar.assign(nv, Eigen::Vector3d::Zero());
      for (int v = 0; v < nv; ++v) {
        const Eigen::Vector3d p = l.side * (Eigen::Vector3d(l.shell_end->row(v)) - mid(v));
        l.shell_depth[v] = l.depth[v] = p.norm();
        if (s.singular[v] || l.shell_depth[v] == 0) continue;
        l.pillar[v] = l.dir[v] = p / l.shell_depth[v];  // pointing outward on both layers
        const Eigen::Vector3d n = normal[v].normalized();
        if (n.dot(l.dir[v]) > 0.5) l.dir[v] = n;
        l.depth[v] = std::max(l.shell_depth[v], beta * length[v] / std::max(count[v], 1));
      }
      // Lipschitz-smooth the target depths so the surface has no steps: depth(v) <=
      // depth(u) + |uv| / 2 for every edge.
      for (int pass = 0; pass < 20; ++pass) {
        bool changed = false;
        for (int f = 0; f < nf; ++f)
          for (int e = 0; e < 3; ++e) {
            const int a = s.F(f, e), b = s.F(f, (e + 1) % 3);
            const double h = 0.5 * (mid(a) - mid(b)).norm();
            for (auto [x, y] : {std::pair{a, b}, std::pair{b, a}})
              if (l.depth[x] > std::max(l.shell_depth[x], l.depth[y] + h)) {
                l.depth[x] = std::max(l.shell_depth[x], l.depth[y] + h);
                changed = true;
              }
          }
        if (!changed) break;
      }
    }
    // Beyond the shell's base / top the vertex follows `dir`; within it, the pillar (so the
    // slab stays a sub-prism of the shell's positive prism).
    auto place = [&](Layer& l, int v) {
      if (l.depth[v] == l.shell_depth[v])
        l.surface->row(v) = l.shell_end->row(v);
      else if (l.depth[v] > l.shell_depth[v])
        l.surface->row(v) = (mid(v) + l.side * l.depth[v] * l.dir[v]).transpose();
      else
        l.surface->row(v) = (mid(v) + l.side * l.depth[v] * l.pillar[v]).transpose();
    };
    for (Layer& l : L)
      for (int v = 0; v < nv; ++v) place(l, v);
    std::vector<char> protect(nv, 0);
    if (!needs_full.empty())
      for (int f = 0; f < nf; ++f)
        if (needs_full[f])
          for (int c = 0; c < 3; ++c) protect[s.F(f, c)] = 1;
    int round = 0;  // protection ends after 20 rounds: a clean surface comes first
    auto is_protected = [&](int v) { return round < 20 && protect[v] != 0; };
    // Repair rounds. A face failing (slabs not certified, or ε violated after an α change)
    // shrinks its vertices beyond the shell's base / top back toward it, or, if it has none,
    // halves its curving α. Vertices of self-intersecting or degenerate triangles of a surface
    // move halfway back to the shell's base / top, then toward the middle surface along the
    // pillar.
    const Eigen::MatrixXi F = s.F;
    bool clean = false;
    for (round = 0; round < 40 && !clean; ++round) {
      std::vector<char> ok(nf, 1), uncertified(nf, 0);
      tbb::parallel_for(0, nf, [&](int f) {
        const int verdict = face_check(f, eps);
        ok[f] = verdict == 0;
        uncertified[f] = verdict == 1;
      });
      clean = std::count(ok.begin(), ok.end(), 0) == 0;
      // A face whose low-degree slab fails takes the full shear before anything moves.
      bool sheared = false;
      for (int f = 0; f < nf; ++f)
        if (uncertified[f] && k > 2 && smooth[f]) {
          smooth[f] = 0;
          sheared = true;
        }
      if (sheared) {
        clean = false;
        continue;
      }
      std::vector<std::vector<char>> shrink(std::size_t(layers), std::vector<char>(nv, 0));
      std::vector<std::vector<char>> deepen = shrink;  // toward the middle (intersections only)
      for (int f = 0; f < nf; ++f) {
        if (ok[f]) continue;
        bool any = false;
        for (int i = 0; i < layers; ++i)
          for (int c = 0; c < 3; ++c)
            if (L[std::size_t(i)].depth[F(f, c)] > L[std::size_t(i)].shell_depth[F(f, c)]) {
              shrink[std::size_t(i)][F(f, c)] = 1;
              any = true;
            }
        if (!any) lower_for(f);
      }
      for (int i = 0; i < layers; ++i) {
        const Eigen::MatrixXd& X = *L[std::size_t(i)].surface;
        auto& sh = shrink[std::size_t(i)];
        auto& dp = deepen[std::size_t(i)];
        const std::vector<char> degenerate = check::exactly_degenerate_faces(X, F);
        for (int f = 0; f < nf; ++f)
          if (degenerate[f])
            for (int c = 0; c < 3; ++c) sh[F(f, c)] = dp[F(f, c)] = 1;
        const auto si = check::find_self_intersections(X, F, degenerate, true,
                                                       check::SelfIntersectionEngine::soup);
        // A pair moves the corners that no face needing full curving uses, if it has any (for
        // 20 rounds): such a face's slab was certified on the shell's base, and beyond it full
        // curving may fail.
        for (const auto& [f, g] : si.pairs) {
          bool free_corner = false;
          for (int c = 0; c < 3; ++c)
            free_corner = free_corner || !is_protected(F(f, c)) || !is_protected(F(g, c));
          for (int c = 0; c < 3; ++c)
            for (int v : {F(f, c), F(g, c)})
              if (!free_corner || !is_protected(v)) sh[v] = dp[v] = 1;
        }
        // Folds much sharper than the middle surface's at the same edge (a knife edge whose
        // inner surface closes in on itself: Gmsh's boundary recovery refuses dihedral angles
        // far below the input's) move their four corners back like an intersecting pair.
        const std::vector<std::array<int, 4>> folds = sharp_folds(X);
        for (const auto& q : folds)
          for (int v : q) sh[v] = dp[v] = 1;
        clean = clean && si.pairs.empty() && folds.empty() &&
                std::count(degenerate.begin(), degenerate.end(), 1) == 0;
      }
      for (int i = 0; i < layers; ++i) {
        Layer& l = L[std::size_t(i)];
        for (int v = 0; v < nv; ++v) {
          if (!shrink[std::size_t(i)][v] || s.singular[v]) continue;
          if (l.depth[v] > l.shell_depth[v])
            l.depth[v] = round < 8 ? l.shell_depth[v] + 0.5 * (l.depth[v] - l.shell_depth[v])
                                   : l.shell_depth[v];
          else if (deepen[std::size_t(i)][v])
            l.depth[v] *= 0.5;
          place(l, v);
        }
      }
    }
    if (!clean)
      throw MeshingError(std::string("thicken: the ") + (exterior ? "inner or outer" : "inner") +
                         " surface of the slab layer could not be made free of "
                         "self-intersections with certified slabs in 40 rounds");
    if (recurve) raise_alpha(eps);
    raise_smooth(eps);
    if (quality_floor > 0) lower_for_quality(eps);
    if (distortion_floor > 0) lower_for_distortion(eps);
    if (embed) embed_boundary(eps);
    int moved = 0;
    pulled_above.assign(nv, 0);
    for (int v = 0; v < nv; ++v) {
      moved += L[0].depth[v] > L[0].shell_depth[v];
      pulled_above[v] = L[0].depth[v] < L[0].shell_depth[v];
    }
    outer_raised = 0;
    outer_lowered = 0;
    if (exterior)
      for (int v = 0; v < nv; ++v) {
        outer_raised += L[1].depth[v] > L[1].shell_depth[v];
        outer_lowered += L[1].depth[v] < L[1].shell_depth[v];
      }
    return moved;
  }
  int outer_raised = 0, outer_lowered = 0;
  bool embed = true;  // run embed_boundary at the end of each thickening

  // Interior dihedral angle (radians, in [0, π]) at edge (a, b) between faces f and g of X.
  double dihedral(const Eigen::MatrixXd& X, int f, int g) const {
    auto normal = [&](int h) {
      const Eigen::Vector3d p = X.row(s.F(h, 0)), q = X.row(s.F(h, 1)), r = X.row(s.F(h, 2));
      return Eigen::Vector3d((q - p).cross(r - p).normalized());
    };
    return M_PI - std::acos(std::clamp(normal(f).dot(normal(g)), -1.0, 1.0));
  }
  // Edges (with the four corners of their two faces) where the surface X folds to less than half
  // the middle surface's dihedral angle there and below 10°.
  std::vector<std::array<int, 4>> sharp_folds(const Eigen::MatrixXd& X) const {
    std::vector<std::array<int, 4>> out;
    for (const auto& [e, faces] : edge_faces) {
      if (faces.size() != 2) continue;
      const double d = dihedral(X, faces[0], faces[1]);
      if (!(d < 10 * M_PI / 180) || !(d < 0.5 * dihedral(s.mid, faces[0], faces[1]))) continue;
      std::array<int, 4> q{e.first, e.second, -1, -1};
      for (int i = 0; i < 2; ++i)
        for (int c = 0; c < 3; ++c) {
          const int v = s.F(faces[std::size_t(i)], c);
          if (v != e.first && v != e.second) q[std::size_t(2 + i)] = v;
        }
      out.push_back(q);
    }
    return out;
  }

  // The curved middle surface (the mesh boundary at the current α) as m × m flat triangles per
  // face, face f's first at row f·m²; corner and edge points are evaluated once and shared.
  void sample_middle(int m, Eigen::MatrixXd& V, Eigen::MatrixXi& F) const {
    std::map<std::array<int, 3>, int> shared;  // (lo vertex, hi vertex, steps from lo)
    std::vector<Eigen::Vector3d> points;
    F.resize(Eigen::Index(nf) * m * m, 3);
    std::vector<int> id(std::size_t((m + 1) * (m + 2) / 2));
    auto index = [m](int i, int j) { return std::size_t(j * (m + 1) - j * (j - 1) / 2 + i); };
    for (int f = 0; f < nf; ++f) {
      const auto d = node_displacements(f);
      for (int j = 0; j <= m; ++j)
        for (int i = 0; i + j <= m; ++i) {
          const int w[3] = {m - i - j, i, j};  // weights on the rotated corners 0, 1, 2
          const int nz = (w[0] > 0) + (w[1] > 0) + (w[2] > 0);
          std::array<int, 3> key{-1, -1, -1};
          if (nz == 1) {
            const int c = w[0] > 0 ? 0 : (w[1] > 0 ? 1 : 2);
            key = {rotated(f, c), rotated(f, c), 0};
          } else if (nz == 2) {
            const int p = w[0] == 0 ? 1 : 0, q = w[2] == 0 ? 1 : 2;
            const int vp = rotated(f, p), vq = rotated(f, q);
            key = vp < vq ? std::array<int, 3>{vp, vq, w[q]} : std::array<int, 3>{vq, vp, w[p]};
          }
          int pid = -1;
          if (key[0] >= 0)
            if (auto it = shared.find(key); it != shared.end()) pid = it->second;
          if (pid < 0) {
            pid = int(points.size());
            const double u = double(i) / m, v = double(j) / m;
            points.push_back(
                nz == 1 ? mid(key[0])
                        : Eigen::Vector3d(linear_mid(f, u, v) + patch_displacement(d, k, u, v)));
            if (key[0] >= 0) shared[key] = pid;
          }
          id[index(i, j)] = pid;
        }
      Eigen::Index row = Eigen::Index(f) * m * m;
      // Orientation of the face's rotated corners (a rotation keeps it).
      for (int j = 0; j < m; ++j)
        for (int i = 0; i + j < m; ++i) {
          F.row(row++) << id[index(i, j)], id[index(i + 1, j)], id[index(i, j + 1)];
          if (i + j + 1 < m)
            F.row(row++) << id[index(i + 1, j)], id[index(i + 1, j + 1)], id[index(i, j + 1)];
        }
    }
    V.resize(Eigen::Index(points.size()), 3);
    for (std::size_t i = 0; i < points.size(); ++i) V.row(Eigen::Index(i)) = points[i].transpose();
  }
  // Pairs of coarse faces (f < g) whose sampled curved patches intersect, or whose samples are
  // degenerate (a face with a degenerate sample pairs with itself).
  std::vector<std::pair<int, int>> curved_boundary_intersections(int m) const {
    Eigen::MatrixXd V;
    Eigen::MatrixXi F;
    sample_middle(m, V, F);
    const std::vector<char> degenerate = check::exactly_degenerate_faces(V, F);
    const auto si =
        check::find_self_intersections(V, F, degenerate, true, check::SelfIntersectionEngine::soup);
    std::set<std::pair<int, int>> out;
    for (const auto& [a, b] : si.pairs) {
      const int f = a / (m * m), g = b / (m * m);
      out.insert({std::min(f, g), std::max(f, g)});
    }
    for (std::size_t t = 0; t < degenerate.size(); ++t)
      if (degenerate[t]) out.insert({int(t) / (m * m), int(t) / (m * m)});
    return {out.begin(), out.end()};
  }
  // Construction-time embedding of the curved boundary (issue 21): the faces of every
  // intersecting pair of sampled patches (2k per edge, the validator's default) halve their α
  // (down to 0, their linear triangles, which the shell keeps embedded), and a face across their
  // edges whose slabs or distance bound then fail follows, until the surface is clean. Faces the
  // curved-aware coarsening let beyond ε of their linear triangle (needs_full) are not lowered.
  // Pairs left that nothing could lower stay in embedding_pairs_after.
  void embed_boundary(double eps) {
    if (k < 2) return;
    const int m = 2 * k;
    for (int round = 0;; ++round) {
      const auto pairs = curved_boundary_intersections(m);
      if (round == 0) embedding_pairs_before = int(pairs.size());
      embedding_pairs_after = int(pairs.size());
      if (pairs.empty()) return;
      ++embedding_rounds;
      std::set<int> lowered;
      for (const auto& [f, g] : pairs)
        for (int h : {f, g})
          if (alpha[h] > 0 && (needs_full.empty() || !needs_full[h])) lowered.insert(h);
      if (lowered.empty() || round >= 64) return;
      for (int h : lowered) {
        lower_alpha(h);
        embedding_lowered.insert(h);
      }
      // The faces across the lowered ones share their edge nodes: re-certify them, lowering
      // further where they fail (α = 0 meets both by the shell).
      std::vector<int> work;
      for (int h : lowered)
        for (int g : across(h)) work.push_back(g);
      while (!work.empty()) {
        std::sort(work.begin(), work.end());
        work.erase(std::unique(work.begin(), work.end()), work.end());
        std::vector<int> next;
        for (int g : work) {
          if (alpha[g] == 0 || face_check(g, eps) == 0) continue;
          if (!needs_full.empty() && needs_full[g]) continue;
          lower_alpha(g);
          embedding_lowered.insert(g);
          for (int h : across(g)) next.push_back(h);
        }
        work = std::move(next);
      }
    }
  }
  int embedding_pairs_before = 0, embedding_pairs_after = 0, embedding_rounds = 0;
  std::set<int> embedding_lowered;

  // Curving was decided on slabs down to the shell's base; the deeper inner surface leaves the
  // curved patch room. Each face below α = 1 tries 1, 1/2, ... down to (not including) its α,
  // kept when its slabs and those of the faces across its edges (which share its edge nodes)
  // still certify and the distance bound holds. The inner surface does not change. Sequential:
  // neighbouring faces interact through their edges.
  void raise_alpha(double eps) {
    int raised = 0;
    for (int f = 0; f < nf; ++f) {
      if (alpha[f] == 1) continue;
      const double old = alpha[f];
      std::vector<int> around;
      for (int e = 0; e < 3; ++e) {
        const int p = s.F(f, e), q = s.F(f, (e + 1) % 3);
        for (int g : edge_faces.at({std::min(p, q), std::max(p, q)}))
          if (g != f) around.push_back(g);
      }
      for (double a = 1; a > old && a >= 1.0 / 64; a /= 2) {
        alpha[f] = a;
        bool ok = face_check(f, eps) == 0;
        for (std::size_t i = 0; i < around.size() && ok; ++i) ok = face_check(around[i], eps) == 0;
        if (ok) break;
        alpha[f] = old;
      }
      raised += alpha[f] > old;
    }
    alpha_raised = raised;
  }
  int alpha_raised = 0;
  bool recurve = true;

  // Worst sampled scaled Jacobian (min_scaled_jacobian) of the bottom slab tets of f (and, with
  // an exterior, the top ones).
  double slab_quality(int f) const {
    double q = HUGE_VAL;
    const auto d = node_displacements(f);
    for (int layer = 0; layer < (exterior ? 2 : 1); ++layer)
      for (const auto& t : slab_tets(f, d, layer == 1))
        q = std::min(q, min_scaled_jacobian(k, t.nodes));
    return q;
  }
  // Certified slabs and the distance bound may still leave a face's slab tets near-degenerate:
  // where the slab layer stays shallow (thin parts, concave regions the thickening could not
  // deepen) a curved edge shears into its slab tets by about their depth and pinches them
  // (homer, K = 3: a slab tet of scaled Jacobian 7.8e-4 that no smoothing could lift, its
  // straight shape 0.06). Each face whose slab tets are below quality_floor tries α / 2, α / 4,
  // ..., 0, every step checked like raise_alpha (its slabs and those across its edges certified,
  // ε held); it keeps the first α whose worst slab tet over the face and its neighbours reaches
  // the floor, else the best one if it at least doubles that worst value, else its α.
  // Sequential and deterministic; faces that need full curving for ε keep it.
  void lower_for_quality(double eps) {
    int lowered = 0;
    for (int f = 0; f < nf; ++f) {
      if (alpha[f] == 0 || (!needs_full.empty() && needs_full[f])) continue;
      if (!(slab_quality(f) < quality_floor)) continue;
      const std::vector<int> around = across(f);  // includes f
      auto worst = [&] {
        double q = HUGE_VAL;
        for (int g : around) q = std::min(q, slab_quality(g));
        return q;
      };
      const double old = alpha[f], before = worst();
      double best_alpha = old, best = before;
      for (double a = old > 1.0 / 64 ? old / 2 : 0.0;; a = a > 1.0 / 64 ? a / 2 : 0.0) {
        alpha[f] = a;
        bool ok = true;
        for (std::size_t i = 0; i < around.size() && ok; ++i) ok = face_check(around[i], eps) == 0;
        if (ok) {
          const double q = worst();
          if (q > best) best = q, best_alpha = a;
          if (q >= quality_floor) break;
        }
        if (a == 0) break;
      }
      alpha[f] = (best >= quality_floor || best >= 2 * before) ? best_alpha : old;
      if (alpha[f] < old) {
        ++lowered;
        quality_before = std::min(quality_before, before);
        quality_after = std::min(quality_after, best);
      }
    }
    alpha_lowered_for_quality = lowered;
  }
  // Parametric distortion of f's curved middle triangle at the current α: the smallest area
  // element |x_u × x_v| over the order-4k lattice of the triangle, counted as 0 where the patch's
  // normal turns against its linear triangle's (the patch folds), over the largest. 1 for a
  // uniform parametrization (every linear face). The area element is the boundary factor of the
  // Jacobian of every tet on the face, (x_u × x_v) · x_w, so a small one makes a flat curved tet
  // that no interior node can lift.
  double patch_distortion(int f) const {
    const auto d = node_displacements(f);
    std::vector<Eigen::Vector3d> x(tri_lattice.size());
    for (std::size_t i = 0; i < tri_lattice.size(); ++i)
      x[i] = linear_mid(f, double(tri_lattice[i][1]) / k, double(tri_lattice[i][2]) / k) + d[i];
    return triangle_area_element_ratio(k, x);
  }
  // A face whose fibers cross the input far apart (tilted pillars over a noisy or folded input)
  // gets a patch bunched toward one side or folded over, certified and within ε, whose slab tets
  // are flat on the boundary (noise_sphere_2, K = 3: curved MIPS 5.8e4 on a face whose area
  // element fell to 1.6% of its largest; 37 of its 1,184 faces folded). Each face that does not
  // need full curving and is below distortion_floor tries α / 2, α / 4, ..., 0, every step
  // checked like lower_for_quality (its slabs and those across its edges certified, ε held) and
  // not taking a neighbour, which shares its edge nodes, below min(its value, the floor); it
  // keeps the first α that reaches the floor, else the least distorted. A neighbour that the
  // straightened edges fold (its inside still curved) joins the step with the same α, and so
  // does a neighbour whose slabs no longer certify or that misses ε with those edges straight
  // (four rounds of joins at most). Without the first, noise_sphere_2 kept 7 folds (1 with);
  // without the second, tr12j_occt (K = 4) kept a folded patch whose slab tet had a sampled
  // scaled Jacobian of 2.7e-5 (straight shape 0.14): lowering it uncertified a neighbour's slabs.
  // Sequential.
  void lower_for_distortion(double eps) {
    // The last thickening's counts (a failed interior fill thickens again).
    distortion_faces_before = distortion_faces_after = folded_faces_before = folded_faces_after = 0;
    distorted_needed_after = 0;
    alpha_lowered_for_distortion = 0;
    std::vector<double> dist(static_cast<std::size_t>(nf));
    for (int f = 0; f < nf; ++f) {
      dist[std::size_t(f)] = patch_distortion(f);
      distortion_faces_before += dist[std::size_t(f)] < distortion_floor;
      folded_faces_before += dist[std::size_t(f)] == 0;
    }
    const std::vector<double> alpha_before = alpha;  // faces lowered: counted once, at the end
    auto lowerable = [&](int g) { return alpha[g] > 0 && (needs_full.empty() || !needs_full[g]); };
    for (int f = 0; f < nf; ++f) {
      if (!(dist[std::size_t(f)] < distortion_floor) || !lowerable(f)) continue;
      // Lowering f straightens its edges, which can fold a neighbour whose inside stays curved:
      // such a neighbour (one that may be lowered) joins the group and takes the same α.
      std::vector<std::pair<int, double>> group{{f, alpha[f]}};  // face, its α before
      std::vector<std::pair<int, double>> best_group;
      double best = dist[std::size_t(f)], best_a = -1;
      auto restore = [&] {
        for (const auto& [g, a] : group) alpha[g] = a;
      };
      for (double a = alpha[f] > 1.0 / 64 ? alpha[f] / 2 : 0.0;; a = a > 1.0 / 64 ? a / 2 : 0.0) {
        bool ok = false;
        for (int grow = 0; grow <= 4; ++grow) {
          for (const auto& [g, old] : group) alpha[g] = std::min(old, a);
          std::set<int> around;
          for (const auto& [g, old] : group)
            for (int h : across(g)) around.insert(h);
          auto in_group = [&](int h) {
            return std::any_of(group.begin(), group.end(),
                               [&](const auto& e) { return e.first == h; });
          };
          ok = true;
          int joined = 0;
          const std::size_t members = group.size();
          for (int h : around)
            if (face_check(h, eps) != 0) {
              ok = false;
              // A neighbour whose slabs no longer certify (or that misses ε) with the group's
              // edges straightened joins the group, if it may be lowered; if one may not, none
              // of this round joins (they would be lowered for nothing).
              if (in_group(h) || !lowerable(h)) {
                group.resize(members);
                joined = 0;
                break;
              }
              group.emplace_back(h, alpha[h]);
              ++joined;
            }
          if (!ok) {
            if (joined == 0) break;
            continue;
          }
          for (int h : around) {
            if (in_group(h)) continue;
            if (patch_distortion(h) >= std::min(dist[std::size_t(h)], distortion_floor)) continue;
            ok = false;
            if (lowerable(h)) {
              group.emplace_back(h, alpha[h]);
              ++joined;
            }
          }
          if (ok || joined == 0) break;
        }
        if (ok) {
          double worst = HUGE_VAL;
          for (const auto& [g, old] : group) worst = std::min(worst, patch_distortion(g));
          if (worst > best) {
            best = worst;
            best_a = a;
            best_group = group;
          }
          if (worst >= distortion_floor) break;
        }
        if (a == 0) break;
      }
      restore();
      if (best_a < 0) continue;
      std::set<int> changed;
      for (const auto& [g, old] : best_group) {
        alpha[g] = std::min(old, best_a);
        for (int h : across(g)) changed.insert(h);
      }
      for (int h : changed) dist[std::size_t(h)] = patch_distortion(h);
    }
    for (int f = 0; f < nf; ++f) {
      alpha_lowered_for_distortion += alpha[f] < alpha_before[std::size_t(f)];
      distortion_faces_after += dist[std::size_t(f)] < distortion_floor;
      folded_faces_after += dist[std::size_t(f)] == 0;
      distorted_needed_after +=
          dist[std::size_t(f)] < distortion_floor && !needs_full.empty() && needs_full[f];
    }
  }
  double distortion_floor = 0;
  int alpha_lowered_for_distortion = 0;
  int distortion_faces_before = 0, distortion_faces_after = 0;
  int folded_faces_before = 0, folded_faces_after = 0, distorted_needed_after = 0;
  double quality_floor = 0;
  int alpha_lowered_for_quality = 0;
  double quality_before = HUGE_VAL, quality_after = HUGE_VAL;

  // Certified slab tets and the distance bound at the face's input vertices: 0 when both hold,
  // 1 when the slabs are not certified, 2 when an input vertex is farther than eps.
  int face_check(int f, double eps) const {
    if (!slabs_certified(f)) return 1;
    if (alpha[f] == 0) return 0;  // the linear shell's bound was enforced by simplification
    // A face the curved-aware coarsening let beyond ε of its linear triangle meets ε only near
    // full curving: lowering its α cannot help (and would lower its edges' α, passing the miss on
    // to its neighbours). Its distance is checked once, at the end (build_attempt).
    if (!needs_full.empty() && needs_full[f]) return 0;
    return meets_eps(f, eps) ? 0 : 2;
  }
};

}  // namespace

namespace {

// Thrown by one attempt of the curved-aware coarsening when the final curved surface misses ε
// at input vertices the coarsening placed beyond ε of the linear surface: the surface vertices
// to keep under the linear bound next time.
struct CurvedBoundMissed {
  std::vector<int> vertices;
  // The input vertices of the faces across every needed face with a corner the thickening left
  // above the shell's base (where full curving became uncertain, missed or not).
  std::vector<int> above_base;
  std::vector<int> own;  // the input vertices of the faces that missed
  int faces = 0;
};

// What the attempts of the curved-aware coarsening share: the input's (beveled) shell and
// distance points, built once, and the coarse shell of the last attempt with the points each of
// its prisms owns, which the next attempt repairs locally (CurvedMeshOptions::curved_repair)
// instead of coarsening the input again.
// The two-phase coarsening's linear phase run on a thread of its own beside the first attempt
// (CurvedMeshOptions::concurrent_linear_phase). Destroying it cancels and joins the thread.
struct LinearPhaseRun {
  std::atomic<bool> cancel{false};
  std::thread thread;
  sh::Shell shell;
  sh::SimplifyStats stats;
  std::exception_ptr error;
  bool cancelled = false;
  double seconds = 0;
  LinearPhaseRun() = default;
  LinearPhaseRun(const LinearPhaseRun&) = delete;
  LinearPhaseRun& operator=(const LinearPhaseRun&) = delete;
  ~LinearPhaseRun() { stop(); }
  // Not needed any more: stops it at its next operation.
  void stop() {
    cancel.store(true, std::memory_order_relaxed);
    if (thread.joinable()) thread.join();
  }
  void wait() {
    if (thread.joinable()) thread.join();
  }
};

// The options of the linear phase: the attempt's, without the curved-aware bound.
sh::SimplifyOptions linear_phase_options(const sh::SimplifyOptions& attempt) {
  sh::SimplifyOptions linear = attempt;
  linear.curved_order = 0;
  linear.relaxed_distance = linear.curved_distance = 0;
  linear.strict_input_vertices.clear();
  linear.curved_slab_ok = nullptr;
  return linear;
}

struct CoarseState {
  bool built = false;   // beveled, points: the input's shell and distance points
  bool coarse = false;  // shell, owned, coarsen_stats: a coarse shell to repair
  bool repair = false;  // the next attempt repairs the coarse shell
  sh::BeveledShell beveled;
  sh::ShellStats shell_stats;
  sh::ThinRefineStats thin_stats;
  sh::ShapeRefineStats shape_stats;
  // The feature edges as vertex pairs of the refined surface (the input's when nothing bisected
  // one): the coarsening's chains run on them.
  std::vector<std::array<int, 2>> surface_features;
  std::vector<Eigen::Vector3d> points, point_bary;
  std::vector<int> point_faces, point_input_face;
  sh::Shell shell;
  std::vector<std::vector<int>> owned;
  CurvedMeshStats coarsen_stats;  // the stats after the coarsening that made `shell`
  // The input vertices a repair keeps under the linear bound: those of the faces that missed in
  // any attempt so far (and, once widened, around the slabs pulled above the shell's base). A
  // repair keeps every other face where it is, so the two edge steps of margin that a new
  // coarsening needs (its faces move) are tried only if the repair with these is refused.
  std::vector<char> repair_strict;
  int repairs = 0, repair_splits = 0, repair_failures = 0;
  // ε levels (build_curved_mesh_levels): the coarse shell of the finer level before, with its
  // owned points, from which this level's coarsening resumes instead of the input's shell.
  double shell_seconds = 0;  // building `beveled`
  bool resume = false;
  bool linear_phase_done = false;  // CurvedMeshOptions::two_phase
  int linear_phase_faces = 0;
  double linear_phase_seconds = 0;
  bool linear_phase_concurrent = false;  // it ran beside the first attempt
  sh::Shell start;
  std::vector<std::vector<int>> start_owned;
  // The input vertices the finer level's attempts kept under the linear bound: where its curved
  // surface missed ε, a coarser level's (larger faces, same thin parts) mostly misses too, so its
  // first attempt starts with them (each miss found again costs a whole attempt).
  std::vector<char> carried_strict;
  // The linear phase started beside the first attempt (declared last: destroyed, which joins its
  // thread, before the shell it reads).
  std::unique_ptr<LinearPhaseRun> linear_run;
  // The next level starts from the coarse shell the last one kept, with a fresh attempt loop.
  void next_level() {
    linear_run.reset();
    linear_phase_faces = 0;
    linear_phase_seconds = 0;
    linear_phase_concurrent = false;
    start = shell;
    start_owned = owned;
    resume = true;
    repair = false;
    repair_strict.clear();
    repairs = repair_splits = repair_failures = 0;
  }
};

CurvedMesh build_attempt(const SurfaceMesh& input, const CurvedMeshOptions& options,
                         const std::vector<char>& strict, bool relaxed, CurvedMeshStats& stats,
                         const ProgressFn& progress, CoarseState* state = nullptr) {
  if (options.order < 1 || options.order > k_max_order)
    throw InputError("mesh: order " + std::to_string(options.order) + " is not in 1..4");
  if (!(options.eps_rel > 0)) throw InputError("mesh: eps must be positive");
  std::unique_ptr<tbb::global_control> threads;
  if (options.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    std::size_t(options.threads));
  const double unit = bbox_longest_edge(input.V);
  const double eps = options.eps_rel * unit;
  stats.input_vertices = input.num_vertices();
  stats.input_faces = input.num_faces();
  stats.feature_edges = int(options.feature_edges.size());
  const std::vector<char> frozen = feature_vertices(input.num_vertices(), options.feature_edges);
  stats.frozen_vertices = int(std::count(frozen.begin(), frozen.end(), 1));

  // 1. Shell.
  CoarseState local_state;
  CoarseState& st = state ? *state : local_state;
  Stopwatch watch;
  const bool built_now = !st.built;
  if (built_now) {
    sh::ShellOptions shell_options;
    shell_options.max_thickness_rel = options.thickness_rel;
    shell_options.max_thickness_per_edge = options.thickness_per_edge;
    shell_options.threads = options.threads;
    // Topological beveling where the input's own shell is not a section (meshing/shell/
    // bevel.hpp): from here on the shell works on `surface`, the input refined without moving
    // it, whose vertices 0..#V-1 are the input's; the map and the returned shell refer to the
    // input again.
    // Thin parts first (meshing/shell/thin_refine.hpp): input edges much longer than the object
    // is thick there are bisected, so the coarsening's thickness guard has vertices to keep.
    // Poorly shaped long faces before that (refine_poor_shapes): CAD fans of needles and caps get
    // vertices inside their flat faces. Feature edges are bisected only where the coarsening will
    // run chains through the new vertices (otherwise they would all stay as frozen vertices).
    sh::ShapeRefineOptions shape;
    shape.max_mips = options.shape_refine_mips;
    shape.min_edge = options.shape_refine * eps;
    shape.min_cone_angle = options.shape_refine_spike_angle * M_PI / 180;
    shape.feature_edges = options.feature_edges;
    shape.bisect_features =
        options.feature_chains && options.constraint_points.empty() && options.eps_samples < 2;
    const sh::BeveledSurface shaped =
        sh::refine_poor_shapes(input, shape, st.shape_stats, st.surface_features);
    sh::ThinRefineOptions thin;
    thin.max_edge_per_thickness = options.thin_refine_ratio;
    thin.longest_edge_closure = options.thin_refine_closure;
    thin.max_child_mips = options.thin_refine_child_mips;
    thin.kept_edges = st.surface_features;
    sh::BeveledSurface refined =
        sh::refine_thin_parts(shaped.refined() ? shaped.mesh : input, thin, st.thin_stats);
    if (shaped.refined()) refined = sh::compose(shaped, std::move(refined));
    if (refined.refined()) {
      st.beveled =
          sh::build_beveled_shell(refined.mesh, shell_options, st.shell_stats, {}, progress);
      st.beveled.surface = sh::compose(refined, std::move(st.beveled.surface));
      st.shell_stats.input_vertices = input.num_vertices();
      st.shell_stats.input_faces = input.num_faces();
    } else {
      st.beveled = sh::build_beveled_shell(input, shell_options, st.shell_stats, {}, progress);
    }
  }
  const sh::BeveledShell& beveled = st.beveled;
  const SurfaceMesh& surface = beveled.surface.mesh;
  stats.beveled_faces = beveled.stats.beveled_faces;
  stats.thin_refined_faces = st.thin_stats.refined_faces;
  stats.thin_splits = st.thin_stats.splits;
  stats.thin_shape_refusals = st.thin_stats.shape_refusals;
  stats.thin_edges_before = st.thin_stats.thin_edges_before;
  stats.thin_edges_after = st.thin_stats.thin_edges_after;
  stats.thin_max_ratio_before = st.thin_stats.max_ratio_before;
  stats.thin_max_ratio_after = st.thin_stats.max_ratio_after;
  stats.shape_poor_before = st.shape_stats.poor_faces_before;
  stats.shape_spike_faces = st.shape_stats.spike_faces;
  stats.shape_poor_after = st.shape_stats.poor_faces_after;
  stats.shape_splits = st.shape_stats.splits;
  stats.shape_feature_splits = st.shape_stats.feature_splits;
  stats.shape_refined_faces = st.shape_stats.refined_faces;
  stats.shape_budget_reached = st.shape_stats.budget_reached;
  stats.singular_vertices = st.shell_stats.singular_vertices;
  stats.shell_faces = int(beveled.shell.F.rows());
  if (built_now) {
    st.shell_seconds = watch.seconds();
    stats.stage_seconds.emplace_back("shell", st.shell_seconds);
  }

  // Distance points besides the input vertices, on the shell's middle surface (the input): their
  // position, the shell face whose prism holds them, and the input face / barycentric
  // coordinates they stand for.
  std::vector<Eigen::Vector3d>& points = st.points;
  std::vector<int>&point_faces = st.point_faces, &point_input_face = st.point_input_face;
  std::vector<Eigen::Vector3d>& point_bary = st.point_bary;
  if (built_now) {
    const sh::Shell& shell = beveled.shell;
    auto bary_in = [](const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                      const Eigen::Vector3d& c) {
      const Eigen::Vector3d v0 = b - a, v1 = c - a, v2 = p - a;
      const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0),
                   d21 = v2.dot(v1), den = d00 * d11 - d01 * d01;
      const double v = (d11 * d20 - d01 * d21) / den, w = (d00 * d21 - d01 * d20) / den;
      return Eigen::Vector3d(1 - v - w, v, w);
    };
    auto add = [&](const Eigen::Vector3d& p, int f) {
      const int t = shell.face_parent[std::size_t(f)];
      Eigen::Vector3d w = bary_in(p, surface.V.row(surface.F(t, 0)), surface.V.row(surface.F(t, 1)),
                                  surface.V.row(surface.F(t, 2)));
      w = w.cwiseMax(0.0);
      w /= w.sum();
      const auto [face, bary] = beveled.surface.to_input(t, w);
      points.push_back(p);
      point_faces.push_back(f);
      point_input_face.push_back(face);
      point_bary.push_back(bary);
    };
    auto corner = [&](int f, int c) { return Eigen::Vector3d(shell.mid.row(shell.F(f, c))); };
    const int L = options.eps_samples;
    if (L >= 2)
      for (int f = 0; f < int(shell.F.rows()); ++f)
        for (int i = 0; i <= L; ++i)
          for (int j = 0; i + j <= L; ++j) {
            const int l = L - i - j;
            if (i == L || j == L || l == L) continue;  // a corner
            if (i == 0 || j == 0 || l == 0) {          // on an edge: once, from its p < q side
              const int zero = i == 0 ? 0 : j == 0 ? 1 : 2;
              const int p = shell.F(f, (zero + 1) % 3), q = shell.F(f, (zero + 2) % 3);
              if (!(p < q)) continue;
            }
            add((i * corner(f, 0) + j * corner(f, 1) + l * corner(f, 2)) / double(L), f);
          }
    if (!options.constraint_points.empty()) {
      const sh::InputSurfaceIndex index(surface.V, surface.F);
      std::vector<std::vector<int>> shell_faces(std::size_t(surface.num_faces()));
      for (int f = 0; f < int(shell.F.rows()); ++f)
        shell_faces[std::size_t(shell.face_parent[std::size_t(f)])].push_back(f);
      for (std::size_t i = 0; i < options.constraint_points.size(); ++i) {
        const Eigen::Vector3d& q = options.constraint_points[i];
        Eigen::Vector3d p;
        const int t = index.closest_face(q, p);
        if (t < 0 || !((p - q).norm() <= 1e-6 * unit))
          throw InputError("mesh: constraint point " + std::to_string(i) + " (" +
                           std::to_string(q.x()) + ", " + std::to_string(q.y()) + ", " +
                           std::to_string(q.z()) + ") is not on the input surface");
        int best = -1;
        double best_w = -HUGE_VAL;
        for (int f : shell_faces[std::size_t(t)]) {
          const double w = bary_in(p, corner(f, 0), corner(f, 1), corner(f, 2)).minCoeff();
          if (w > best_w) best_w = w, best = f;
        }
        add(p, best);
      }
    }
  }
  st.built = true;
  stats.distance_points = int(points.size());

  // Spatially varying ε (CurvedMeshOptions::eps_scale): the factor at every distance point of the
  // shell, in the simplification's numbering (the refined surface's vertices, then the extra
  // points), interpolated linearly over the input face each one lies in.
  std::vector<double> point_scale;
  if (!options.eps_scale.empty()) {
    if (int(options.eps_scale.size()) != input.num_vertices())
      throw InputError("mesh: the eps field has " + std::to_string(options.eps_scale.size()) +
                       " values for " + std::to_string(input.num_vertices()) + " input vertices");
    for (int v = 0; v < input.num_vertices(); ++v)
      if (!(options.eps_scale[std::size_t(v)] > 0 && options.eps_scale[std::size_t(v)] <= 1))
        throw InputError("mesh: the eps field at input vertex " + std::to_string(v) + " is " +
                         std::to_string(options.eps_scale[std::size_t(v)] * options.eps_rel) +
                         ", not in (0, eps]");
    auto at_input = [&](int t, const Eigen::Vector3d& w) {
      double s = 0;
      for (int c = 0; c < 3; ++c) s += w[c] * options.eps_scale[std::size_t(input.F(t, c))];
      return s;
    };
    const int nv = surface.num_vertices();
    point_scale.assign(std::size_t(nv) + points.size(), -1.0);
    for (int v = 0; v < input.num_vertices(); ++v)
      point_scale[std::size_t(v)] = options.eps_scale[std::size_t(v)];
    for (int t = 0; t < surface.num_faces(); ++t)
      for (int c = 0; c < 3; ++c) {
        const int v = surface.F(t, c);
        if (point_scale[std::size_t(v)] > 0) continue;
        const auto [face, w] = beveled.surface.to_input(t, Eigen::Vector3d::Unit(c));
        point_scale[std::size_t(v)] = at_input(face, w);
      }
    for (std::size_t i = 0; i < points.size(); ++i)
      point_scale[std::size_t(nv) + i] = at_input(point_input_face[i], point_bary[i]);
    for (double& s : point_scale) s = std::clamp(s, 1e-300, 1.0);  // unreferenced vertices
  }

  // 2. Coarsen under the distance bound.
  watch = Stopwatch();
  sh::SimplifyOptions simplify_options;
  simplify_options.threads = options.deterministic ? 1 : options.threads > 0 ? options.threads : 2;
  simplify_options.rounds = options.simplify_rounds;
  simplify_options.max_distance = eps;
  simplify_options.max_mips = options.max_triangle_mips;
  simplify_options.shape_slack = options.shape_slack;
  simplify_options.max_edge_per_thickness = options.max_edge_per_thickness;
  simplify_options.flips = options.shell_flips;
  simplify_options.pan = options.shell_pan;
  simplify_options.split_mips = options.shell_split_mips;
  simplify_options.extra_points = points;
  simplify_options.extra_point_faces = point_faces;
  simplify_options.distance_scale = point_scale;
  simplify_options.rotate = options.shell_rotate;
  simplify_options.zoom = options.shell_zoom_rel * unit;
  simplify_options.zoom_passes = options.shell_zoom_passes;
  simplify_options.section_cos = options.shell_pillar_cos;
  simplify_options.section_cos_relative = options.shell_pillar_cos_relative;
  simplify_options.min_reference_area_ratio = options.chain_min_area_ratio;
  simplify_options.frozen_input_vertices = frozen;
  simplify_options.frozen_input_vertices.resize(std::size_t(surface.num_vertices()), 0);
  if (!options.feature_edges.empty() && surface.num_vertices() > input.num_vertices()) {
    // The bevel's points on an input feature edge stay too: collapsed away, they would take the
    // coarse boundary off the feature (the validator's features_off_edges; seen on noisy scans
    // where most edges are features).
    std::set<std::pair<int, int>> features;
    for (const auto& e : options.feature_edges)
      features.insert({std::min(e[0], e[1]), std::max(e[0], e[1])});
    for (int f = 0; f < surface.num_faces(); ++f)
      for (int c = 0; c < 3; ++c) {
        const int v = surface.F(f, c);
        if (v < input.num_vertices()) continue;
        const Eigen::Vector3d w = beveled.surface.corner_bary[std::size_t(f)].col(c);
        const int parent = beveled.surface.face_parent[std::size_t(f)];
        int ends[2], n = 0;
        for (int i = 0; i < 3; ++i)
          if (w[i] != 0 && n < 2) ends[n++] = input.F(parent, i);
        if (n == 2 && (w.array() != 0).count() == 2 &&
            features.count({std::min(ends[0], ends[1]), std::max(ends[0], ends[1])}))
          simplify_options.frozen_input_vertices[std::size_t(v)] = 1;
      }
  }
  if (relaxed) {
    simplify_options.curved_order = options.order;
    simplify_options.relaxed_distance = options.curved_linear_factor * eps;
    simplify_options.curved_distance = options.curved_margin * eps;
    simplify_options.curved_min_area_ratio = options.curved_min_area_ratio;
    simplify_options.strict_input_vertices = strict;
    simplify_options.strict_input_vertices.resize(std::size_t(surface.num_vertices()), 0);
    // With an exterior the top half-prism becomes an outer slab with the same patch.
    simplify_options.curved_slab_ok = [k = options.order, exterior = options.exterior](
                                          const auto& base, const auto& mid, const auto& top,
                                          bool type_a, const auto& d) {
      return slab_certified(k, base, mid, false, type_a, d) &&
             (!exterior || slab_certified(k, top, mid, true, type_a, d));
    };
  }
  if (options.feature_chains && !options.feature_edges.empty()) {
    if (!points.empty())
      log::warn(
          "mesh: feature chains are not coarsened with distance points (constraints, "
          "eps_samples): feature vertices stay");
    else if (stats.beveled_faces > 0)
      log::warn("mesh: feature chains are not coarsened on a beveled shell: feature vertices stay");
    else {
      simplify_options.feature_edges = st.surface_features;
      simplify_options.collapse_chains = true;
    }
  }
  // The first curved-aware attempt coarsens the input's shell on one thread; its linear phase,
  // needed only if the attempt and its repair miss, starts beside it on the idle core.
  const int cores = options.threads > 0 ? options.threads : tbb::info::default_concurrency();
  if (relaxed && options.two_phase && options.concurrent_linear_phase && options.deterministic &&
      cores > 1 && beveled.shell.F.rows() <= options.concurrent_linear_phase_max_faces &&
      !st.coarse && !st.resume && !st.linear_phase_done && !st.linear_run) {
    st.linear_run = std::make_unique<LinearPhaseRun>();
    LinearPhaseRun* run = st.linear_run.get();
    sh::SimplifyOptions linear = linear_phase_options(simplify_options);
    linear.cancel = &run->cancel;
    run->thread = std::thread([run, linear = std::move(linear), &beveled, &surface] {
      Stopwatch clock;
      try {
        run->shell = sh::simplify_shell(beveled.shell, surface, linear, run->stats);
      } catch (const sh::SimplifyCancelled&) {
        run->cancelled = true;
      } catch (...) {
        run->error = std::current_exception();
      }
      run->seconds = clock.seconds();
    });
    st.linear_phase_concurrent = true;
  }
  // A deterministic coarsening's pillar rotations, growths and pans run as ordered levels on
  // every core, the same shell as on one thread. Also beside a concurrent linear phase: sharing
  // its core there cost less than giving the linear phase up (paired, 2 threads, against the
  // levels on the cores it leaves: armadillo 0.95x, homer 0.97x, rocker_arm 0.99x; without it:
  // 0.95x, 0.96x, and 1.25x on rocker_arm, whose linear phase is used). Against one thread for
  // these passes the whole runs are within noise (benchmarks/results/coarsening_speed_4.md).
  if (options.deterministic) simplify_options.smoothing_threads = cores;
  sh::SimplifyStats simplify_stats;
  sh::Shell shell;
  bool repaired = false;
  if (st.repair && st.coarse && relaxed) {
    // The local repair of the last attempt's coarse shell: the edges of the faces owning strict
    // points beyond ε of the linear surface are split at input vertices until no such point is
    // left (SimplifyOptions::repair); the rest of the coarse shell is kept.
    if (progress) progress("repair", 0.0);
    sh::SimplifyOptions repair_options = simplify_options;
    repair_options.repair = true;
    repair_options.owned_points = st.owned;
    repair_options.collapse_chains = false;
    repair_options.feature_edges = st.surface_features;  // never split (SimplifyOptions::repair)
    // First with only the missed faces' input vertices strict; where that is refused (a split's
    // new faces would need full curving that their slabs cannot certify, etc.), with every
    // strict vertex (the two edge steps around the misses), whose new faces need none.
    std::vector<const std::vector<char>*> sets;
    if (!st.repair_strict.empty()) sets.push_back(&st.repair_strict);
    sets.push_back(&strict);
    ++st.repairs;
    for (const std::vector<char>* set : sets) {
      repair_options.strict_input_vertices = *set;
      repair_options.strict_input_vertices.resize(std::size_t(surface.num_vertices()), 0);
      simplify_stats = sh::SimplifyStats();
      shell = sh::simplify_shell(st.shell, surface, repair_options, simplify_stats);
      if (simplify_stats.violating_points == 0) {
        repaired = true;
        break;
      }
    }
    if (repaired) {
      st.repair_splits += simplify_stats.splits;
      log::info("mesh: coarse shell repaired by ", simplify_stats.splits, " splits in ",
                simplify_stats.repair_passes, " passes: ", st.shell.F.rows(), " -> ",
                shell.F.rows(), " faces");
    } else {
      ++st.repair_failures;
      log::info("mesh: the repair left ", simplify_stats.violating_points,
                " input vertices beyond eps of the linear surface: coarsening again");
      simplify_stats = sh::SimplifyStats();
      // Each stage's seconds its own (the coarsening below starts its clock again).
      stats.stage_seconds.emplace_back("repair (failed)", watch.seconds());
      watch = Stopwatch();
    }
  }
  if (repaired) {
    // The coarsening's own figures stay those of the run that made the shell.
    std::vector<std::pair<std::string, double>> seconds = std::move(stats.stage_seconds);
    stats = st.coarsen_stats;
    stats.stage_seconds = std::move(seconds);
    stats.coarse_faces = int(shell.F.rows());
    stats.linear_max_distance_rel = simplify_stats.max_distance / unit;
    stats.stage_seconds.emplace_back("repair", watch.seconds());
  } else {
    if (progress) progress("coarsen", 0.0);
    bool resumed = false;
    if (options.two_phase && st.coarse && !st.resume && !st.linear_phase_done) {
      // Two-phase curved-aware coarsening: once the first attempt (coarsened from the input's
      // shell) has missed, the input's shell is coarsened once under the linear bound
      // everywhere, and every later attempt resumes from it (any strict set holds there, so no
      // attempt coarsens the input again; the last resort, the linear bound, starts there too).
      Stopwatch phase;
      sh::SimplifyStats linear_stats;
      if (st.linear_run) {
        // Started beside the first attempt: wait for it (the stage's time is the wait).
        LinearPhaseRun& run = *st.linear_run;
        run.wait();
        CF_VERIFY(!run.cancelled, "mesh: the concurrent linear phase was cancelled but is needed");
        if (run.error) std::rethrow_exception(run.error);
        st.start = std::move(run.shell);
        linear_stats = std::move(run.stats);
        st.linear_phase_seconds = run.seconds;
        st.linear_run.reset();
      } else {
        st.start = sh::simplify_shell(beveled.shell, surface,
                                      linear_phase_options(simplify_options), linear_stats);
        st.linear_phase_seconds = phase.seconds();
      }
      st.start_owned = std::move(linear_stats.owned_points);
      st.resume = st.linear_phase_done = true;
      st.linear_phase_faces = int(st.start.F.rows());
      stats.stage_seconds.emplace_back("coarsen (linear phase)", phase.seconds());
      watch = Stopwatch();  // "coarsen" below: the resumed coarsening only
      log::info("mesh: linear phase: shell ", beveled.shell.F.rows(), " prisms coarsened to ",
                st.start.F.rows());
    }
    if (st.resume) {
      // The start shell (the finer level's coarse shell, or the linear phase's), coarsened
      // further under this attempt's bounds (not smaller anywhere, so no point starts beyond its
      // bound unless a curved-aware attempt keeps a finer level's relaxed point strict; those
      // are repaired first, SimplifyOptions::resume).
      sh::SimplifyOptions resume_options = simplify_options;
      resume_options.resume = true;
      resume_options.owned_points = st.start_owned;
      shell = sh::simplify_shell(st.start, surface, resume_options, simplify_stats);
      resumed = simplify_stats.violating_points == 0;
      if (resumed)
        stats.coarsen_start_faces = int(st.start.F.rows());
      else {
        log::info("mesh: resuming from the start shell's ", st.start.F.rows(),
                  " coarse faces left ", simplify_stats.violating_points,
                  " points beyond the bound: coarsening the input's shell");
        simplify_stats = sh::SimplifyStats();
      }
    }
    if (!resumed)
      shell = sh::simplify_shell(beveled.shell, surface, simplify_options, simplify_stats);
    if (progress) progress("coarsen", 1.0);
    stats.coarse_faces = int(shell.F.rows());
    stats.coarsen_collapses = simplify_stats.collapses;
    stats.coarsen_flips = simplify_stats.flips;
    stats.coarsen_rotations = simplify_stats.rotations;
    stats.coarsen_zooms = simplify_stats.zooms;
    stats.coarsen_pans = simplify_stats.pans;
    stats.coarsen_splits = simplify_stats.splits;
    stats.coarsen_chain_collapses = simplify_stats.chain_collapses;
    stats.coarsen_relaxed_pillars = simplify_stats.relaxed_pillars;
    stats.coarsen_min_section_bound = simplify_stats.min_section_bound;
    stats.snapped_vertices = simplify_stats.snapped_vertices;
    stats.chain_max_distance_rel = simplify_stats.chain_max_distance / unit;
    for (const auto& [name, pass] : simplify_stats.passes) {
      auto it = std::find_if(stats.coarsen_seconds.begin(), stats.coarsen_seconds.end(),
                             [&](const auto& e) { return e.first == name; });
      if (it == stats.coarsen_seconds.end())
        stats.coarsen_seconds.emplace_back(name, pass.seconds);
      else
        it->second += pass.seconds;
    }
    stats.coarse_median_thickness_rel = simplify_stats.median_half_thickness / unit;
    {
      const auto& why = simplify_stats.collapse_rejections;
      stats.coarsen_rejections = {
          {"shape", why.shape},           {"distance", why.distance},
          {"positivity", why.positivity}, {"intersection", why.intersection},
          {"section", why.section},       {"coverage", why.coverage},
          {"curved", why.curved},         {"thickness", why.thickness}};
    }
    stats.coarse_min_thickness_rel = simplify_stats.min_half_thickness / unit;
    stats.linear_max_distance_rel = simplify_stats.max_distance / unit;
    stats.stage_seconds.emplace_back("coarsen", watch.seconds());
    log::info("mesh: shell ", stats.shell_faces, " prisms coarsened to ", stats.coarse_faces,
              " (linear distance ", stats.linear_max_distance_rel, " of bbox)");
    st.coarsen_stats = stats;
  }
  stats.curved_repairs = st.repairs;
  stats.repair_splits = st.repair_splits;
  stats.repair_failures = st.repair_failures;
  if (state) {
    st.shell = shell;
    st.owned = std::move(simplify_stats.owned_points);
    st.coarse = true;
  }

  watch = Stopwatch();
  const sh::ShellVerification shell_check = sh::verify_shell(shell, surface);
  stats.shell_section_verified = shell_check.section();
  stats.shell_non_section_prisms = shell_check.non_section_faces;
  stats.shell_min_pillar_cos = shell_check.min_pillar_cos;
  stats.shell_reference_collapsed_faces = shell_check.reference_collapsed_faces;
  if (!shell_check.positive() || !shell_check.separated() || !shell_check.embedded_reference())
    throw MeshingError("coarsen: the coarse shell failed verification (" +
                       std::to_string(shell_check.non_positive_faces) + " non-positive prisms, " +
                       std::to_string(shell_check.intersecting_input_faces) +
                       " input faces crossing base/top, " +
                       std::to_string(shell_check.reference_self_intersections) +
                       " self-intersecting faces of the feature chains' reference copy)");
  stats.stage_seconds.emplace_back("shell verification", watch.seconds());

  // 3. Curve.
  watch = Stopwatch();
  const int k = options.order;
  Builder b(shell, surface, k);
  b.exterior = options.exterior;
  b.recurve = options.recurve;
  b.embed = options.embed_boundary;
  b.quality_floor = options.curve_quality_floor;
  b.distortion_floor = options.curve_distortion_floor;
  b.low_degree = options.low_degree_slabs;
  b.extra = points;
  b.point_scale = &point_scale;
  b.compute_targets(progress);
  b.locate_input(progress);
  if (relaxed) b.find_needs_full(eps);
  stats.fiber_misses = b.fiber_misses;
  const int nf = b.nf, nv = b.nv;
  b.alpha.assign(nf, 1.0);
  b.smooth.assign(nf, options.low_degree_slabs ? 1 : 0);
  std::vector<int> deferred_top;     // linear faces whose outer slab only thicken() can certify
  std::vector<int> deferred_bottom;  // linear faces whose slabs the certificate left undecided
  std::vector<int> work(nf);
  for (int f = 0; f < nf; ++f) work[f] = f;
  while (!work.empty()) {
    ++stats.curving_rounds;
    std::vector<char> verdict(work.size(), 0);
    tbb::parallel_for(std::size_t(0), work.size(),
                      [&](std::size_t i) { verdict[i] = char(b.face_check(work[i], eps)); });
    std::vector<int> failing;
    for (std::size_t i = 0; i < work.size(); ++i)
      if (verdict[i] != 0) failing.push_back(work[i]);
    if (stats.curving_rounds == 1) {
      stats.curve_refused_certificate = int(std::count(verdict.begin(), verdict.end(), 1));
      stats.curve_refused_distance = int(std::count(verdict.begin(), verdict.end(), 2));
    }
    if (failing.empty()) break;
    std::vector<int> next;
    for (std::size_t i = 0; i < work.size(); ++i) {
      // A face whose low-degree slab is not certified takes the full shear first.
      const int f = work[i];
      if (verdict[i] == 1 && k > 2 && b.smooth[f]) {
        b.smooth[f] = 0;
        for (int g : b.across(f)) next.push_back(g);
      }
    }
    for (int f : failing) {
      if (k > 2 && !b.smooth[f] && std::find(next.begin(), next.end(), f) != next.end())
        continue;             // just sheared: checked again first
      if (b.alpha[f] == 0) {  // lower the faces across its edges that need full curving
        const std::vector<int> lowered = b.lower_for(f);
        for (int g : lowered)
          for (int h : b.across(g)) next.push_back(h);
        if (!lowered.empty()) continue;
      }
      if (b.alpha[f] == 0 && b.exterior && b.layer_certified(f, false)) {
        // Only the outer slab fails on the linear patch (the shell's top can leave a half-prism
        // too thin for the floating-point certificate): thicken() raises the outer surface and
        // re-certifies every face, so the face is left to it.
        deferred_top.push_back(f);
        continue;
      }
      if (b.alpha[f] == 0) {
        // The linear slab is positive by the shell's exact test (I1); a tet the floating-point
        // certificate leaves undecided (a slab as thin as the shell in a near-contact: the
        // split ring's 0.1 ε slit at K = 4) is left to thicken(), which deepens the slab and
        // re-certifies every face or fails. A tet certified non-positive stops here.
        bool non_positive = false;
        for (int layer = 0; layer < (b.exterior ? 2 : 1); ++layer)
          for (const auto& t : b.slab_tets(f, b.node_displacements(f), layer == 1))
            non_positive = non_positive || certify_tet_jacobian(k, t.nodes).verdict ==
                                               JacobianVerdict::non_positive;
        if (!non_positive) {
          deferred_bottom.push_back(f);
          continue;
        }
      }
      if (b.alpha[f] == 0) {
        std::string detail;
        for (int layer = 0; layer < (b.exterior ? 2 : 1); ++layer)
          for (const auto& t : b.slab_tets(f, b.node_displacements(f), layer == 1)) {
            const auto c = certify_tet_jacobian(k, t.nodes);
            detail += std::string(detail.empty() ? "" : "; ") + (layer ? "top" : "bottom") +
                      " tet (" + std::to_string(t.gid[0]) + " " + std::to_string(t.gid[1]) + " " +
                      std::to_string(t.gid[2]) + " " + std::to_string(t.gid[3]) + ") " +
                      (c.verdict == JacobianVerdict::positive       ? "positive"
                       : c.verdict == JacobianVerdict::non_positive ? "NOT positive"
                                                                    : "undecided") +
                      ", scaled Jacobian " + std::to_string(min_scaled_jacobian(k, t.nodes));
          }
        throw MeshingError("curve: the linear slab of coarse face " + std::to_string(f) +
                           " is not certified positive: " + detail);
      }
      b.lower_alpha(f);
      next.push_back(f);
      for (int e = 0; e < 3; ++e) {
        const int p = shell.F(f, e), q = shell.F(f, (e + 1) % 3);
        for (int g : b.edge_faces.at({std::min(p, q), std::max(p, q)})) next.push_back(g);
      }
    }
    std::sort(next.begin(), next.end());
    next.erase(std::unique(next.begin(), next.end()), next.end());
    work = std::move(next);
    if (progress) progress("curve: certify", 1.0 - double(work.size()) / nf);
  }
  std::sort(deferred_top.begin(), deferred_top.end());
  stats.curve_deferred_outer =
      int(std::unique(deferred_top.begin(), deferred_top.end()) - deferred_top.begin());
  std::sort(deferred_bottom.begin(), deferred_bottom.end());
  stats.curve_deferred_undecided =
      int(std::unique(deferred_bottom.begin(), deferred_bottom.end()) - deferred_bottom.begin());
  stats.stage_seconds.emplace_back("curve", watch.seconds());

  // 4. Thicken the slab layer(s), then fill the inside of the inner surface (and, with an
  // exterior, the region between the outer surface and a padded box, the outer surface entering
  // reversed as the box's cavity). Gmsh's boundary recovery can refuse a surface our exact check
  // accepts (near-contacts): retry with shallower layers, down to the repaired shell base / top.
  tetfill::TetFillOptions fill_options;
  fill_options.threads = options.threads;
  tetfill::TetFillResult fill, outside;
  int box_vertices = 0;
  auto fill_exterior = [&] {
    // The input's bounding box padded by pad on every side (where a case expects it), pushed
    // out where the outer surface comes closer to it than pad / 4.
    const auto [in_lo, in_hi] = padded_bounding_box(input.V, options.exterior_padding);
    const double margin = options.exterior_padding * unit / 4;
    const Eigen::Vector3d lo = in_lo.cwiseMin(b.outer.colwise().minCoeff().transpose() -
                                              Eigen::Vector3d::Constant(margin));
    const Eigen::Vector3d hi = in_hi.cwiseMax(b.outer.colwise().maxCoeff().transpose() +
                                              Eigen::Vector3d::Constant(margin));
    const SurfaceMesh box = make_box(lo, hi, 4);
    stats.exterior_box_lo = lo;
    stats.exterior_box_hi = hi;
    box_vertices = box.num_vertices();
    Eigen::MatrixXd V(nv + box_vertices, 3);
    V << b.outer, box.V;
    Eigen::MatrixXi F(nf + box.num_faces(), 3);
    for (int f = 0; f < nf; ++f) F.row(f) << shell.F(f, 0), shell.F(f, 2), shell.F(f, 1);
    F.bottomRows(box.num_faces()) = box.F.array() + nv;
    try {
      outside = tetfill::fill_interior(V, F, fill_options);
    } catch (const MeshingError& e) {
      throw MeshingError(std::string("exterior: ") + e.what());
    }
  };
  double depth = std::max(options.slab_depth, 0.0);
  for (int attempt = 0;; ++attempt) {
    watch = Stopwatch();
    stats.thickened_vertices = b.thicken(depth, eps);
    stats.outer_raised_vertices = b.outer_raised;
    stats.outer_lowered_vertices = b.outer_lowered;
    stats.faces_recurved = b.alpha_raised;
    stats.faces_lowered_for_quality = b.alpha_lowered_for_quality;
    stats.faces_lowered_for_distortion = b.alpha_lowered_for_distortion;
    stats.distorted_faces_before = b.distortion_faces_before;
    stats.distorted_faces_after = b.distortion_faces_after;
    stats.folded_faces_before = b.folded_faces_before;
    stats.folded_faces_after = b.folded_faces_after;
    stats.distorted_needed_after = b.distorted_needed_after;
    stats.embedding_pairs_before = b.embedding_pairs_before;
    stats.embedding_pairs_after = b.embedding_pairs_after;
    stats.embedding_rounds = b.embedding_rounds;
    stats.faces_lowered_for_embedding = int(b.embedding_lowered.size());
    if (b.embedding_pairs_after > 0)
      log::warn("mesh: ", b.embedding_pairs_after,
                " pairs of curved boundary faces still intersect where no curving could be lowered"
                " (faces the curved-aware coarsening needs fully curved)");
    stats.faces_sheared = b.shear_faces();
    stats.stage_seconds.emplace_back(attempt ? "thicken (retry)" : "thicken", watch.seconds());
    watch = Stopwatch();
    if (progress) progress("fill interior", 0.0);
    try {
      fill = tetfill::fill_interior(b.inner, shell.F, fill_options);
      stats.stage_seconds.emplace_back("fill interior", watch.seconds());
      if (options.exterior) {
        watch = Stopwatch();
        if (progress) progress("fill exterior", 0.0);
        fill_exterior();
        stats.stage_seconds.emplace_back("fill exterior", watch.seconds());
      }
      break;
    } catch (const MeshingError& e) {
      if (depth == 0) throw;
      log::warn("mesh: filling the inner", options.exterior ? " or outer" : "",
                " surface at slab depth ", depth, " failed (", e.what(), ")");
      depth = depth > 0.1 ? depth / 2 : 0.0;
    }
  }

  // The curved-aware coarsening placed input vertices up to curved_linear_factor × ε from the
  // linear surface, counting on full curving. Where the final patch (a lower α: slabs not
  // certified) misses ε at one of its points, the attempt is given up, naming the points of
  // those faces and of the faces within two edge steps of them. (Measured on spot and bunny: the
  // misses are faces whose slab was certified on the shell's base in the coarsening, but whose
  // inner surface the thickening had to pull above that base, where the base self-intersects
  // in thin parts, so their α dropped.)
  if (relaxed) {
    std::vector<char> bad(nf, 0);
    tbb::parallel_for(0, nf, [&](int f) { bad[f] = !b.meets_eps(f, eps); });
    CurvedBoundMissed missed;
    std::vector<char> near(nf, 0);
    for (int f = 0; f < nf; ++f) {
      if (!bad[f]) continue;
      ++missed.faces;
      for (int g : b.across(f))
        for (int h : b.across(g)) near[h] = 1;
    }
    if (missed.faces > 0) {
      std::vector<char> above(nf, 0);
      for (int f = 0; f < nf; ++f)
        if (b.needs_full[f] && (b.pulled_above[shell.F(f, 0)] || b.pulled_above[shell.F(f, 1)] ||
                                b.pulled_above[shell.F(f, 2)]))
          for (int g : b.across(f)) above[g] = 1;
      for (int f = 0; f < nf; ++f)
        for (const Owned& o : b.owned[f])
          if (o.vertex < surface.num_vertices()) {
            if (near[f]) missed.vertices.push_back(o.vertex);
            if (above[f]) missed.above_base.push_back(o.vertex);
            if (bad[f]) missed.own.push_back(o.vertex);
          }
      throw missed;
    }
  }
  // This attempt meets ε: no later one will need the linear phase.
  st.linear_run.reset();

  for (int f = 0; f < nf; ++f) {
    if (b.alpha[f] == 1)
      ++stats.faces_fully_curved;
    else if (b.alpha[f] == 0)
      ++stats.faces_linear;
    else
      ++stats.faces_blended;
  }

  // 5. Flip the straight interior toward better tets (its boundary, the inner surface, is kept).
  auto flip = [&](tetfill::TetFillResult& part) {
    if (options.optimize.sweeps <= 0 || !options.optimize.flips) return;
    watch = Stopwatch();
    if (progress) progress("optimize: interior flips", 0.0);
    editing::FlipOptions flip_options;
    flip_options.threads = options.deterministic ? 1 : std::max(options.threads, 1);
    const editing::FlipResult flipped = editing::flip_tets(part.V, part.T, flip_options);
    auto& f = stats.optimize.flips;
    const long long before = part.T.rows(), after = flipped.T.rows();
    f.mean_energy_before = (f.mean_energy_before * double(f.tets_before) +
                            flipped.mean_energy_before * double(before)) /
                           double(f.tets_before + before);
    f.mean_energy_after =
        (f.mean_energy_after * double(f.tets_after) + flipped.mean_energy_after * double(after)) /
        double(f.tets_after + after);
    f.tets_before += before;
    f.tets_after += after;
    f.count += (long long)flipped.pass.succeeded;
    f.max_energy_before = std::max(f.max_energy_before, flipped.max_energy_before);
    f.max_energy_after = std::max(f.max_energy_after, flipped.max_energy_after);
    f.seconds += watch.seconds();
    part.T = flipped.T;
    stats.stage_seconds.emplace_back("flips", watch.seconds());
  };
  flip(fill);

  if (options.exterior) {
    flip(outside);
    stats.exterior_tets = int(outside.T.rows());
  }

  // 6. Stitch.
  watch = Stopwatch();
  std::unordered_map<NodeKey, int, NodeKeyHash> node_id;
  std::vector<Eigen::Vector3d> nodes;
  std::vector<std::vector<int>> cells;
  std::vector<int> tags;
  const auto& tet_lattice = lagrange_lattice(CellKind::tetrahedron, k);
  auto add_tet = [&](const TetNodes& t, int tag) {
    std::vector<int> row(tet_lattice.size());
    for (std::size_t n = 0; n < tet_lattice.size(); ++n) {
      const NodeKey key = make_node_key(t.gid.data(), tet_lattice[n], 4);
      auto [it, inserted] = node_id.try_emplace(key, int(nodes.size()));
      if (inserted) nodes.push_back(t.nodes.row(Eigen::Index(n)).transpose());
      row[n] = it->second;
    }
    cells.push_back(std::move(row));
    tags.push_back(tag);
  };
  auto add_straight = [&](const tetfill::TetFillResult& part, int tag,
                          const std::function<int(int)>& gid_of) {
    for (int c = 0; c < int(part.T.rows()); ++c) {
      TetNodes t;
      Eigen::Vector3d P[4];
      for (int j = 0; j < 4; ++j) {
        const int v = part.T(c, j);
        t.gid[j] = gid_of(v);
        P[j] = part.V.row(v).transpose();
      }
      t.nodes.resize(Eigen::Index(tet_lattice.size()), 3);
      for (std::size_t n = 0; n < tet_lattice.size(); ++n) {
        Eigen::Vector3d x = Eigen::Vector3d::Zero();
        for (int j = 0; j < 4; ++j) x += (double(tet_lattice[n][j]) / k) * P[j];
        t.nodes.row(Eigen::Index(n)) = x.transpose();
      }
      add_tet(t, tag);
    }
  };
  for (int f = 0; f < nf; ++f) {
    const auto d = b.node_displacements(f);
    for (const auto& t : b.slab_tets(f, d)) {
      add_tet(t, 1);
      ++stats.slab_tets;
    }
    if (options.exterior)
      for (const auto& t : b.slab_tets(f, d, true)) {
        add_tet(t, 3);
        ++stats.outer_slab_tets;
      }
  }
  // Global corner ids: 0..nv base, nv..2nv middle, 2nv..3nv top, then the interior's Steiner
  // points, the box corners and the exterior's Steiner points.
  const int inner_steiner = int(fill.V.rows()) - nv;
  add_straight(fill, 2, [&](int v) { return v < nv ? b.gid_base(v) : 3 * nv + (v - nv); });
  stats.interior_tets = int(fill.T.rows());
  if (options.exterior)
    add_straight(outside, 4,
                 [&](int v) { return v < nv ? b.gid_top(v) : 3 * nv + inner_steiner + (v - nv); });
  CurvedMesh out;
  out.mesh.kind = CellKind::tetrahedron;
  out.mesh.order = k;
  out.mesh.nodes.resize(Eigen::Index(nodes.size()), 3);
  for (std::size_t n = 0; n < nodes.size(); ++n) out.mesh.nodes.row(Eigen::Index(n)) = nodes[n];
  out.mesh.cells.resize(Eigen::Index(cells.size()), Eigen::Index(tet_lattice.size()));
  out.mesh.cell_tags.resize(Eigen::Index(cells.size()));
  for (std::size_t c = 0; c < cells.size(); ++c) {
    for (std::size_t n = 0; n < cells[c].size(); ++n)
      out.mesh.cells(Eigen::Index(c), Eigen::Index(n)) = cells[c][n];
    out.mesh.cell_tags[Eigen::Index(c)] = tags[c];
  }
  stats.nodes = int(nodes.size());
  stats.stage_seconds.emplace_back("stitch", watch.seconds());

  // Boundary map: the curved middle triangles (rotated to their smallest shell id, so (u, v) of
  // the shell projection are their reference coordinates) and every input vertex's place.
  watch = Stopwatch();
  const auto& tri_lattice = lagrange_lattice(CellKind::triangle, k);
  std::vector<int> local_of(nodes.size(), -1), volume_of;
  Eigen::MatrixXi bcells(nf, Eigen::Index(tri_lattice.size()));
  for (int f = 0; f < nf; ++f) {
    const int gid[3] = {b.gid_mid(b.rotated(f, 0)), b.gid_mid(b.rotated(f, 1)),
                        b.gid_mid(b.rotated(f, 2))};
    for (std::size_t n = 0; n < tri_lattice.size(); ++n) {
      const auto it = node_id.find(make_node_key(gid, tri_lattice[n], 3));
      CF_VERIFY(it != node_id.end(), "stitch: a boundary node of coarse face " + std::to_string(f) +
                                         " belongs to no tet");
      if (local_of[it->second] < 0) {
        local_of[it->second] = int(volume_of.size());
        volume_of.push_back(it->second);
      }
      bcells(f, Eigen::Index(n)) = local_of[it->second];
    }
  }
  BoundaryMap& map = out.map;
  map.boundary.kind = CellKind::triangle;
  map.boundary.order = k;
  map.boundary.cells = bcells;
  map.boundary.nodes.resize(Eigen::Index(volume_of.size()), 3);
  map.boundary_node_to_volume.resize(Eigen::Index(volume_of.size()));
  for (std::size_t i = 0; i < volume_of.size(); ++i) {
    map.boundary.nodes.row(Eigen::Index(i)) = nodes[volume_of[i]].transpose();
    map.boundary_node_to_volume[Eigen::Index(i)] = volume_of[i];
  }
  map.feature_edges = options.feature_edges;
  map.eps_scale = options.eps_scale;
  map.vertex_face = Eigen::VectorXi::Constant(input.num_vertices(), -1);
  map.vertex_uv = Eigen::MatrixXd::Zero(input.num_vertices(), 2);
  const int np = int(points.size());
  map.point_input_face.resize(np);
  map.point_bary.resize(np, 3);
  map.point_face = Eigen::VectorXi::Constant(np, -1);
  map.point_uv.resize(np, 2);
  for (int i = 0; i < np; ++i) {
    map.point_input_face[i] = point_input_face[std::size_t(i)];
    map.point_bary.row(i) = point_bary[std::size_t(i)].transpose();
  }
  for (int f = 0; f < nf; ++f)
    for (const Owned& o : b.owned[f]) {
      if (o.vertex >= surface.num_vertices()) {  // a distance point
        const int i = o.vertex - surface.num_vertices();
        map.point_face[i] = f;
        map.point_uv(i, 0) = o.u;
        map.point_uv(i, 1) = o.v;
        continue;
      }
      if (o.vertex >= input.num_vertices()) continue;  // added by beveling
      map.vertex_face[o.vertex] = f;
      map.vertex_uv(o.vertex, 0) = o.u;
      map.vertex_uv(o.vertex, 1) = o.v;
    }
  stats.stage_seconds.emplace_back("boundary map", watch.seconds());

  // 7. Smooth the inner surface, the interior (and the exterior); the curved surface's nodes are
  // frozen (with an exterior they are not on the mesh boundary).
  // Collapses and flips of the stitched mesh come first (curved_edit.hpp): they renumber the
  // nodes, so the map's boundary nodes follow.
  watch = Stopwatch();
  auto frozen_nodes = [&] {
    std::vector<char> frozen(std::size_t(out.mesh.num_nodes()), 0);
    for (Eigen::Index i = 0; i < map.boundary_node_to_volume.size(); ++i)
      frozen[std::size_t(map.boundary_node_to_volume[i])] = 1;
    return frozen;
  };
  // Edits before and after the smoothing: the first pass removes what the smoothing cannot move
  // (the stitched slabs' flat and needle cells), the second what the smoothing left.
  CurvedEditStats edits;
  bool edited_once = false;
  // The flips for the mean (CurvedEditOptions::mean_flips) run alone, after everything else
  // (`mean_only`), so the mesh's worst cells are those of the other steps: no new cell falls below
  // min(its cavity's smallest scaled Jacobian, 0.1) nor rises above max(its cavity's worst
  // curved MIPS, 30). Run in the edits before the smoothing they changed what it did (fandisk
  // K = 4, max curved MIPS 413 -> 587); in the edits after it, what the search for the worst
  // cells did (a torus, K = 4: min scaled Jacobian 0.0082 -> 0.0074).
  auto edit = [&](bool mean_only) {
    if (options.optimize.edits.passes <= 0) return;
    CurvedEditOptions edit_options = options.optimize.edits;
    if (mean_only)
      edit_options.collapses = edit_options.flips = edit_options.splits = false;
    else
      edit_options.mean_flips = false;
    const CurvedEditResult edited =
        edit_curved_mesh(out.mesh, frozen_nodes(), edit_options, progress);
    if (edited_once)
      accumulate(edits, edited.stats);
    else
      edits = edited.stats;
    edited_once = true;
    for (Eigen::Index i = 0; i < map.boundary_node_to_volume.size(); ++i)
      map.boundary_node_to_volume[i] = edited.node_map[std::size_t(map.boundary_node_to_volume[i])];
    stats.nodes = out.mesh.num_nodes();
    stats.slab_tets = stats.interior_tets = stats.outer_slab_tets = stats.exterior_tets = 0;
    for (Eigen::Index c = 0; c < out.mesh.cell_tags.size(); ++c) {
      const int tag = out.mesh.cell_tags[c];
      (tag == 1   ? stats.slab_tets
       : tag == 2 ? stats.interior_tets
       : tag == 3 ? stats.outer_slab_tets
                  : stats.exterior_tets) += 1;
    }
  };
  edit(/*mean_only=*/false);
  if (options.optimize.sweeps > 0) {
    const std::vector<char> frozen = frozen_nodes();
    const OptimizeStats::Flips flips = stats.optimize.flips;
    OptimizeOptions smoothing = options.optimize;
    smoothing.worst_sweeps = smoothing.mean_sweeps = 0;
    stats.optimize = optimize_vertices(out.mesh, smoothing, progress, &frozen);
    stats.optimize.flips = flips;
    edit(/*mean_only=*/false);
    // The search for the worst cells comes last: the edits after the smoothing would otherwise
    // undo its moves (cheese K = 3: 107 tets below 0.01 with the search before them, 100 without
    // it).
    if (options.optimize.worst_sweeps > 0 || options.optimize.mean_sweeps > 0) {
      OptimizeOptions worst = options.optimize;
      worst.sweeps = worst.node_sweeps = 0;
      const std::vector<char> frozen_now = frozen_nodes();
      const OptimizeStats w = optimize_vertices(out.mesh, worst, progress, &frozen_now);
      stats.optimize.worst_movable = w.worst_movable;
      stats.optimize.worst_sweeps = w.worst_sweeps;
      stats.optimize.worst_visits = w.worst_visits;
      stats.optimize.worst_moves = w.worst_moves;
      stats.optimize.worst_sj_before = w.worst_sj_before;
      stats.optimize.worst_sj_after = w.worst_sj_after;
      stats.optimize.worst_seconds = w.worst_seconds;
      stats.optimize.worst_mips_movable = w.worst_mips_movable;
      stats.optimize.worst_mips_visits = w.worst_mips_visits;
      stats.optimize.worst_mips_moves = w.worst_mips_moves;
      stats.optimize.worst_mips_before = w.worst_mips_before;
      stats.optimize.worst_mips_after = w.worst_mips_after;
      stats.optimize.mean_mips_movable = w.mean_mips_movable;
      stats.optimize.mean_mips_visits = w.mean_mips_visits;
      stats.optimize.mean_mips_moves = w.mean_mips_moves;
      stats.optimize.mean_variation_guard = w.mean_variation_guard;
      stats.optimize.mean_mips_before = w.mean_mips_before;
      stats.optimize.mean_mips_after = w.mean_mips_after;
      stats.optimize.rejected_by_certificate += w.rejected_by_certificate;
      stats.optimize.max_energy_after = w.max_energy_after;
      stats.optimize.mean_energy_after = w.mean_energy_after;
      stats.optimize.seconds += w.seconds;
    }
  }
  if (options.optimize.edits.mean_flips) edit(/*mean_only=*/true);
  stats.optimize.edits = edits;
  for (Eigen::Index i = 0; i < map.boundary_node_to_volume.size(); ++i)
    CF_VERIFY((out.mesh.nodes.row(map.boundary_node_to_volume[i]) - map.boundary.nodes.row(i))
                      .cwiseAbs()
                      .maxCoeff() == 0,
              "optimize: a node of the curved surface moved");
  stats.stage_seconds.emplace_back("optimize", watch.seconds());
  sh::restore_input_ids(shell, beveled.surface);
  out.shell = std::move(shell);
  log::info("mesh: ", stats.slab_tets, " slab + ", stats.interior_tets, " interior + ",
            stats.outer_slab_tets + stats.exterior_tets, " exterior tets of order ", k,
            "; faces curved/blended/linear ", stats.faces_fully_curved, "/", stats.faces_blended,
            "/", stats.faces_linear);
  return out;
}

// The attempts of the curved-aware coarsening; `thin_refined` receives the input faces the thin
// refinement refined (0 when it refined nothing), also when an attempt throws.
CurvedMesh build_with_attempts(const SurfaceMesh& input, const CurvedMeshOptions& options,
                               CurvedMeshStats& stats, const ProgressFn& progress,
                               CoarseState& state) {
  const bool curved = options.curved_coarsening && options.order >= 2 &&
                      options.curved_linear_factor > 1 && options.curved_attempts > 0;
  if (!curved) return build_attempt(input, options, {}, false, stats, progress, &state);
  // Curved-aware attempts, each keeping more input vertices under the linear bound; the last
  // resort is the linear bound everywhere (whose α = 0 fallback always meets ε).
  std::vector<char> strict = state.resume ? state.carried_strict : std::vector<char>();
  std::vector<std::pair<std::string, double>> discarded;
  int last_misses = INT_MAX;
  bool give_up = false, widened = false;
  std::vector<int> above_base;  // from every discarded attempt
  for (int attempt = 1;; ++attempt) {
    const bool relaxed = !give_up && attempt <= options.curved_attempts;
    state.repair = options.curved_repair && relaxed && attempt > 1;
    CurvedMeshStats s;
    Stopwatch watch;
    const bool had_shell = state.built;
    try {
      CurvedMesh out = build_attempt(input, options, strict, relaxed, s, progress, &state);
      s.curved_coarsening = relaxed;
      s.curved_attempts = attempt;
      s.strict_vertices = int(std::count(strict.begin(), strict.end(), 1));
      s.curved_widened = widened;
      s.linear_phase_faces = state.linear_phase_faces;
      s.linear_phase_seconds = state.linear_phase_seconds;
      s.linear_phase_concurrent = state.linear_phase_concurrent;
      s.stage_seconds.insert(s.stage_seconds.begin(), discarded.begin(), discarded.end());
      stats = std::move(s);
      state.carried_strict = strict;
      return out;
    } catch (const CurvedBoundMissed& missed) {
      // The shell built by this attempt is kept for the next ones: its time is its own stage.
      double seconds = watch.seconds();
      if (!had_shell && state.built) {
        seconds -= state.shell_seconds;
        discarded.emplace_back("shell", state.shell_seconds);
      }
      discarded.emplace_back("discarded attempt " + std::to_string(attempt), seconds);
      if (strict.empty()) strict.assign(std::size_t(input.num_vertices()), 0);
      auto keep_linear = [&](const std::vector<int>& vertices) {
        for (int x : vertices) {
          if (std::size_t(x) >= strict.size()) strict.resize(std::size_t(x) + 1, 0);
          strict[std::size_t(x)] = 1;
        }
      };
      keep_linear(missed.vertices);
      auto keep_repaired = [&](const std::vector<int>& vertices) {
        auto& r = state.repair_strict;
        for (int x : vertices) {
          if (std::size_t(x) >= r.size()) r.resize(std::size_t(x) + 1, 0);
          r[std::size_t(x)] = 1;
        }
      };
      keep_repaired(missed.own);
      above_base.insert(above_base.end(), missed.above_base.begin(), missed.above_base.end());
      // Misses that do not drop mean the thickening keeps pulling the inner surface above the
      // shell's base somewhere else (thin parts): once, every needed face where it did so in any
      // attempt so far keeps the linear bound around it; after that, the linear bound everywhere.
      const bool no_fewer = missed.faces >= last_misses;
      const bool widen = no_fewer && !widened;
      give_up = no_fewer && widened;
      if (widen) {
        keep_linear(above_base);
        keep_repaired(above_base);
        widened = true;
      }
      last_misses = missed.faces;
      log::info("mesh: curved-aware coarsening, attempt ", attempt, ": ", missed.faces,
                " coarse faces miss eps once curved; ",
                give_up ? "no fewer than before: the linear bound next"
                : widen ? "no fewer than before: the input vertices around every face whose "
                          "slab was pulled above the shell's base keep the linear bound next"
                        : std::to_string(missed.vertices.size()) +
                              " input vertices near them keep the linear bound next");
    }
  }
}

// φ of every input vertex pulled back along the coarse shell's fibers (the projection the
// boundary map's inverse uses): "" when each lands within 1e-6 of the bounding box's longest
// edge of its vertex, else what missed and where. A φ(v) on an edge or a corner of its boundary
// triangle is pulled back from every triangle around that edge or corner too (1e-13 inside): the
// inverse finds the point from its position and may take any of them (CGAL's spool.off: a chain
// vertex whose image on a coarse feature edge came back from the other side 7.4e-3 away).
std::string fiber_roundtrip_miss(const CurvedMesh& m, const SurfaceMesh& input) {
  const FiberProjection projection(sh::fibers_of(m.shell, input), input);
  const double unit = bbox_longest_edge(input.V);
  // Boundary triangle f's corners in the map's order (the shell face rotated to its smallest
  // id), and the triangles around each vertex.
  const int nf = int(m.shell.F.rows());
  std::vector<std::array<int, 3>> corners;
  corners.resize(std::size_t(nf));
  std::unordered_map<int, std::vector<int>> around;
  for (int f = 0; f < nf; ++f) {
    const Eigen::Vector3i F = m.shell.F.row(f);
    const int r = min_rotation(F);
    for (int c = 0; c < 3; ++c) {
      corners[std::size_t(f)][std::size_t(c)] = F[(r + c) % 3];
      around[F[c]].push_back(f);
    }
  }
  double worst = 0;
  int worst_vertex = -1, misses = 0;
  for (int v = 0; v < m.map.num_input_vertices(); ++v) {
    const int f = m.map.vertex_face[v];
    if (f < 0 || f >= nf) continue;
    const double u = m.map.vertex_uv(v, 0), w = m.map.vertex_uv(v, 1);
    // The point as weights on shell vertices (zero weights dropped).
    const std::array<double, 3> bary{1 - u - w, u, w};
    std::vector<std::pair<int, double>> weights;
    for (int c = 0; c < 3; ++c)
      if (bary[std::size_t(c)] != 0)
        weights.emplace_back(corners[std::size_t(f)][std::size_t(c)], bary[std::size_t(c)]);
    std::vector<int> faces{f};
    if (weights.size() < 3)  // on an edge or a corner: every triangle holding all its vertices
      for (int g : around[weights.front().first]) {
        bool holds = g != f;
        for (const auto& [x, unused] : weights)
          holds = holds &&
                  std::count(corners[std::size_t(g)].begin(), corners[std::size_t(g)].end(), x) > 0;
        if (holds) faces.push_back(g);
      }
    double error = 0;
    for (int g : faces) {
      std::array<double, 3> b{0, 0, 0};
      for (const auto& [x, weight] : weights)
        for (int c = 0; c < 3; ++c)
          if (corners[std::size_t(g)][std::size_t(c)] == x) b[std::size_t(c)] = weight;
      // Just inside g (1e-13 toward its other corners): the inverse locates points to rounding,
      // and the fibers must agree on both sides of the edge, not only on it.
      if (g != f) {
        double sum = 0;
        for (double& x : b) sum += (x += 1e-13);
        for (double& x : b) x /= sum;
      }
      const auto p = g == f ? projection.project(f, u, w) : projection.project(g, b[1], b[2]);
      error =
          std::max(error, p ? (p->position - input.V.row(v).transpose()).norm() / unit : HUGE_VAL);
    }
    if (error > 1e-6) ++misses;
    if (error > worst || worst_vertex < 0) worst = error, worst_vertex = v;
  }
  if (misses == 0) return "";
  return "the boundary map's round trip misses " + std::to_string(misses) +
         " input vertices (worst: vertex " + std::to_string(worst_vertex) + " by " +
         std::to_string(worst) + " of the bounding box)";
}

}  // namespace

CurvedMesh build_curved_mesh(const SurfaceMesh& input, const CurvedMeshOptions& options,
                             CurvedMeshStats& stats, const ProgressFn& progress) {
  std::vector<CurvedMeshStats> level_stats;
  std::vector<CurvedMesh> out = build_curved_mesh_levels(
      input, options, {{options.eps_rel, options.eps_scale}}, level_stats, progress);
  stats = std::move(level_stats.front());
  return std::move(out.front());
}

std::vector<CurvedMesh> build_curved_mesh_levels(const SurfaceMesh& input,
                                                 const CurvedMeshOptions& options,
                                                 const std::vector<EpsLevel>& levels,
                                                 std::vector<CurvedMeshStats>& stats,
                                                 const ProgressFn& progress) {
  if (levels.empty()) throw InputError("mesh: no eps level given");
  for (std::size_t i = 0; i < levels.size(); ++i) {
    if (!(levels[i].eps_rel > 0))
      throw InputError("mesh: eps level " + std::to_string(i + 1) + " is not positive");
    for (std::size_t j = 0; j < i; ++j)
      if (levels[j].eps_rel == levels[i].eps_rel)
        throw InputError("mesh: eps level " + std::to_string(i + 1) + " repeats level " +
                         std::to_string(j + 1));
  }
  // Finest first: a coarse shell within the smaller bounds is within the larger ones.
  std::vector<std::size_t> order(levels.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return levels[a].eps_rel < levels[b].eps_rel;
  });
  auto run = [&](const CurvedMeshOptions& base, CoarseState& state) {
    std::vector<CurvedMesh> out(levels.size());
    stats.assign(levels.size(), CurvedMeshStats());
    for (std::size_t n = 0; n < order.size(); ++n) {
      const std::size_t i = order[n];
      CurvedMeshOptions o = base;
      o.eps_rel = levels[i].eps_rel;
      o.eps_scale = levels[i].eps_scale;
      if (n > 0) state.next_level();
      if (levels.size() > 1)
        log::info("mesh: eps level ", n + 1, " of ", levels.size(), " (eps ", o.eps_rel, ")",
                  n > 0 ? " from the finer level's coarse shell" : "");
      out[i] = build_with_attempts(input, o, stats[i], progress, state);
    }
    return out;
  };
  // Feature curves smaller than the finest bound (CurvedMeshOptions::feature_min_size).
  CurvedMeshOptions pruned = options;
  int small_curves = 0, small_edges = 0;
  if (options.feature_min_size > 0 && !options.feature_edges.empty()) {
    const EpsLevel& finest = levels[order.front()];
    pruned.feature_edges = drop_small_feature_components(
        input, options.feature_edges,
        options.feature_min_size * finest.eps_rel * bbox_longest_edge(input.V), finest.eps_scale,
        &small_curves);
    small_edges = int(options.feature_edges.size() - pruned.feature_edges.size());
    if (small_curves > 0)
      log::info("mesh: ", small_curves, " feature curves (", small_edges, " edges) smaller than ",
                options.feature_min_size, " eps are not kept as features");
  }
  int trimmed_ends = 0, trimmed_edges = 0;
  if (options.feature_end_trim > 0 && !pruned.feature_edges.empty()) {
    const EpsLevel& finest = levels[order.front()];
    const std::size_t before = pruned.feature_edges.size();
    pruned.feature_edges =
        trim_feature_ends(input, pruned.feature_edges,
                          options.feature_end_trim * finest.eps_rel * bbox_longest_edge(input.V),
                          finest.eps_scale, &trimmed_ends);
    trimmed_edges = int(before - pruned.feature_edges.size());
    if (trimmed_ends > 0)
      log::info("mesh: ", trimmed_ends, " open feature-curve ends cut back by ",
                options.feature_end_trim, " eps (", trimmed_edges, " edges)");
  }
  auto note_small = [&](std::vector<CurvedMesh> out) {
    for (CurvedMeshStats& s : stats) {
      s.small_feature_curves = small_curves;
      s.small_feature_edges = small_edges;
      s.trimmed_feature_ends = trimmed_ends;
      s.trimmed_feature_edges = trimmed_edges;
    }
    return out;
  };
  CoarseState state;
  try {
    std::vector<CurvedMesh> out = run(pruned, state);
    // A refined input: the round trip of φ along the fibers, which the validator checks
    // independently (pipeline/mesh_validity.hpp); on a miss, the input refined less.
    double check_seconds = 0;  // 0: no refined mesh checked
    auto miss_of = [&](const std::vector<CurvedMesh>& meshes) {
      std::string miss;
      for (const CurvedMesh& m : meshes)
        if (miss.empty() && !m.shell.refinement.empty()) {
          Stopwatch watch;
          miss = fiber_roundtrip_miss(m, input);
          check_seconds += watch.seconds();
        }
      return miss;
    };
    std::string miss = options.refined_roundtrip_check ? miss_of(out) : "";
    std::string fallback;
    for (int step = 0; step < 2 && !miss.empty(); ++step) {
      CurvedMeshOptions less = pruned;
      less.shape_refine = 0;
      if (step == 1) less.thin_refine_ratio = 0;
      const char* what = step == 0 ? "the shape refinement" : "the shape and thin refinements";
      log::warn("mesh: on the refined input ", miss, "; meshing again without ", what);
      fallback += (fallback.empty() ? "" : "; ") + miss + ": meshed again without " + what;
      state = CoarseState();
      out = run(less, state);
      miss = miss_of(out);
    }
    for (CurvedMeshStats& s : stats) {
      s.roundtrip_fallback = fallback;
      if (check_seconds > 0) s.stage_seconds.emplace_back("refined round trip", check_seconds);
    }
    return note_small(std::move(out));
  } catch (const MeshingError& e) {
    const int thin_refined = state.thin_stats.refined_faces,
              shape_refined = state.shape_stats.refined_faces;
    if (thin_refined == 0 && shape_refined == 0) throw;
    // The refined surface's shell could not be meshed (seen on a plate 0.1 ε thick: the slab
    // layer's inner surface stayed self-intersecting): the unrefined input, as before.
    log::warn("mesh: on the refined input (", thin_refined, " input faces refined for thin parts, ",
              shape_refined, " for their shape) ", e.what(),
              "; meshing the input without the refinements");
    CurvedMeshOptions plain = pruned;
    plain.thin_refine_ratio = 0;
    plain.shape_refine = 0;
    CoarseState plain_state;
    std::vector<CurvedMesh> out = run(plain, plain_state);
    for (CurvedMeshStats& s : stats) s.thin_fallback = e.what();
    return note_small(std::move(out));
  }
}

}  // namespace curvefem::meshing::curved
