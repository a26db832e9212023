// Bounds-checked parser of Gmsh MSH 2.x and 4.1 files, ascii and binary.
//
// Layout (gmsh.info/doc/texinfo, "MSH file format"): sections "$Name" ... "$EndName". In ascii
// files every number is a blank-separated token (read here across line breaks); in binary files
// the section bodies are raw numbers (2.x: int32 and double; 4.1: int32, double and the size_t of
// $MeshFormat, i.e. uint64) while the section markers, the 2.x count lines and $PhysicalNames stay
// text. Text errors name the line (ascii) or the byte offset (binary); unknown sections are
// skipped by searching for their end marker.
#include "meshing/io/msh_parser.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

#include "meshing/core/error.hpp"
#include "meshing/io/text_scanner.hpp"

namespace curvefem::io::detail {

namespace {

struct TypeInfo {
  int type, nodes, dim;
};

// Gmsh element types: number, nodes per element, dimension (the MSH format's table).
constexpr std::array<TypeInfo, 33> k_types = {{
    {1, 2, 1},   {2, 3, 2},   {3, 4, 2},   {4, 4, 3},   {5, 8, 3},    {6, 6, 3},   {7, 5, 3},
    {8, 3, 1},   {9, 6, 2},   {10, 9, 2},  {11, 10, 3}, {12, 27, 3},  {13, 18, 3}, {14, 14, 3},
    {15, 1, 0},  {16, 8, 2},  {17, 20, 3}, {18, 15, 3}, {19, 13, 3},  {20, 9, 2},  {21, 10, 2},
    {22, 12, 2}, {23, 15, 2}, {24, 15, 2}, {25, 21, 2}, {26, 4, 1},   {27, 5, 1},  {28, 6, 1},
    {29, 20, 3}, {30, 35, 3}, {31, 56, 3}, {92, 64, 3}, {93, 125, 3},
}};

const TypeInfo* find_type(long long type) {
  for (const auto& t : k_types)
    if (t.type == type) return &t;
  return nullptr;
}

constexpr long long k_max_int = std::numeric_limits<int>::max();

// Numbers of a section body, from text tokens (ascii) or raw bytes (binary).
class Source {
 public:
  Source(TextScanner* text, BinaryReader* bin) : m_text(text), m_bin(bin) {}
  bool binary() const { return m_bin != nullptr; }

  /// An int (binary: int32).
  long long integer(std::string_view what) {
    if (m_bin) return m_bin->read<std::int32_t>(what);
    return token_int(what);
  }
  /// A size_t of MSH 4.1 (binary: uint64), as a non-negative long long.
  long long size(std::string_view what) {
    if (m_bin) {
      const std::size_t at = m_bin->offset();
      const std::uint64_t v = m_bin->read<std::uint64_t>(what);
      if (v > static_cast<std::uint64_t>(std::numeric_limits<long long>::max()))
        m_bin->fail_at(at, std::string(what) + " is absurdly large");
      return static_cast<long long>(v);
    }
    const long long v = token_int(what);
    if (v < 0) fail(std::string(what) + " is negative (" + std::to_string(v) + ")");
    return v;
  }
  double real(std::string_view what) {
    if (m_bin) return m_bin->read<double>(what);
    std::string_view t = next_token(what);
    double v;
    if (!parse_double(t, v))
      fail("expected a number for " + std::string(what) + ", got \"" +
           std::string(t.substr(0, 40)) + "\"");
    return v;
  }
  /// Bytes left in the file after the current position.
  std::size_t remaining() const {
    return m_bin ? m_bin->remaining() : m_text->bytes_left() + m_text->rest().size();
  }
  /// Marks the start of a value for binary error offsets.
  void mark() {
    if (m_bin) m_mark = m_bin->offset();
  }
  [[noreturn]] void fail(const std::string& defect) const {
    if (m_bin) m_bin->fail_at(m_mark ? *m_mark : m_bin->offset(), defect);
    m_text->fail(defect);
  }

 private:
  std::string_view next_token(std::string_view what) {
    for (;;) {
      std::string_view t = m_text->token();
      if (!t.empty()) return t;
      if (!m_text->next_line()) m_text->fail("truncated: expected " + std::string(what));
      if (!m_text->at_line_end() && m_text->rest()[0] == '$')
        m_text->fail("section ends early: expected " + std::string(what) + ", got \"" +
                     std::string(trim(m_text->rest()).substr(0, 40)) + "\" (count mismatch?)");
    }
  }
  long long token_int(std::string_view what) {
    std::string_view t = next_token(what);
    long long v;
    if (!parse_int(t, v))
      fail("expected an integer for " + std::string(what) + ", got \"" +
           std::string(t.substr(0, 40)) + "\"");
    return v;
  }

