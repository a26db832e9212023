#include "meshing/curved/curved_edit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <climits>
#include <cmath>
#include <compare>
#include <limits>
#include <map>
#include <set>
#include <string>

#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/curved/jacobian_certificate.hpp"
#include "meshing/curved/node_key.hpp"
#include "meshing/curved/optimize.hpp"
#include "meshing/editing/refusal_memo.hpp"
#include "meshing/editing/scheduler.hpp"
#include "meshing/editing/tet_mesh.hpp"

namespace curvefem::meshing::curved {
namespace {

using editing::Id;
using editing::OperationRecord;
using editing::TetMesh;

constexpr double k_inf = std::numeric_limits<double>::infinity();

using NodeKey = curved::NodeKey<Id>;

using Face = std::array<Id, 3>;  // sorted
using Edge = std::array<Id, 2>;  // sorted

Face sorted_face(Id a, Id b, Id c) {
  Face f{a, b, c};
  std::sort(f.begin(), f.end());
  return f;
}
Edge sorted_edge(Id a, Id b) { return a < b ? Edge{a, b} : Edge{b, a}; }

class CurvedEditMesh : public TetMesh {
 public:
  editing::Attribute<int> tag{*this, 3, 0};
  editing::Attribute<double> energy{*this, 3, 0.0};
  editing::Attribute<double> scaled_jacobian{*this, 3, 0.0};  // min_scaled_jacobian
  // curved_mips of the cell, NaN where not computed (the guards below are off): a cell's nodes
  // never move during the edits, so the value of its creation holds while it lives.
  editing::Attribute<double> mips{*this, 3, std::numeric_limits<double>::quiet_NaN()};

  int k = 1;
  bool mips_guard = false;  // every operation: the cavity's worst curved MIPS may not grow
  double locked_mips = 0;   // CurvedEditOptions::locked_mips
  // The mean pass (CurvedEditOptions::mean_flips): its checks replace invariants()'s.
  bool mean_mode = false;
  double mean_above = 30, mean_ref = 0, mean_sj_floor = 0.1, mean_flat = 0.01;
  const std::vector<std::array<int, 4>>* lattice = nullptr;
  const std::vector<std::array<int, 4>>* tri_lattice = nullptr;
  std::vector<Eigen::Vector3d> pos;                      // node positions (grows)
  NodeKeyMap<Id> node_of;                                // current node of every key
  editing::Attribute<char> vertex_fixed{*this, 0, 0};    // per vertex: never removed
  editing::Attribute<char> surface_vertex{*this, 0, 0};  // per vertex: on the frozen surface
  std::set<Face> curved_faces;                           // frozen faces (sorted vertices)
  std::map<Edge, Face> curved_edge_face;                 // a curved face of each curved edge
  CurvedEditStats* stats = nullptr;

  CurvedEditMesh() = default;

  // Node of each starting vertex's corner (vertices never move; a split's new vertex, beyond
  // the list, is looked up by its key).
  std::vector<int> corner_node;
  Eigen::Vector3d corner(Id v) const {
    if (v == split_vertex) return split_x;
    if (v < corner_node.size()) return pos[std::size_t(corner_node[v])];
    const std::array<int, 4> alpha{k, 0, 0, 0};
    return pos[std::size_t(node_of.at(make_node_key(&v, alpha, 1)))];
  }

  Eigen::MatrixXd cell_nodes(const Cell& c) const {
    Eigen::MatrixXd X(Eigen::Index(lattice->size()), 3);
    for (std::size_t n = 0; n < lattice->size(); ++n)
      X.row(Eigen::Index(n)) =
          pos[std::size_t(node_of.at(make_node_key(c.data(), (*lattice)[n], 4)))].transpose();
    return X;
  }

  // Refused collapses and swaps replayed (CurvedEditOptions::replay_refusals). A collapse
  // v -> w reads the cells around v and w (their corners, nodes, energies and scaled Jacobians)
  // and fixed data (tags, the frozen surface, the options); every accepted operation stamps the
  // corners of the cells it removes, creates or reshapes, and a face shared with a cell around v
  // or w has its corners among theirs. So while no corner of a cell around v or w carries a
  // stamp later than a refusal, the checks would refuse again for the same reason: the refusal
  // is counted again and nothing is run. One thread (the edits are sequential). A collapse the
  // editing engine refused for its topology (the link condition of v w, or no cell left) read
  // only the cells around v: it is replayed the same way (`remember_topology`).
  // A swap of a face (f0 f1 f2) or of an edge (a b) reads the cells holding that face or edge,
  // all around f0 (a), and its topology test looks for a new edge or face among their corners
  // (a cell created with it stamps them): remembered under (f0, f1) or (a, b) and a tag naming
  // the kind and, where the new cells depend on it, the tuple's third vertex (the order of the
  // new cells follows the tuple's, so the tuple is remembered as given).
  bool replay = false;
  bool precheck = true;  // CurvedEditOptions::precheck_collapse_energy
  struct Refusal {
    bool certificate = false;  // counted as rejected_certificate (else rejected_energy)
    bool topology = false;     // counted as rejected_topology
    bool locked = false;       // also counted as rejected_locked
  };
  // The operation under way as the memo keeps it (`kept` false: a split, not remembered).
  struct MemoKey {
    Id v = editing::k_no_id, w = editing::k_no_id;
    std::uint64_t tag = 0;  // 0: the collapse v -> w
    bool kept = false;
  } current;
  enum SwapKind : std::uint64_t { swap23 = 1, swap32 = 2, swap44 = 3 };
  SwapKind next_edge_swap = swap32;  // the edge swap the pass runs next
  static std::uint64_t swap_tag(SwapKind kind, Id third) {
    return (std::uint64_t(kind) << 32) | std::uint64_t(third);
  }
  void remember_topology(Id v, Id w) {
    if (replay) memo.remember(v, w, Refusal{false, true});
  }
  editing::RefusalMemo<TetMesh, Refusal> memo{*this};
  // Counts a replayed refusal of the checks as the checks would have.
  void count_replayed(const Refusal& x) {
    ++stats->attempted;
    ++(x.certificate ? stats->rejected_certificate : stats->rejected_energy);
    if (x.locked) ++stats->rejected_locked;
  }
  // Makes `key` the operation under way; true where it is a remembered refusal (counted again).
  bool replayed(const MemoKey& key) {
    current = key;
    if (!replay) return false;
    const Refusal* x = memo.replay(key.v, key.w, key.tag);
    if (!x) return false;
    count_replayed(*x);
    return true;
  }

