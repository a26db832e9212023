#include "meshing/io/msh_io.hpp"

#include <gmsh.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <memory>
#include <mutex>
#include <type_traits>
#include <unordered_map>

#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/io/gmsh_session.hpp"
#include "meshing/io/msh_parser.hpp"
#include "meshing/io/node_permutation.hpp"

namespace curvefem::io {
namespace {

// Gmsh stores exact reference coordinates; anything close to the lattice spacing would be a bug.
constexpr double k_match_tolerance = 1e-8;

const char* kind_name(CellKind kind) {
  return kind == CellKind::triangle ? "triangle" : "tetrahedron";
}

struct GmshElement {
  int type = 0;           ///< Gmsh element type number
  std::vector<int> perm;  ///< Gmsh local node i = canonical local node perm[i]
};

/// Gmsh type numbers and node permutations of triangles and tetrahedra of order 1..k_max_order,
/// queried once per process from Gmsh itself.
///
/// These queries do not touch the Gmsh model, so they run WITHOUT a GmshSession: a session's
/// constructor clears the current model, and callers (e.g. cad_part.cpp) ask for permutations
/// while holding a session with a live model. Gmsh is initialized here if nobody has done so yet
/// (gmsh::initialize is a no-op on a second call, so GmshSession still works afterwards).
class GmshTables {
 public:
  static const GmshTables& instance() {
    // Lock order gmsh → tables everywhere; keep_model leaves an outer session's model alone.
    const GmshSession session("tables", GmshSession::Mode::keep_model);
    static std::mutex mutex;
    static std::unique_ptr<GmshTables> tables;
    std::lock_guard lock(mutex);
    if (!tables) tables.reset(new GmshTables());
    return *tables;
  }

  const GmshElement& element(CellKind kind, int order) const {
    CF_VERIFY(order >= 1 && order <= k_max_order, "Gmsh element order out of range");
    return m_elements[kind == CellKind::triangle ? 0 : 1][order];
  }

  /// (kind, order) of a Gmsh type number, or order -1 if it is not one of ours.
  std::pair<CellKind, int> find(int type) const {
    for (CellKind kind : {CellKind::tetrahedron, CellKind::triangle})
      for (int order = 1; order <= k_max_order; ++order)
        if (element(kind, order).type == type) return {kind, order};
    return {CellKind::triangle, -1};
  }

 private:
  GmshTables() {  // called with the gmsh lock held (instance())
    for (CellKind kind : {CellKind::triangle, CellKind::tetrahedron})
      for (int order = 1; order <= k_max_order; ++order) {
        const int dim = cell_dimension(kind);
        GmshElement& e = m_elements[kind == CellKind::triangle ? 0 : 1][order];
        e.type = gmsh::model::mesh::getElementType(
            kind == CellKind::triangle ? "Triangle" : "Tetrahedron", order);
        std::string name;
        int gdim = 0, gorder = 0, num_nodes = 0, num_primary = 0;
        std::vector<double> coords;
        gmsh::model::mesh::getElementProperties(e.type, name, gdim, gorder, num_nodes, coords,
                                                num_primary);
        const std::string what = "Gmsh element type " + std::to_string(e.type) + " (" + name + ")";
        CF_VERIFY(gdim == dim && gorder == order && num_nodes == num_lagrange_nodes(kind, order) &&
                      static_cast<int>(coords.size()) == dim * num_nodes,
                  what + " is not a complete Lagrange " + kind_name(kind) + " of order " +
                      std::to_string(order));
        Eigen::MatrixXd x(num_nodes, dim);
        for (int i = 0; i < num_nodes; ++i)
          for (int d = 0; d < dim; ++d) x(i, d) = coords[static_cast<std::size_t>(dim) * i + d];
        e.perm = detail::match_reference_nodes(x, kind, order, k_match_tolerance, what);
      }
  }

  std::array<std::array<GmshElement, k_max_order + 1>, 2> m_elements;
};

// --- MSH 4.1 text output ---------------------------------------------------------------------

class TextBuffer {
 public:
  TextBuffer& operator<<(const char* s) {
    m_text += s;
    return *this;
  }
  TextBuffer& operator<<(const std::string& s) {
    m_text += s;
    return *this;
  }
  TextBuffer& operator<<(char c) {
    m_text += c;
    return *this;
  }
  template <class T>
  requires std::is_arithmetic_v<T> TextBuffer& operator<<(T value) {
    char buffer[64];
    // Shortest representation that reads back to the same double: exact round trips.
    const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
    m_text.append(buffer, result.ptr);
    return *this;
  }
  const std::string& text() const { return m_text; }