  TextScanner* m_text;
  BinaryReader* m_bin;
  std::optional<std::size_t> m_mark;
};

class MshParser {
 public:
  MshParser(std::string_view data, std::string file)
      : m_data(data), m_file(std::move(file)), m_text(data, m_file) {}

  MshData run() {
    if (trim(m_data).empty()) throw InputError("empty file", {.file = m_file});
    if (next_line() && (section_name() == "NOD" || section_name() == "NOE"))
      m_text.fail("MSH 1.0 files are not supported (re-save as MSH 2.2 or 4.1)");
    if (m_text.line_number() < 1 || section_name() != "MeshFormat")
      m_text.fail("not a Gmsh MSH file (expected \"$MeshFormat\" first)");
    parse_format();
    while (next_line()) {
      std::string_view name = section_name();
      if (name.empty())
        m_text.fail("expected a section header \"$Name\", got \"" +
                    std::string(trim(m_text.line()).substr(0, 40)) + "\"");
      if (name.substr(0, 3) == "End")
        m_text.fail("unexpected \"$" + std::string(name.substr(0, 40)) + "\" (no section open)");
      if (name == "MeshFormat") m_text.fail("duplicate $MeshFormat section");
      while (!m_text.at_line_end()) m_text.token();  // the section header is consumed
      if (name == "PhysicalNames") {
        parse_physical_names();
      } else if (name == "Entities" && m_major == 4) {
        parse_entities();
      } else if (name == "Nodes") {
        if (m_have_nodes) m_text.fail("duplicate $Nodes section");
        m_major == 4 ? parse_nodes_41() : parse_nodes_22();
        m_have_nodes = true;
      } else if (name == "Elements") {
        if (m_have_elements) m_text.fail("duplicate $Elements section");
        m_major == 4 ? parse_elements_41() : parse_elements_22();
        m_have_elements = true;
      } else {
        skip_section(name);
      }
    }
    if (!m_have_nodes) throw InputError("no $Nodes section", {.file = m_file});
    if (!m_have_elements) throw InputError("no $Elements section", {.file = m_file});
    if (m_deferred_node_check) check_all_node_references();
    return std::move(m_out);
  }

 private:
  // ------------------------------------------------------------------------------ text helpers
  bool next_line() { return m_text.next_content_line('\0'); }

  // "Name" if the current line is "$Name", else empty.
  std::string_view section_name() {
    std::string_view l = trim(m_text.line());
    if (l.size() < 2 || l[0] != '$') return {};
    return l.substr(1);
  }

  void expect_end(std::string_view name) {
    const std::string end = "$End" + std::string(name);
    if (!m_text.at_line_end())
      m_text.fail("unexpected \"" + std::string(trim(m_text.rest()).substr(0, 40)) +
                  "\" at the end of $" + std::string(name) + " (count mismatch?)");
    if (!next_line()) m_text.fail("truncated: missing \"" + end + "\"");
    if (trim(m_text.line()) != end)
      m_text.fail("expected \"" + end + "\", got \"" +
                  std::string(trim(m_text.line()).substr(0, 40)) + "\" (count mismatch?)");
  }

  // Continues reading text at byte `offset` (after binary data).
  void resume_text(std::size_t offset) {
    m_text = TextScanner(m_data, m_file, offset);
    m_text.set_report_byte_offsets(true);
  }

  BinaryReader binary_here() {
    return BinaryReader(m_data, m_file, m_text.next_line_offset(), m_swap);
  }

  void skip_section(std::string_view name) {
    const std::string end = "$End" + std::string(name);
    const std::size_t from = m_text.next_line_offset();
    std::size_t at = from;
    for (;;) {
      at = m_data.find(end, at);
      if (at == std::string_view::npos)
        m_text.fail("truncated: section $" + std::string(name.substr(0, 40)) + " has no \"" +
                    end.substr(0, 44) + "\"");
      if (at == 0 || m_data[at - 1] == '\n') break;
      ++at;
    }
    const long long line = m_text.line_number() + 1 +
                           std::count(m_data.begin() + static_cast<std::ptrdiff_t>(from),
                                      m_data.begin() + static_cast<std::ptrdiff_t>(at), '\n');
    const bool offsets = m_out.binary;
    m_text = TextScanner(m_data, m_file, at, line);
    m_text.set_report_byte_offsets(offsets);
    next_line();  // the end marker
  }