  bool is_target(Id t, double threshold) const { return energy[t] > threshold; }
  bool is_split_target(Id t, double threshold, double flat) const {
    return energy[t] > threshold && scaled_jacobian[t] < flat;
  }

 protected:
  bool collapse_edge_before(const Tuple& t) override {
    current = MemoKey{};
    if (vertex_fixed[t.vid]) return false;
    current = MemoKey{t.vid, other_vertex(t), 0, true};
    const Refusal* x = replay ? memo.replay(t.vid, other_vertex(t)) : nullptr;
    if (!x) return !(precheck && collapse_energy_refused(t.vid, other_vertex(t)));
    if (x->topology) {
      ++stats->rejected_topology;  // (the engine counts this refusal as its user's)
      return false;
    }
    count_replayed(*x);
    return false;
  }
  // The energy check of invariants() for the collapse v -> w, before the engine carries it out:
  // the same new cells (v's star without the cells holding w, v replaced by w, in the engine's
  // order), their nodes built by the same code in the same order, so the same verdict; most
  // collapses are refused there, and the link condition and the engine's replacement and
  // rollback cost more than the check (menger_sponge K = 3: the link condition alone took 17% of
  // the edits). Counted as attempted and refused for energy, and remembered like a refusal of
  // the checks (it reads cells around v only).
  bool collapse_energy_refused(Id v, Id w) {
    std::vector<Cell> cells;
    double before = 0;
    for (Id c : vertex_cells(v)) {
      before = std::max(before, energy[c]);
      Cell cv = cell(c);
      if (std::find(cv.begin(), cv.end(), w) != cv.end()) continue;
      std::replace(cv.begin(), cv.end(), v, w);
      cells.push_back(cv);
    }
    if (cells.empty()) return false;  // the engine refuses it for its topology
    const Cavity cavity(cells);
    std::map<NodeKey, Eigen::Vector3d> staged;
    Eigen::MatrixXd X;
    for (const Cell& c : cells) {
      build_nodes(c, cavity, staged, X);
      if (!(cell_energy(k, X) < before * (1.0 - 1e-9))) {
        ++stats->attempted;
        ++stats->rejected_energy;
        ++stats->energy_prechecked;
        if (replay) memo.remember(v, w, Refusal{});
        return true;
      }
    }
    return false;
  }
  // Counts a refusal of the checks and remembers a collapse's or a swap's.
  bool refuse(bool certificate, bool locked = false) {
    ++(certificate ? stats->rejected_certificate : stats->rejected_energy);
    if (locked) ++stats->rejected_locked;
    if (replay && current.kept)
      memo.remember(current.v, current.w, Refusal{certificate, false, locked}, current.tag);
    return false;
  }
  bool swap_face_before(const Tuple& t) override {
    current = MemoKey{};
    const auto f = face_vertices(t);
    if (curved_faces.count(sorted_face(f[0], f[1], f[2]))) return false;
    return !replayed(MemoKey{f[0], f[1], swap_tag(swap23, f[2]), true});
  }
  // (swap_edge_32 and swap_edge_44 share this hook; the tag tells them apart by the kind the
  // pass asked for, `next_edge_swap`.)
  bool swap_edge_before(const Tuple& t) override {
    current = MemoKey{};
    const Id a = t.vid, b = other_vertex(t);
    if (curved_edge_face.count(sorted_edge(a, b))) return false;
    Id third = editing::k_no_id;
    if (next_edge_swap == swap44)
      for (Id v : face_vertices(t))
        if (v != a && v != b) third = v;
    return !replayed(MemoKey{a, b, swap_tag(next_edge_swap, third), true});
  }
  // Splits: interior edges only (neither on a boundary face nor on the frozen surface).
  bool split_edge_before(const Tuple& t) override {
    current = MemoKey{};
    return !is_boundary_edge(t) && !curved_edge_face.count(sorted_edge(t.vid, other_vertex(t)));
  }