 private:
  std::string m_text;
};

}  // namespace

std::vector<int> gmsh_node_permutation(CellKind kind, int order) {
  if (order < 1 || order > k_max_order)
    throw InputError("Gmsh node permutation: order " + std::to_string(order) + " is not in 1.." +
                     std::to_string(k_max_order));
  return GmshTables::instance().element(kind, order).perm;
}

void write_msh(const std::filesystem::path& path, const LagrangeMesh& mesh) {
  validate_structure(mesh, "write_msh " + path.string());
  const GmshElement& element = GmshTables::instance().element(mesh.kind, mesh.order);
  const int dim = cell_dimension(mesh.kind);
  const int n = mesh.nodes_per_cell();
  const bool tagged = mesh.cell_tags.size() > 0;

  // One elementary entity per distinct tag (entity tags 1, 2, .. in increasing tag order); tag
  // t > 0 becomes physical group t, tag 0 an entity without physical group.
  std::vector<int> distinct;
  if (tagged) {
    for (int c = 0; c < mesh.num_cells(); ++c)
      if (mesh.cell_tags[c] < 0)
        throw InputError("negative cell tag " + std::to_string(mesh.cell_tags[c]) +
                             " (MSH physical tags are positive; 0 = no physical group)",
                         {.file = path.string(), .element = c});
    distinct.assign(mesh.cell_tags.begin(), mesh.cell_tags.end());
    std::sort(distinct.begin(), distinct.end());
    distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
  } else {
    distinct.push_back(0);
  }
  const int num_entities = static_cast<int>(distinct.size());
  auto entity_of = [&](int c) {
    if (!tagged) return 0;
    return static_cast<int>(std::lower_bound(distinct.begin(), distinct.end(), mesh.cell_tags[c]) -
                            distinct.begin());
  };
  std::vector<std::vector<int>> cells_of(num_entities);
  for (int c = 0; c < mesh.num_cells(); ++c) cells_of[entity_of(c)].push_back(c);

  TextBuffer out;
  out << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
  const long physical_count =
      std::count_if(distinct.begin(), distinct.end(), [](int t) { return t > 0; });
  if (physical_count > 0) {
    out << "$PhysicalNames\n" << physical_count << '\n';
    for (int t : distinct)
      if (t > 0) out << dim << ' ' << t << " \"tag_" << t << "\"\n";
    out << "$EndPhysicalNames\n";
  }

  out << "$Entities\n0 0 " << (dim == 2 ? num_entities : 0) << ' ' << (dim == 3 ? num_entities : 0)
      << '\n';
  for (int e = 0; e < num_entities; ++e) {
    Eigen::RowVector3d lo = Eigen::RowVector3d::Zero(), hi = Eigen::RowVector3d::Zero();
    bool first = true;
    for (int c : cells_of[e])
      for (int i = 0; i < n; ++i) {
        const Eigen::RowVector3d x = mesh.nodes.row(mesh.cells(c, i));
        lo = first ? x : lo.cwiseMin(x);
        hi = first ? x : hi.cwiseMax(x);
        first = false;
      }
    out << e + 1 << ' ' << lo[0] << ' ' << lo[1] << ' ' << lo[2] << ' ' << hi[0] << ' ' << hi[1]
        << ' ' << hi[2];
    if (distinct[e] > 0)
      out << " 1 " << distinct[e];
    else
      out << " 0";
    out << " 0\n";  // no bounding entities
  }
  out << "$EndEntities\n";

  // All nodes (also unreferenced and interior high-order ones), tags 1..N, in one block.
  const long long num_nodes = mesh.num_nodes();
  out << "$Nodes\n"
      << (num_nodes > 0 ? 1 : 0) << ' ' << num_nodes << ' ' << (num_nodes > 0 ? 1 : 0) << ' '
      << num_nodes << '\n';
  if (num_nodes > 0) {
    out << dim << " 1 0 " << num_nodes << '\n';
    for (long long i = 0; i < num_nodes; ++i) out << i + 1 << '\n';
    for (long long i = 0; i < num_nodes; ++i)
      out << mesh.nodes(i, 0) << ' ' << mesh.nodes(i, 1) << ' ' << mesh.nodes(i, 2) << '\n';
  }
  out << "$EndNodes\n";

  // Element tag = cell index + 1, so the cell order survives regrouping by entity.
  int blocks = 0;
  for (const auto& cells : cells_of) blocks += cells.empty() ? 0 : 1;
  out << "$Elements\n"
      << blocks << ' ' << mesh.num_cells() << ' ' << (mesh.num_cells() > 0 ? 1 : 0) << ' '
      << mesh.num_cells() << '\n';
  for (int e = 0; e < num_entities; ++e) {
    if (cells_of[e].empty()) continue;
    out << dim << ' ' << e + 1 << ' ' << element.type << ' ' << cells_of[e].size() << '\n';
    for (int c : cells_of[e]) {
      out << c + 1;
      for (int i = 0; i < n; ++i) out << ' ' << mesh.cells(c, element.perm[i]) + 1;
      out << '\n';
    }
  }
  out << "$EndElements\n";

  write_text_file_atomic(path, out.text());
  log::debug("wrote ", path.string(), ": ", mesh.num_cells(), " ", kind_name(mesh.kind),
             "s of order ", mesh.order, " (Gmsh type ", element.type, "), ", num_nodes, " nodes");
}

SurfaceMesh read_msh_boundary_triangles(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw IoError(std::filesystem::exists(path, ec) ? "not a regular file" : "file not found",
                  {.file = file});
  const GmshTables& tables = GmshTables::instance();
  const detail::MshData data = detail::parse_msh(path);
  std::vector<std::array<int, 3>> faces;
  std::vector<int> tags;
  std::unordered_map<int, int> vertex;  // row of data.nodes → vertex id
  std::vector<int> rows;
  for (const auto& block : data.blocks) {
    const auto [kind, order] = tables.find(block.gmsh_type);
    if (order < 0 || kind != CellKind::triangle) continue;
    for (std::size_t e = 0; e < block.element_ids.size(); ++e) {
      std::array<int, 3> f;
      for (int c = 0; c < 3; ++c) {  // the first three nodes are the corners in every order
        const int row = data.node_index.at(block.node_ids[e * block.nodes_per_element + c]);
        auto [it, inserted] = vertex.try_emplace(row, static_cast<int>(rows.size()));
        if (inserted) rows.push_back(row);
        f[c] = it->second;
      }
      faces.push_back(f);
      tags.push_back(block.physical_tags.empty() ? 0 : block.physical_tags[e]);
    }
  }
  if (faces.empty()) throw InputError("no triangle elements", {.file = file});
  SurfaceMesh m;
  m.V.resize(static_cast<Eigen::Index>(rows.size()), 3);
  for (std::size_t i = 0; i < rows.size(); ++i)
    m.V.row(static_cast<Eigen::Index>(i)) = data.nodes.row(rows[i]);
  m.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  m.tags.resize(static_cast<Eigen::Index>(faces.size()));
  for (std::size_t i = 0; i < faces.size(); ++i) {
    for (int c = 0; c < 3; ++c) m.F(static_cast<Eigen::Index>(i), c) = faces[i][c];
    m.tags[static_cast<Eigen::Index>(i)] = tags[i];
  }
  return m;
}

LagrangeMesh read_msh(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))  // as every reader: cannot open = I/O failure
    throw IoError(std::filesystem::exists(path, ec) ? "not a regular file" : "file not found",
                  {.file = file});
  const GmshTables& tables = GmshTables::instance();
  const detail::MshData data = detail::parse_msh(path);

  // The highest-dimensional simplices: tetrahedra if the file has any, else triangles.
  bool has_tets = false, has_triangles = false;
  for (const auto& block : data.blocks) {
    const auto [kind, order] = tables.find(block.gmsh_type);
    if (order < 0) continue;
    (kind == CellKind::tetrahedron ? has_tets : has_triangles) = true;
  }
  if (!has_tets && !has_triangles)
    throw InputError("no triangles or tetrahedra of order 1.." + std::to_string(k_max_order) +
                         " (complete Lagrange elements)",
                     {.file = file});
  const CellKind kind = has_tets ? CellKind::tetrahedron : CellKind::triangle;
  const int dim = cell_dimension(kind);

  struct Ref {
    long long id;
    int block;
    std::size_t index;
  };
  std::vector<Ref> refs;
  int order = -1;
  long long ignored = 0;
  for (int b = 0; b < static_cast<int>(data.blocks.size()); ++b) {
    const auto& block = data.blocks[b];
    const auto [block_kind, block_order] = tables.find(block.gmsh_type);
    if (block_order < 0 || block_kind != kind) {
      if (block.dim >= dim) ignored += static_cast<long long>(block.element_ids.size());
      continue;
    }
    if (block.element_ids.empty()) continue;
    if (order < 0) order = block_order;
    if (block_order != order)
      throw InputError("mixed orders: " + std::string(kind_name(kind)) + "s of order " +
                           std::to_string(block_order) + " after order " + std::to_string(order) +
                           " (one order per file)",
                       {.file = file, .element = block.element_ids.front()});
    CF_VERIFY(block.nodes_per_element == num_lagrange_nodes(kind, order) &&
                  block.node_ids.size() ==
                      block.element_ids.size() * static_cast<std::size_t>(block.nodes_per_element),
              "MSH parser returned an inconsistent element block");
    for (std::size_t i = 0; i < block.element_ids.size(); ++i)
      refs.push_back({block.element_ids[i], b, i});
  }
  if (ignored > 0)
    log::warn(file, ": ignored ", ignored, " elements of dimension ≥ ", dim,
              " that are not complete Lagrange ", kind_name(kind), "s");
  if (refs.empty())
    throw InputError(std::string("no ") + kind_name(kind) + " elements", {.file = file});
  // Element ids give the cell order (write_msh stores cell c as element c + 1).
  std::stable_sort(refs.begin(), refs.end(),
                   [](const Ref& a, const Ref& b) { return a.id < b.id; });

  const int n = num_lagrange_nodes(kind, order);
  const std::vector<int>& perm = tables.element(kind, order).perm;
  LagrangeMesh mesh;
  mesh.kind = kind;
  mesh.order = order;
  mesh.cells.resize(static_cast<Eigen::Index>(refs.size()), n);
  bool any_physical = false;
  Eigen::VectorXi tags(static_cast<Eigen::Index>(refs.size()));
  for (std::size_t c = 0; c < refs.size(); ++c) {
    const auto& block = data.blocks[refs[c].block];
    for (int i = 0; i < n; ++i) {
      const long long id = block.node_ids[refs[c].index * n + i];
      const auto it = data.node_index.find(id);
      if (it == data.node_index.end())
        throw InputError("element references undefined node " + std::to_string(id),
                         {.file = file, .element = refs[c].id});
      mesh.cells(static_cast<Eigen::Index>(c), perm[i]) = it->second;  // row in data.nodes
    }
    const int tag = block.physical_tags.empty() ? 0 : block.physical_tags[refs[c].index];
    tags[static_cast<Eigen::Index>(c)] = tag;
    any_physical = any_physical || tag != 0;
  }
  if (any_physical) mesh.cell_tags = tags;

  // Compact renumbering: referenced nodes only, in their order in the file.
  std::vector<int> new_id(static_cast<std::size_t>(data.nodes.rows()), -1);
  for (Eigen::Index c = 0; c < mesh.cells.rows(); ++c)
    for (int i = 0; i < n; ++i) new_id[mesh.cells(c, i)] = 0;
  int count = 0;
  for (int& id : new_id)
    if (id == 0) id = count++;
  mesh.nodes.resize(count, 3);
  for (std::size_t r = 0; r < new_id.size(); ++r)
    if (new_id[r] >= 0) mesh.nodes.row(new_id[r]) = data.nodes.row(static_cast<Eigen::Index>(r));
  for (Eigen::Index c = 0; c < mesh.cells.rows(); ++c)
    for (int i = 0; i < n; ++i) mesh.cells(c, i) = new_id[mesh.cells(c, i)];

  validate_structure(mesh, file);  // non-finite coordinates
  log::debug("read ", file, ": ", mesh.num_cells(), " ", kind_name(kind), "s of order ", order,
             ", ", mesh.num_nodes(), " nodes");
  return mesh;
}

}  // namespace curvefem::io