  // ---------------------------------------------------------------------------------- sections
  void parse_format() {
    if (!next_line()) m_text.fail("truncated: missing the MSH version line");
    std::string_view version_text = m_text.token();
    double version;
    if (!parse_double(version_text, version))
      m_text.fail("bad MSH version \"" + std::string(version_text.substr(0, 40)) + "\"");
    if (version >= 2.0 && version < 3.0) {
      m_major = 2;
    } else if (version == 4.1) {
      m_major = 4;
    } else {
      m_text.fail("unsupported MSH version " + std::string(version_text.substr(0, 20)) +
                  " (curvefem reads 2.2 and 4.1)");
    }
    m_out.version = version;
    const long long file_type = m_text.integer_in("MSH file type", 0, 1);
    const long long data_size = m_text.integer("MSH data size");
    m_text.expect_line_end("the MSH version line");
    m_out.binary = file_type == 1;
    if (m_out.binary) {
      if (data_size != 8)
        m_text.fail("unsupported data size " + std::to_string(data_size) +
                    " in a binary MSH (only 8)");
      BinaryReader bin = binary_here();
      const std::int32_t one = bin.read<std::int32_t>("the binary endianness marker");
      if (one != 1) {
        std::int32_t swapped;
        BinaryReader again(m_data, m_file, bin.offset() - 4, true);
        swapped = again.read<std::int32_t>("the binary endianness marker");
        if (swapped != 1)
          bin.fail_at(bin.offset() - 4, "bad binary endianness marker (expected the int 1)");
        m_swap = true;
      }
      resume_text(bin.offset());
    }
    expect_end("MeshFormat");
  }

  void parse_physical_names() {
    if (!next_line()) m_text.fail("truncated: missing the number of physical names");
    const long long n = m_text.integer("number of physical names");
    m_text.expect_line_end("the number of physical names");
    check_count(n, 6, m_text.bytes_left(), "physical names", m_file,
                m_out.binary ? -1 : m_text.line_number(),
                static_cast<long long>(m_text.line_offset()));
    for (long long i = 0; i < n; ++i) {
      if (!next_line()) m_text.fail("truncated: expected " + std::to_string(n) + " physical names");
      const long long dim = m_text.integer_in("physical dimension", 0, 3);
      const long long tag = m_text.integer_in("physical tag", -k_max_int, k_max_int);
      std::string_view name = trim(m_text.rest());
      if (name.size() < 2 || name.front() != '"' || name.back() != '"')
        m_text.fail("physical name must be in double quotes");
      std::string value(name.substr(1, name.size() - 2));
      m_out.physical_names_by_dim[{static_cast<int>(dim), static_cast<int>(tag)}] = value;
      m_text.token();  // consume the rest of the line
      while (!m_text.at_line_end()) m_text.token();
    }
    // physical_names: tag → name, the highest dimension winning on a clash.
    for (const auto& [key, name] : m_out.physical_names_by_dim)
      m_out.physical_names[key.second] = name;
    expect_end("PhysicalNames");
  }

  // Runs `body(Source&)` over the section data in the file's representation.
  template <class Body>
  void with_source(Body&& body) {
    if (m_out.binary) {
      BinaryReader bin = binary_here();
      Source src(&m_text, &bin);
      body(src);
      resume_text(bin.offset());
    } else {
      Source src(&m_text, nullptr);
      body(src);
    }
  }

  void parse_entities() {
    with_source([&](Source& src) {
      long long counts[4];
      for (long long& c : counts) c = src.size("number of entities");
      for (int dim = 0; dim < 4; ++dim) {
        const std::size_t each = src.binary() ? (dim == 0 ? 36 : 68) : (dim == 0 ? 10 : 18);
        src.mark();
        if (counts[dim] > 0 &&
            static_cast<unsigned long long>(counts[dim]) > src.remaining() / each)
          src.fail("announces " + std::to_string(counts[dim]) + " entities of dimension " +
                   std::to_string(dim) + " but only " + std::to_string(src.remaining()) +
                   " bytes follow (truncated file or absurd count)");
        for (long long e = 0; e < counts[dim]; ++e) {
          const long long tag = src.integer("entity tag");
          for (int k = 0; k < (dim == 0 ? 3 : 6); ++k) src.real("entity coordinate");
          src.mark();
          const long long nphys = src.size("number of physical tags");
          check_list(src, nphys, "physical tags");
          long long first = 0;
          for (long long k = 0; k < nphys; ++k) {
            const long long p = src.integer("physical tag");
            if (k == 0) first = p;
          }
          if (first < -k_max_int || first > k_max_int || tag < -k_max_int || tag > k_max_int)
            src.fail("entity or physical tag out of range");
          m_entity_physical[{dim, static_cast<int>(tag)}] = static_cast<int>(first);
          if (dim > 0) {
            src.mark();
            const long long nb = src.size("number of bounding entities");
            check_list(src, nb, "bounding entities");
            for (long long k = 0; k < nb; ++k) src.integer("bounding entity tag");
          }
        }
      }
    });
    expect_end("Entities");
  }