  // The mean pass's checks (CurvedEditOptions::mean_flips): the cavity's Σ(MIPS − mean_ref)
  // falls by 1% of its summed MIPS at least, no new cell above max(its worst, mean_above) nor
  // below min(its smallest scaled Jacobian, mean_sj_floor), no more cells below mean_flat than
  // it had, no locked cell above locked_mips that was not there, every new cell certified.
  bool mean_invariants(const OperationRecord& r) {
    ++stats->attempted;
    std::vector<Cell> new_cells;
    new_cells.reserve(r.new_cells.size());
    for (Id t : r.new_cells) new_cells.push_back(cell(t));
    const Cavity cavity(new_cells);
    auto locked = [&](const Cell& c) {
      return vertex_fixed[c[0]] && vertex_fixed[c[1]] && vertex_fixed[c[2]] && vertex_fixed[c[3]];
    };
    double sum_before = 0, max_before = 0, sj_before = k_inf, locked_before = 0;
    int flat_before = 0;
    for (Id t : r.old_cells) {
      const double x = mips[t];
      sum_before += x;
      max_before = std::max(max_before, x);
      sj_before = std::min(sj_before, scaled_jacobian[t]);
      flat_before += scaled_jacobian[t] < mean_flat;
      if (locked(cell(t))) locked_before = std::max(locked_before, x);
    }
    const double n_before = double(r.old_cells.size()), n_after = double(r.new_cells.size());
    const double limit = sum_before - mean_ref * (n_before - n_after) - 0.01 * sum_before;
    const double cap = std::max(max_before, mean_above);
    const double locked_bound = std::max(locked_mips, locked_before);
    std::map<NodeKey, Eigen::Vector3d> staged;
    std::vector<Eigen::MatrixXd> Xs;
    const std::size_t nn = r.new_cells.size();
    std::vector<double> new_mips(nn), new_sj(nn), new_energy(nn);
    double sum_after = 0;
    for (std::size_t i = 0; i < nn; ++i) {
      build_nodes(cell(r.new_cells[i]), cavity, staged, Xs.emplace_back());
      new_mips[i] = curved_mips(k, Xs[i]);
      sum_after += new_mips[i];
      if (!(new_mips[i] <= cap) || !(sum_after < limit)) return refuse(false);
      if (locked_mips > 0 && locked(cell(r.new_cells[i])) && !(new_mips[i] <= locked_bound))
        return refuse(false, true);
    }
    const double sj_needed = std::min(sj_before, mean_sj_floor);
    int flat_after = 0;
    for (std::size_t i = 0; i < nn; ++i) {
      new_sj[i] = min_scaled_jacobian(k, Xs[i]);
      flat_after += new_sj[i] < mean_flat;
      if (!(new_sj[i] >= sj_needed) || flat_after > flat_before) return refuse(false);
    }
    for (std::size_t i = 0; i < nn; ++i) new_energy[i] = cell_energy(k, Xs[i]);
    return certify_and_keep(r, Xs, staged, new_energy, new_sj, new_mips);
  }

  // The last check of an operation, the certificate of every new cell; then the new cells'
  // values and their new nodes are kept.
  bool certify_and_keep(const OperationRecord& r, const std::vector<Eigen::MatrixXd>& Xs,
                        const std::map<NodeKey, Eigen::Vector3d>& staged,
                        const std::vector<double>& new_energy, const std::vector<double>& new_sj,
                        const std::vector<double>& new_mips) {
    for (const Eigen::MatrixXd& X : Xs)
      if (certify_tet_jacobian(k, X).verdict != JacobianVerdict::positive) return refuse(true);
    for (std::size_t i = 0; i < r.new_cells.size(); ++i) {
      energy.set(r.new_cells[i], new_energy[i]);
      scaled_jacobian.set(r.new_cells[i], new_sj[i]);
      mips.set(r.new_cells[i], new_mips[i]);
    }
    for (const auto& [key, x] : staged) {
      node_of.assign(key, int(pos.size()));
      pos.push_back(x);
    }
    memo.stamp({&r.old_cells, &r.new_cells, &r.affected_cells});
    return true;
  }