  // A list of `n` int32 / tokens must fit in what is left.
  static void check_list(Source& src, long long n, std::string_view what) {
    const std::size_t each = src.binary() ? 4 : 2;
    if (n < 0 || static_cast<unsigned long long>(n) > src.remaining() / each)
      src.fail("absurd number of " + std::string(what) + " (" + std::to_string(n) + ") for the " +
               std::to_string(src.remaining()) + " bytes left");
  }

  void add_node(Source& src, long long id, double x, double y, double z, long long row) {
    if (id <= 0) src.fail("node id " + std::to_string(id) + " (ids must be positive)");
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
      src.fail("node " + std::to_string(id) + " has a NaN/inf coordinate");
    auto [it, inserted] = m_out.node_index.try_emplace(id, static_cast<int>(row));
    if (!inserted) src.fail("duplicate node id " + std::to_string(id));
    m_out.nodes(row, 0) = x;
    m_out.nodes(row, 1) = y;
    m_out.nodes(row, 2) = z;
  }

  void parse_nodes_22() {
    if (!next_line()) m_text.fail("truncated: missing the number of nodes");
    const long long n = m_text.integer("number of nodes");
    m_text.expect_line_end("the number of nodes");
    check_count(n, m_out.binary ? 28 : 8, m_text.bytes_left(), "nodes", m_file,
                m_out.binary ? -1 : m_text.line_number(),
                static_cast<long long>(m_text.line_offset()), k_max_int);
    m_out.nodes.resize(n, 3);
    m_out.node_index.reserve(static_cast<std::size_t>(n));
    with_source([&](Source& src) {
      for (long long i = 0; i < n; ++i) {
        src.mark();
        const long long id = src.integer("node id");
        const double x = src.real("node x"), y = src.real("node y"), z = src.real("node z");
        add_node(src, id, x, y, z, i);
      }
    });
    expect_end("Nodes");
  }

  void parse_nodes_41() {
    with_source([&](Source& src) {
      src.mark();
      const long long blocks = src.size("number of node blocks");
      const long long n = src.size("number of nodes");
      src.size("minimum node tag");
      src.size("maximum node tag");
      const bool bin = src.binary();
      if (n > k_max_int) src.fail("too many nodes (" + std::to_string(n) + ")");
      if (static_cast<unsigned long long>(n) > src.remaining() / (bin ? 32 : 8) ||
          static_cast<unsigned long long>(blocks) > src.remaining() / (bin ? 20 : 8))
        src.fail("announces " + std::to_string(n) + " nodes in " + std::to_string(blocks) +
                 " blocks but only " + std::to_string(src.remaining()) +
                 " bytes follow (truncated file or absurd count)");
      m_out.nodes.resize(n, 3);
      m_out.node_index.reserve(static_cast<std::size_t>(n));
      long long filled = 0;
      std::vector<long long> ids;
      for (long long b = 0; b < blocks; ++b) {
        src.mark();
        const long long dim = src.integer("node block entity dimension");
        src.integer("node block entity tag");
        const long long parametric = src.integer("node block parametric flag");
        const long long count = src.size("number of nodes in the block");
        if (dim < 0 || dim > 3) src.fail("bad entity dimension " + std::to_string(dim));
        if (parametric != 0 && parametric != 1)
          src.fail("bad parametric flag " + std::to_string(parametric));
        if (count > n - filled)
          src.fail("node blocks hold more nodes than the " + std::to_string(n) +
                   " announced in the header");
        ids.resize(static_cast<std::size_t>(count));
        for (auto& id : ids) {
          src.mark();
          id = src.size("node tag");
        }
        const int params = parametric ? static_cast<int>(dim) : 0;
        for (long long k = 0; k < count; ++k) {
          src.mark();
          const double x = src.real("node x"), y = src.real("node y"), z = src.real("node z");
          for (int p = 0; p < params; ++p) src.real("node parametric coordinate");
          add_node(src, ids[static_cast<std::size_t>(k)], x, y, z, filled + k);
        }
        filled += count;
      }
      if (filled != n)
        src.fail("node blocks hold " + std::to_string(filled) + " nodes, the header announces " +
                 std::to_string(n));
    });
    expect_end("Nodes");
  }

  void check_node(Source& src, long long node_id, long long element_id) {
    if (m_have_nodes && !m_out.node_index.count(node_id))
      src.fail("element " + std::to_string(element_id) + " references node " +
               std::to_string(node_id) + ", which is not in $Nodes");
    if (!m_have_nodes) m_deferred_node_check = true;
  }

  void check_all_node_references() {
    for (const auto& block : m_out.blocks)
      for (std::size_t k = 0; k < block.node_ids.size(); ++k)
        if (!m_out.node_index.count(block.node_ids[k]))
          throw InputError(
              "element " +
                  std::to_string(
                      block.element_ids[k / static_cast<std::size_t>(block.nodes_per_element)]) +
                  " references node " + std::to_string(block.node_ids[k]) +
                  ", which is not in $Nodes",
              {.file = m_file});
  }

  const TypeInfo& element_type(Source& src, long long type) {
    const TypeInfo* info = find_type(type);
    if (!info) src.fail("unknown or unsupported Gmsh element type " + std::to_string(type));
    return *info;
  }

  void parse_elements_22() {
    if (!next_line()) m_text.fail("truncated: missing the number of elements");
    const long long n = m_text.integer("number of elements");
    m_text.expect_line_end("the number of elements");
    check_count(n, m_out.binary ? 12 : 8, m_text.bytes_left(), "elements", m_file,
                m_out.binary ? -1 : m_text.line_number(),
                static_cast<long long>(m_text.line_offset()), k_max_int);
    with_source([&](Source& src) {
      MshElementBlock* block = nullptr;
      // Starts a new block unless the element continues the current one.
      auto block_for = [&](const TypeInfo& info, long long elementary) -> MshElementBlock& {
        if (!block || block->gmsh_type != info.type || block->entity_tag != elementary) {
          MshElementBlock& b = m_out.blocks.emplace_back();
          b.gmsh_type = info.type;
          b.dim = info.dim;
          b.entity_tag = static_cast<int>(elementary);
          b.nodes_per_element = info.nodes;
          block = &b;
        }
        return *block;
      };
      std::vector<long long> tags;
      // The rest of an element after its id: ntags tags (physical, elementary, ...), nodes.
      auto read_element = [&](const TypeInfo& info, long long id, long long ntags) {
        tags.resize(static_cast<std::size_t>(ntags));
        for (auto& t : tags) t = src.integer("element tag");
        const long long physical = ntags >= 1 ? tags[0] : 0;
        const long long elementary = ntags >= 2 ? tags[1] : 0;
        if (std::abs(physical) > k_max_int || std::abs(elementary) > k_max_int)
          src.fail("element tag out of range");
        MshElementBlock& b = block_for(info, elementary);
        b.element_ids.push_back(id);
        b.physical_tags.push_back(static_cast<int>(physical));
        for (int k = 0; k < info.nodes; ++k) {
          const long long node = src.integer("element node");
          check_node(src, node, id);
          b.node_ids.push_back(node);
        }
      };
      if (!src.binary()) {
        for (long long i = 0; i < n; ++i) {
          const long long id = src.integer("element id");
          const TypeInfo& info = element_type(src, src.integer("element type"));
          const long long ntags = src.integer("number of element tags");
          check_list(src, ntags, "element tags");
          read_element(info, id, ntags);
        }
        return;
      }
      long long read = 0;
      while (read < n) {
        src.mark();
        const long long type = src.integer("element type");
        const long long count = src.integer("number of elements following");
        const long long ntags = src.integer("number of element tags");
        const TypeInfo& info = element_type(src, type);
        if (count <= 0 || count > n - read)
          src.fail("element block of " + std::to_string(count) + " elements (" +
                   std::to_string(n - read) + " left of the " + std::to_string(n) + " announced)");
        if (ntags < 0 || ntags > 1000)
          src.fail("bad number of element tags " + std::to_string(ntags));
        const unsigned long long bytes = static_cast<unsigned long long>(count) *
                                         static_cast<unsigned long long>(1 + ntags + info.nodes) *
                                         4;
        if (bytes > src.remaining())
          src.fail("truncated: element block needs " + std::to_string(bytes) + " bytes, only " +
                   std::to_string(src.remaining()) + " left");
        for (long long k = 0; k < count; ++k) {
          src.mark();
          read_element(info, src.integer("element id"), ntags);
        }
        read += count;
      }
    });
    expect_end("Elements");
  }