  bool invariants(const OperationRecord& r) override {
    if (mean_mode) return mean_invariants(r);
    ++stats->attempted;
    std::vector<Cell> new_cells;
    new_cells.reserve(r.new_cells.size());
    for (Id t : r.new_cells) new_cells.push_back(cell(t));
    const Cavity cavity(new_cells);

    double before = 0, sj_before = k_inf;
    for (Id t : r.old_cells) {
      before = std::max(before, energy[t]);
      sj_before = std::min(sj_before, scaled_jacobian[t]);
    }

    // The new cells' nodes, then the checks from the cheapest to the dearest, each over all new
    // cells before the next: energy (each cell as soon as it is built: most operations are
    // refused there, and building the rest is wasted), scaled Jacobian, certificate.
    std::map<NodeKey, Eigen::Vector3d> staged;  // new nodes shared by several new cells
    std::vector<Eigen::MatrixXd> Xs;
    auto build_cell = [&](Id t) { build_nodes(cell(t), cavity, staged, Xs.emplace_back()); };
    struct ClearSplit {
      CurvedEditMesh* m;
      ~ClearSplit() { m->split_vertex = editing::k_no_id; }
    } clear_split{this};
    if (r.new_vertex != editing::k_no_id) {
      // A split: the new corner starts at the old edge's midpoint (on its curve) and moves to
      // where the worst energy of the new cells' straight tets (their corners) is lowest
      // (pattern search, steps halving from a quarter of the edge down to 1/64 of it); the
      // curved cells are built once, at the end.
      split_vertex = r.new_vertex;
      split_x = edge_midpoint(r.old_cells.front(), r.v0, r.v1);
      const double len = (corner(r.v0) - corner(r.v1)).norm();
      std::vector<Eigen::Matrix<double, 4, 3>> corners(r.new_cells.size());
      std::vector<int> moving(r.new_cells.size(), -1);
      for (std::size_t i = 0; i < r.new_cells.size(); ++i) {
        const Cell& c = cell(r.new_cells[i]);
        for (int j = 0; j < 4; ++j) {
          if (c[std::size_t(j)] == split_vertex) moving[i] = j;
          corners[i].row(j) = corner(c[std::size_t(j)]).transpose();
        }
        CF_VERIFY(moving[i] >= 0, "curved edit: a split's new cell lacks the new vertex");
      }
      auto worst = [&]() {
        double e = 0;
        for (std::size_t i = 0; i < corners.size(); ++i) {
          corners[i].row(moving[i]) = split_x.transpose();
          e = std::max(e, cell_energy(1, corners[i]));
        }
        return e;
      };
      double best = worst();
      for (double h = 0.25 * len; h >= len / 64;) {
        const Eigen::Vector3d at = split_x;
        Eigen::Vector3d to = at;
        double to_e = best;
        for (int d = 0; d < 6; ++d) {
          split_x = at + (d % 2 ? -h : h) * Eigen::Vector3d::Unit(d / 2);
          const double e = worst();
          if (e < to_e) to_e = e, to = split_x;
        }
        split_x = to;
        if (to_e < best) {
          best = to_e;
        } else {
          h /= 2;
        }
      }
    }
    const std::size_t nn = r.new_cells.size();
    std::vector<double> new_energy(nn), new_sj(nn);
    for (std::size_t i = 0; i < nn; ++i) {
      build_cell(r.new_cells[i]);
      new_energy[i] = cell_energy(k, Xs[i]);
      if (!(new_energy[i] < before * (1.0 - 1e-9))) return refuse(false);
    }
    // A split adds cells, so it must also raise the cavity's worst scaled Jacobian.
    const double sj_needed =
        r.new_vertex != editing::k_no_id ? sj_before * (1 + split_sj_gain) : sj_before;
    for (std::size_t i = 0; i < nn; ++i) {
      new_sj[i] = min_scaled_jacobian(k, Xs[i]);
      if (!(new_sj[i] >= sj_needed)) return refuse(false);
    }
    // ... and not raise its worst curved MIPS (the quality goal's measure, which the conformal
    // energy above weighs differently: a split that trades a flat cell for a needle passes
    // that one) ...
    const bool guard_mips = r.new_vertex != editing::k_no_id || mips_guard;
    std::vector<double> new_mips(nn, std::numeric_limits<double>::quiet_NaN());
    if (guard_mips || locked_mips > 0) {
      auto locked = [&](const Cell& c) {
        return vertex_fixed[c[0]] && vertex_fixed[c[1]] && vertex_fixed[c[2]] && vertex_fixed[c[3]];
      };
      double mips_before = 0, locked_before = 0;
      for (Id t : r.old_cells) {
        const double x = std::isnan(mips[t]) ? curved_mips(k, cell_nodes(cell(t))) : mips[t];
        mips_before = std::max(mips_before, x);
        if (locked(cell(t))) locked_before = std::max(locked_before, x);
      }
      // ... and not leave a locked cell (its four corners fixed, so no later smoothing moves
      // them) worse than locked_mips, unless the cavity held a worse locked cell already.
      const double locked_bound = std::max(locked_mips, locked_before);
      for (std::size_t i = 0; i < nn; ++i) {
        new_mips[i] = curved_mips(k, Xs[i]);
        if (guard_mips && !(new_mips[i] <= mips_before)) return refuse(false);
      }
      if (locked_mips > 0)
        for (std::size_t i = 0; i < nn; ++i)
          if (locked(cell(r.new_cells[i])) && !(new_mips[i] <= locked_bound))
            return refuse(false, true);
    }
    return certify_and_keep(r, Xs, staged, new_energy, new_sj, new_mips);
  }

  // The boundary of the cavity that `cells` fill (the new cells of an operation): the faces used
  // by one of them, and those faces' edges. A node is on it when its support (the corners of its
  // sub-simplex) lies in such a face: the face itself for three corners, one of its edges for
  // two. (Sorted vectors: a cavity has a few dozen faces, and this runs on every attempt.)
  struct Cavity {
    std::vector<Face> faces;
    std::vector<Edge> edges;
    explicit Cavity(const std::vector<Cell>& cells) {
      std::vector<Face> all;
      all.reserve(4 * cells.size());
      for (const Cell& c : cells)
        for (int skip = 0; skip < 4; ++skip) {
          Id f[3];
          int n = 0;
          for (int j = 0; j < 4; ++j)
            if (j != skip) f[n++] = c[std::size_t(j)];
          all.push_back(sorted_face(f[0], f[1], f[2]));
        }
      std::sort(all.begin(), all.end());
      for (std::size_t i = 0; i < all.size();) {
        std::size_t j = i + 1;
        while (j < all.size() && all[j] == all[i]) ++j;
        if (j == i + 1) {
          const Face& f = all[i];
          faces.push_back(f);
          edges.push_back({f[0], f[1]});
          edges.push_back({f[0], f[2]});
          edges.push_back({f[1], f[2]});
        }
        i = j;
      }
      std::sort(edges.begin(), edges.end());
    }
    bool on_boundary(const Id* support, int size) const {
      switch (size) {
        case 1:
          return true;
        case 2:
          return std::binary_search(edges.begin(), edges.end(),
                                    sorted_edge(support[0], support[1]));
        case 3:
          return std::binary_search(faces.begin(), faces.end(),
                                    sorted_face(support[0], support[1], support[2]));
        default:
          return false;
      }
    }
  };
  // The nodes X of new cell c (corners): on the cavity's boundary the existing nodes, a split's
  // new corner at split_x, and elsewhere the rule of the header, each new node placed once
  // (`staged`, shared by the cavity's cells; the first cell to need it places it).
  void build_nodes(const Cell& c, const Cavity& cavity, std::map<NodeKey, Eigen::Vector3d>& staged,
                   Eigen::MatrixXd& X) const {
    X.resize(Eigen::Index(lattice->size()), 3);
    Eigen::Vector3d P[4];
    for (int j = 0; j < 4; ++j) P[j] = corner(c[std::size_t(j)]);
    for (std::size_t n = 0; n < lattice->size(); ++n) {
      const auto& alpha = (*lattice)[n];
      Id support[4];
      int size = 0, first = 0;
      for (int j = 0; j < 4; ++j)
        if (alpha[std::size_t(j)] > 0) {
          if (size == 0) first = j;
          support[size++] = c[std::size_t(j)];
        }
      // A corner's node: its corner (the node of a vertex never changes), without a key.
      if (size == 1 && support[0] != split_vertex) {
        X.row(Eigen::Index(n)) = P[first].transpose();
        continue;
      }
      const NodeKey key = make_node_key(c.data(), alpha, 4);
      Eigen::Vector3d x;
      if (size == 1) {
        x = split_x;
        staged.emplace(key, x);
      } else if (cavity.on_boundary(support, size)) {
        const int* node = node_of.find(key);
        CF_VERIFY(node, "curved edit: a cavity-boundary node has no position");
        x = pos[std::size_t(*node)];
      } else if (const auto it = staged.find(key); it != staged.end()) {
        x = it->second;
      } else {
        x = place(c, alpha, P);
        staged.emplace(key, x);
      }
      X.row(Eigen::Index(n)) = x.transpose();
    }
  }