  void parse_elements_41() {
    with_source([&](Source& src) {
      src.mark();
      const long long blocks = src.size("number of element blocks");
      const long long n = src.size("number of elements");
      src.size("minimum element tag");
      src.size("maximum element tag");
      const bool bin = src.binary();
      if (n > k_max_int) src.fail("too many elements (" + std::to_string(n) + ")");
      if (static_cast<unsigned long long>(n) > src.remaining() / (bin ? 16 : 4) ||
          static_cast<unsigned long long>(blocks) > src.remaining() / (bin ? 20 : 8))
        src.fail("announces " + std::to_string(n) + " elements in " + std::to_string(blocks) +
                 " blocks but only " + std::to_string(src.remaining()) +
                 " bytes follow (truncated file or absurd count)");
      long long read = 0;
      for (long long b = 0; b < blocks; ++b) {
        src.mark();
        const long long dim = src.integer("element block entity dimension");
        const long long entity = src.integer("element block entity tag");
        const long long type = src.integer("element type");
        const long long count = src.size("number of elements in the block");
        const TypeInfo& info = element_type(src, type);
        if (dim != info.dim)
          src.fail("element block of dimension " + std::to_string(dim) + " holds element type " +
                   std::to_string(type) + " of dimension " + std::to_string(info.dim));
        if (entity < -k_max_int || entity > k_max_int) src.fail("entity tag out of range");
        if (count > n - read)
          src.fail("element blocks hold more elements than the " + std::to_string(n) +
                   " announced in the header");
        const unsigned long long each =
            static_cast<unsigned long long>(info.nodes + 1) * (bin ? 8 : 2);
        if (static_cast<unsigned long long>(count) > src.remaining() / each)
          src.fail("truncated: element block of " + std::to_string(count) + " elements needs " +
                   "more than the " + std::to_string(src.remaining()) + " bytes left");
        MshElementBlock& blk = m_out.blocks.emplace_back();
        blk.gmsh_type = info.type;
        blk.dim = info.dim;
        blk.entity_tag = static_cast<int>(entity);
        blk.nodes_per_element = info.nodes;
        auto phys = m_entity_physical.find({info.dim, static_cast<int>(entity)});
        const int physical = phys != m_entity_physical.end() ? phys->second : 0;
        blk.element_ids.resize(static_cast<std::size_t>(count));
        blk.node_ids.resize(static_cast<std::size_t>(count * info.nodes));
        blk.physical_tags.assign(static_cast<std::size_t>(count), physical);
        for (long long k = 0; k < count; ++k) {
          src.mark();
          const long long id = src.size("element tag");
          blk.element_ids[static_cast<std::size_t>(k)] = id;
          for (int j = 0; j < info.nodes; ++j) {
            const long long node = src.size("element node tag");
            check_node(src, node, id);
            blk.node_ids[static_cast<std::size_t>(k * info.nodes + j)] = node;
          }
        }
        read += count;
      }
      if (read != n)
        src.fail("element blocks hold " + std::to_string(read) +
                 " elements, the header announces " + std::to_string(n));
    });
    expect_end("Elements");
  }

  std::string_view m_data;
  std::string m_file;
  TextScanner m_text;
  MshData m_out;
  int m_major = 0;
  bool m_swap = false;
  bool m_have_nodes = false, m_have_elements = false, m_deferred_node_check = false;
  std::map<std::pair<int, int>, int> m_entity_physical;  // (dim, entity) → first physical tag
};

}  // namespace

int gmsh_nodes_per_element(int gmsh_type) {
  const TypeInfo* info = find_type(gmsh_type);
  return info ? info->nodes : -1;
}

int gmsh_element_dim(int gmsh_type) {
  const TypeInfo* info = find_type(gmsh_type);
  return info ? info->dim : -1;
}

MshData parse_msh(const std::filesystem::path& path) {
  const std::string data = read_file_bytes(path);
  return MshParser(data, path.string()).run();
}

}  // namespace curvefem::io::detail