  double split_sj_gain = 0.5;
  Id split_vertex = editing::k_no_id;  // the corner a split is placing (not yet in node_of)
  Eigen::Vector3d split_x = Eigen::Vector3d::Zero();

 private:
  // The rule of the header for the lattice point alpha of cell c (corners at P): the Boolean sum
  // of the blends of the curved faces and edges spanned by the node's corners on the surface
  // (an edge counts 1 minus the number of those faces holding it, so a node on a sub-simplex gets
  // the same from every cell).
  Eigen::Vector3d place(const Cell& c, const std::array<int, 4>& alpha,
                        const Eigen::Vector3d* P) const {
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    for (int j = 0; j < 4; ++j) x += (double(alpha[std::size_t(j)]) / k) * P[j];
    int on[4], n_on = 0;  // (fixed arrays: this runs for every new node of every attempt)
    for (int j = 0; j < 4; ++j)
      if (alpha[std::size_t(j)] > 0 && surface_vertex[c[std::size_t(j)]]) on[n_on++] = j;
    if (n_on < 2) return x;
    std::array<std::array<int, 3>, 4> faces;
    int n_faces = 0;
    for (int a = 0; a < n_on; ++a)
      for (int b = a + 1; b < n_on; ++b)
        for (int d = b + 1; d < n_on; ++d)
          if (curved_faces.count(
                  sorted_face(c[std::size_t(on[a])], c[std::size_t(on[b])], c[std::size_t(on[d])])))
            faces[std::size_t(n_faces++)] = {on[a], on[b], on[d]};
    for (int i = 0; i < n_faces; ++i) x += blend(c, alpha, faces[std::size_t(i)].data(), 3);
    for (int a = 0; a < n_on; ++a)
      for (int b = a + 1; b < n_on; ++b) {
        if (!curved_edge_face.count(sorted_edge(c[std::size_t(on[a])], c[std::size_t(on[b])])))
          continue;
        int holding = 0;
        for (int i = 0; i < n_faces; ++i) {
          const auto& f = faces[std::size_t(i)];
          holding += std::count(f.begin(), f.end(), on[a]) && std::count(f.begin(), f.end(), on[b]);
        }
        if (holding == 1) continue;
        const int pair[2] = {on[a], on[b]};
        x += double(1 - holding) * blend(c, alpha, pair, 2);
      }
    return x;
  }

  // The point of old cell t's map at the middle of its edge (a, b).
  Eigen::Vector3d edge_midpoint(Id t, Id a, Id b) const {
    const Cell& c = cell(t);
    Eigen::Vector4d lambda = Eigen::Vector4d::Zero();
    for (int j = 0; j < 4; ++j)
      if (c[std::size_t(j)] == a || c[std::size_t(j)] == b) lambda[j] = 0.5;
    const Eigen::VectorXd N = lagrange_shape_values(
        CellKind::tetrahedron, k, Eigen::Vector3d(lambda[1], lambda[2], lambda[3]));
    const Eigen::MatrixXd X = cell_nodes(c);
    return (N.transpose() * X).transpose();
  }

  // t · d_σ(normalised λ on σ) for σ = the local corners `sigma` (a curved face or edge).
  Eigen::Vector3d blend(const Cell& c, const std::array<int, 4>& alpha, const int* sigma,
                        int count) const {
    int share = 0;
    for (int i = 0; i < count; ++i) share += alpha[std::size_t(sigma[i])];
    if (share == 0) return Eigen::Vector3d::Zero();
    const double t = double(share) / k;
    // The curved face carrying σ, its corners sorted; barycentric weights on them.
    Face f;
    if (count == 3) {
      f = sorted_face(c[std::size_t(sigma[0])], c[std::size_t(sigma[1])], c[std::size_t(sigma[2])]);
    } else {
      f = curved_edge_face.at(sorted_edge(c[std::size_t(sigma[0])], c[std::size_t(sigma[1])]));
    }
    Eigen::Vector3d mu = Eigen::Vector3d::Zero();  // on f's sorted corners
    for (int i = 0; i < count; ++i) {
      const Id v = c[std::size_t(sigma[i])];
      const int at = int(std::find(f.begin(), f.end(), v) - f.begin());
      mu[at] = double(alpha[std::size_t(sigma[i])]) / share;
    }
    const Eigen::VectorXd N =
        lagrange_shape_values(CellKind::triangle, k, Eigen::Vector3d(mu[1], mu[2], 0));
    Eigen::Vector3d patch = Eigen::Vector3d::Zero(), linear = Eigen::Vector3d::Zero();
    for (std::size_t n = 0; n < tri_lattice->size(); ++n)
      patch += N[Eigen::Index(n)] *
               pos[std::size_t(node_of.at(make_node_key(f.data(), (*tri_lattice)[n], 3)))];
    for (int i = 0; i < 3; ++i) linear += mu[i] * corner(f[std::size_t(i)]);
    return t * (patch - linear);
  }
};

}  // namespace

void accumulate(CurvedEditStats& total, const CurvedEditStats& next) {
  total.passes += next.passes;
  total.collapses += next.collapses;
  total.flips += next.flips;
  total.splits += next.splits;
  total.mean_flips += next.mean_flips;
  if (next.mean_flips > 0 || next.mean_mips_before > 0) {
    if (!(total.mean_mips_before > 0)) total.mean_mips_before = next.mean_mips_before;
    total.mean_mips_after = next.mean_mips_after;
  }
  total.attempted += next.attempted;
  total.rejected_certificate += next.rejected_certificate;
  total.rejected_energy += next.rejected_energy;
  total.rejected_topology += next.rejected_topology;
  total.rejected_locked += next.rejected_locked;
  total.energy_prechecked += next.energy_prechecked;
  total.cells_after = next.cells_after;
  total.targets_after = next.targets_after;
  total.max_energy_after = next.max_energy_after;
  total.mean_energy_after = next.mean_energy_after;
  total.seconds += next.seconds;
}

CurvedEditResult edit_curved_mesh(LagrangeMesh& mesh, const std::vector<char>& frozen,
                                  const CurvedEditOptions& options, const ProgressFn& progress) {
  Stopwatch watch;
  CurvedEditResult result;
  CurvedEditStats& stats = result.stats;
  if (mesh.kind != CellKind::tetrahedron)
    throw InputError("edit_curved_mesh: needs a tetrahedral mesh");
  CF_VERIFY(frozen.size() == std::size_t(mesh.num_nodes()), "edit_curved_mesh: frozen size");
  const int k = mesh.order, nc = mesh.num_cells();
  const auto& lattice = lagrange_lattice(CellKind::tetrahedron, k);
  std::array<int, 4> corner_row{};
  for (std::size_t n = 0; n < lattice.size(); ++n)
    for (int j = 0; j < 4; ++j)
      if (lattice[n][std::size_t(j)] == k) corner_row[std::size_t(j)] = int(n);

  // Vertices: the corner nodes, numbered densely.
  std::vector<int> vertex_of(std::size_t(mesh.num_nodes()), -1), node_of_vertex;
  for (int c = 0; c < nc; ++c)
    for (int j = 0; j < 4; ++j) {
      const int node = mesh.cells(c, corner_row[std::size_t(j)]);
      if (vertex_of[std::size_t(node)] < 0) {
        vertex_of[std::size_t(node)] = int(node_of_vertex.size());
        node_of_vertex.push_back(node);
      }
    }
  std::vector<TetMesh::Cell> cells(static_cast<std::size_t>(nc));
  for (int c = 0; c < nc; ++c)
    for (int j = 0; j < 4; ++j)
      cells[std::size_t(c)][std::size_t(j)] =
          Id(vertex_of[std::size_t(mesh.cells(c, corner_row[std::size_t(j)]))]);

  CurvedEditMesh m;
  m.k = k;
  m.lattice = &lattice;
  m.tri_lattice = &lagrange_lattice(CellKind::triangle, k);
  m.stats = &stats;
  m.mips_guard = options.mips_guard;
  m.locked_mips = options.locked_mips;
  m.replay = options.replay_refusals;
  m.precheck = options.precheck_collapse_energy;
  m.initialize(node_of_vertex.size(), cells);
  m.corner_node = node_of_vertex;
  m.pos.resize(std::size_t(mesh.num_nodes()));
  for (int n = 0; n < mesh.num_nodes(); ++n) m.pos[std::size_t(n)] = mesh.nodes.row(n).transpose();
  for (int c = 0; c < nc; ++c)
    for (std::size_t n = 0; n < lattice.size(); ++n) {
      const auto key = make_node_key(cells[std::size_t(c)].data(), lattice[n], 4);
      const int node = mesh.cells(c, Eigen::Index(n));
      const auto [kept, inserted] = m.node_of.insert(key, node);
      if (!inserted && kept != node)
        throw MeshingError("edit_curved_mesh: cell " + std::to_string(c) +
                           " has a second node for one lattice point (node " +
                           std::to_string(node) + " and " + std::to_string(kept) + ")");
    }

  // Fixed vertices: on the frozen surface or on a boundary face. Curved faces: every node
  // frozen. The boundary faces are never touched by the engine's operations on interior
  // vertices, faces and edges, and the frozen surface is protected by the before hooks.
  const std::size_t nv = node_of_vertex.size();
  for (std::size_t v = 0; v < nv; ++v)
    if (frozen[std::size_t(node_of_vertex[v])]) {
      m.vertex_fixed.set(v, 1);
      m.surface_vertex.set(v, 1);
    }
  const auto& tri = *m.tri_lattice;
  for (int c = 0; c < nc; ++c) {
    const auto& cv = cells[std::size_t(c)];
    for (int skip = 0; skip < 4; ++skip) {
      Id f[3];
      int n = 0;
      for (int j = 0; j < 4; ++j)
        if (j != skip) f[n++] = cv[std::size_t(j)];
      const Face sf = sorted_face(f[0], f[1], f[2]);
      if (m.is_boundary_facet(std::span<const Id>(sf.data(), 3)))
        for (Id v : sf) m.vertex_fixed.set(v, 1);
      bool curved = true;
      for (const auto& alpha : tri) {
        const int node = m.node_of.at(make_node_key(sf.data(), alpha, 3));
        curved = curved && frozen[std::size_t(node)];
      }
      if (!curved) continue;
      m.curved_faces.insert(sf);
      for (int a = 0; a < 3; ++a)
        for (int b = a + 1; b < 3; ++b)
          m.curved_edge_face.emplace(sorted_edge(sf[std::size_t(a)], sf[std::size_t(b)]), sf);
    }
  }

  for (int c = 0; c < nc; ++c) {
    m.tag.set(Id(c), mesh.cell_tags.size() == nc ? mesh.cell_tags[c] : 0);
    const Eigen::MatrixXd X = m.cell_nodes(cells[std::size_t(c)]);
    m.energy.set(Id(c), cell_energy(k, X));
    m.scaled_jacobian.set(Id(c), min_scaled_jacobian(k, X));
    if (options.mips_guard || options.locked_mips > 0 || options.splits || options.mean_flips)
      m.mips.set(Id(c), curved_mips(k, X));
  }
  auto summarize = [&](double& mean, double& max, int& targets) {
    mean = max = 0;
    targets = 0;
    const auto live = m.live_cells();
    for (Id t : live) {
      mean += m.energy[t] / double(std::max<std::size_t>(live.size(), 1));
      max = std::max(max, m.energy[t]);
      if (m.energy[t] > options.energy) ++targets;
    }
  };
  stats.cells_before = nc;
  summarize(stats.mean_energy_before, stats.max_energy_before, stats.targets_before);

  using Pass = editing::ExecutePass<TetMesh>;
  enum class Mode { collapse, flip, split, mean_flip };
  auto wanted = [&](Id t, Mode mode) {
    if (m.is_cell_removed(t)) return false;
    if (mode == Mode::mean_flip) return m.mips[t] > options.mean_mips_above;
    return mode == Mode::split ? m.is_split_target(t, options.energy, options.split_scaled_jacobian)
                               : m.is_target(t, options.energy);
  };
  auto target_work = [&](const std::vector<Id>& tets, Mode mode) {
    std::vector<Pass::Work> work;
    for (Id t : tets) {
      if (!wanted(t, mode)) continue;
      if (mode == Mode::split) {
        // Its interior edges, longest first (the queue orders by the cell's energy only, so
        // the order among one cell's edges is this one).
        std::vector<std::pair<double, TetMesh::Tuple>> edges;
        for (const auto& e : m.edges_of_tets({t}))
          edges.emplace_back((m.corner(e.vid) - m.corner(m.other_vertex(e))).norm(), e);
        std::stable_sort(edges.begin(), edges.end(),
                         [](const auto& x, const auto& y) { return x.first > y.first; });
        for (const auto& [len, e] : edges) work.emplace_back("split", e);
      } else if (mode == Mode::collapse) {
        // Every edge of the cell, from both ends (the removed vertex is the tuple's).
        for (int le = 0; le < 6; ++le)
          for (int end = 0; end < 2; ++end) {
            const auto loc = TetMesh::local_simplex(1, le);
            const Id a = m.cell(t)[std::size_t(loc[std::size_t(end)])];
            const Id b = m.cell(t)[std::size_t(loc[std::size_t(1 - end)])];
            if (m.vertex_fixed[a]) continue;
            if (auto e = m.edge_tuple(a, b)) {
              if (e->vid != a) e = m.switch_vertex(*e);
              work.emplace_back("collapse", *e);
            }
          }
        // Ring collapses of a flat or needle cell: each of its free corners toward every other
        // neighbour too, so a slab cell's inner corner can go to a deeper vertex of its ring.
        if (m.scaled_jacobian[t] < options.ring_collapse_scaled_jacobian) {
          const auto cv = m.cell(t);
          for (Id a : cv) {
            if (m.vertex_fixed[a]) continue;
            for (Id b : m.one_ring(a)) {
              if (std::find(cv.begin(), cv.end(), b) != cv.end()) continue;  // done above
              if (auto e = m.edge_tuple(a, b)) {
                if (e->vid != a) e = m.switch_vertex(*e);
                work.emplace_back("collapse", *e);
              }
            }
          }
        }
      } else {  // Mode::flip, Mode::mean_flip
        for (const auto& f : m.faces_of_tets({t})) work.emplace_back("swap23", f);
        for (const auto& e : m.edges_of_tets({t})) {
          work.emplace_back("swap32", e);
          work.emplace_back("swap44", e);
          work.emplace_back("swap44", m.switch_face(e));
        }
      }
    }
    return work;
  };
  auto run = [&](Mode mode) {
    Pass pass;
    pass.num_threads = 1;
    long long split_budget = (long long)(options.max_split_share * double(m.live_cells().size()));
    if (mode == Mode::split) {
      pass.operations["split"] = [&split_budget](TetMesh& mm, const TetMesh::Tuple& t) {
        if (split_budget <= 0) return std::optional<TetMesh::Tuple>();
        auto done = mm.split_edge(t);
        if (done) --split_budget;
        return done;
      };
    } else if (mode == Mode::collapse) {
      pass.operations["collapse"] = [&m](TetMesh& mm, const TetMesh::Tuple& t) {
        auto done = mm.collapse_edge(t);
        // (A topology refusal comes before any change: t is still valid.)
        if (!done && mm.last_rejection() == editing::Rejection::topology)
          m.remember_topology(t.vid, mm.other_vertex(t));
        return done;
      };
    } else {  // Mode::flip, Mode::mean_flip
      pass.operations["swap23"] = [](TetMesh& mm, const TetMesh::Tuple& t) {
        return mm.swap_face_23(t);
      };
      pass.operations["swap32"] = [&m](TetMesh& mm, const TetMesh::Tuple& t) {
        m.next_edge_swap = CurvedEditMesh::swap32;
        return mm.swap_edge_32(t);
      };
      pass.operations["swap44"] = [&m](TetMesh& mm, const TetMesh::Tuple& t) {
        m.next_edge_swap = CurvedEditMesh::swap44;
        return mm.swap_edge_44(t);
      };
    }
    // Worst cells first; a queued entry whose cell is no longer a target is dropped.
    // A collapse is judged by the star of the vertex it removes (its tuple's cell need not be
    // the target cell that asked for it).
    auto star_energy = [&m](Id v) {
      double e = 0;
      for (Id c : m.vertex_cells(v)) e = std::max(e, m.energy[c]);
      return e;
    };
    pass.priority = [&m, mode, &star_energy](const TetMesh&, const std::string&,
                                             const TetMesh::Tuple& t) {
      if (mode == Mode::mean_flip) return m.mips[t.tid];
      return mode == Mode::collapse ? star_energy(t.vid) : m.energy[t.tid];
    };
    pass.should_process = [&wanted, &star_energy, &options, mode](const TetMesh&,
                                                                  const Pass::Work& w, double) {
      if (mode == Mode::collapse) return star_energy(w.second.vid) > options.energy;
      return wanted(w.second.tid, mode);
    };
    pass.renew_neighbor_tuples = [&](const TetMesh&, const std::string&, const TetMesh::Tuple&) {
      return target_work(m.operation_record().new_cells, mode);
    };
    const auto s = pass.run(m, target_work(m.live_cells(), mode));
    log::debug("optimize: curved edits, ",
               mode == Mode::collapse    ? "collapses"
               : mode == Mode::flip      ? "flips"
               : mode == Mode::mean_flip ? "flips for the mean"
                                         : "splits",
               ": ", s.summary());
    stats.rejected_topology += (long long)(s.rejected_topology);
    return (long long)(s.succeeded);
  };

  for (int p = 0; p < options.passes; ++p) {
    if (progress) progress("optimize: curved edits", double(p) / options.passes);
    long long done = 0;
    if (options.collapses) {
      const long long c = run(Mode::collapse);
      stats.collapses += c;
      done += c;
    }
    if (options.flips) {
      const long long f = run(Mode::flip);
      stats.flips += f;
      done += f;
    }
    if (options.splits) {
      const long long sp = run(Mode::split);
      stats.splits += sp;
      done += sp;
    }
    ++stats.passes;
    if (done == 0) break;
  }
  if (options.mean_flips) {
    // The mean pass: its own checks (mean_invariants); refusals are not replayed (the memo's
    // were judged by the other checks).
    auto mean_mips = [&m] {
      const auto live = m.live_cells();
      double sum = 0;
      for (Id t : live) sum += m.mips[t];
      return sum / double(std::max<std::size_t>(live.size(), 1));
    };
    for (Id t : m.live_cells())
      if (std::isnan(m.mips[t])) m.mips.set(t, curved_mips(k, m.cell_nodes(m.cell(t))));
    stats.mean_mips_before = m.mean_ref = mean_mips();
    m.mean_mode = true;
    m.mean_above = options.mean_mips_above;
    m.mean_sj_floor = options.mean_sj_floor;
    m.mean_flat = options.mean_flat;
    const bool replay = m.replay;
    m.replay = false;
    stats.mean_flips = run(Mode::mean_flip);
    m.replay = replay;
    m.mean_mode = false;
    stats.mean_mips_after = mean_mips();
  }
  if (progress) progress("optimize: curved edits", 1.0);
  summarize(stats.mean_energy_after, stats.max_energy_after, stats.targets_after);
  stats.replayed = m.memo.replayed();

  // Back to a LagrangeMesh: the original nodes still used keep their order, new nodes follow.
  const auto live = m.live_cells();
  std::vector<int> new_id(m.pos.size(), -1);
  Eigen::MatrixXi new_cells(Eigen::Index(live.size()), Eigen::Index(lattice.size()));
  Eigen::VectorXi new_tags(Eigen::Index(live.size()));
  for (std::size_t i = 0; i < live.size(); ++i) {
    const auto& cv = m.cell(live[i]);
    for (std::size_t n = 0; n < lattice.size(); ++n)
      new_cells(Eigen::Index(i), Eigen::Index(n)) =
          m.node_of.at(make_node_key(cv.data(), lattice[n], 4));
    new_tags[Eigen::Index(i)] = m.tag[live[i]];
  }
  for (int n = 0; n < mesh.num_nodes(); ++n)
    if (frozen[std::size_t(n)]) new_id[std::size_t(n)] = 0;  // kept even if unused
  for (Eigen::Index i = 0; i < new_cells.size(); ++i) new_id[std::size_t(new_cells.data()[i])] = 0;
  int count = 0;
  for (auto& id : new_id)
    if (id == 0) id = count++;
  Eigen::MatrixXd nodes(count, 3);
  for (std::size_t n = 0; n < m.pos.size(); ++n)
    if (new_id[n] >= 0) nodes.row(new_id[n]) = m.pos[n].transpose();
  for (Eigen::Index i = 0; i < new_cells.size(); ++i)
    new_cells.data()[i] = new_id[std::size_t(new_cells.data()[i])];
  result.node_map.assign(new_id.begin(), new_id.begin() + mesh.num_nodes());
  mesh.nodes = std::move(nodes);
  mesh.cells = std::move(new_cells);
  if (mesh.cell_tags.size() > 0) mesh.cell_tags = std::move(new_tags);
  stats.cells_after = mesh.num_cells();
  stats.seconds = watch.seconds();
  return result;
}

}  // namespace curvefem::meshing::curved
