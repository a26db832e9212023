// PLY reader: ascii, binary_little_endian, binary_big_endian.
//
// Vertex x, y, z of any numeric type; the face list `vertex_indices` (or `vertex_index`) of any
// count / index types; face tags from an integer face property named tag, tags, label, region,
// group, physical or material_index, else the first other integer face property. Other elements
// (edges, materials, ...) are skipped. "comment tag_name <tag> <name>" lines (written by
// write_surface) fill tag_names.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/io/text_scanner.hpp"

namespace curvefem::io {

namespace {

enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };

bool parse_type(std::string_view name, PlyType& type) {
  struct Entry {
    std::string_view a, b;
    PlyType t;
  };
  static constexpr std::array<Entry, 8> k_types = {{{"char", "int8", PlyType::i8},
                                                    {"uchar", "uint8", PlyType::u8},
                                                    {"short", "int16", PlyType::i16},
                                                    {"ushort", "uint16", PlyType::u16},
                                                    {"int", "int32", PlyType::i32},
                                                    {"uint", "uint32", PlyType::u32},
                                                    {"float", "float32", PlyType::f32},
                                                    {"double", "float64", PlyType::f64}}};
  for (const auto& e : k_types)
    if (name == e.a || name == e.b) {
      type = e.t;
      return true;
    }
  return false;
}

std::size_t type_size(PlyType t) {
  switch (t) {
    case PlyType::i8:
    case PlyType::u8:
      return 1;
    case PlyType::i16:
    case PlyType::u16:
      return 2;
    case PlyType::i32:
    case PlyType::u32:
    case PlyType::f32:
      return 4;
    case PlyType::f64:
      return 8;
  }
  return 8;
}

bool is_integer(PlyType t) { return t != PlyType::f32 && t != PlyType::f64; }

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::f32;
  bool is_list = false;
  PlyType count_type = PlyType::u8;
};

struct PlyElement {
  std::string name;
  long long count = 0;
  long long line = 0;
  std::vector<PlyProperty> props;
};

enum class PlyFormat { ascii, binary_le, binary_be };

struct PlyHeader {
  PlyFormat format = PlyFormat::ascii;
  std::vector<PlyElement> elements;
  std::map<int, std::string> tag_names;
  std::size_t data_offset = 0;
  long long data_line = 0;  // line of the first data line (ascii)
};

PlyHeader parse_header(std::string_view data, const std::string& file) {
  detail::TextScanner in(data, file);
  PlyHeader h;
  if (!in.next_line() || detail::trim(in.line()) != "ply")
    in.fail("not a PLY file (the first line must be \"ply\")");
  bool have_format = false;
  for (;;) {
    if (!in.next_line()) in.fail("truncated header: missing \"end_header\"");
    std::string_view key = in.token();
    if (key.empty()) continue;
    if (key == "end_header") break;
    if (key == "comment") {
      if (in.token() == "tag_name") {
        long long tag;
        if (detail::parse_int(in.token(), tag) && tag >= -2147483647LL && tag <= 2147483647LL)
          h.tag_names[static_cast<int>(tag)] = std::string(detail::trim(in.rest()));
      }
      continue;
    }
    if (key == "obj_info") continue;
    if (key == "format") {
      std::string_view f = in.token();
      if (f == "ascii")
        h.format = PlyFormat::ascii;
      else if (f == "binary_little_endian")
        h.format = PlyFormat::binary_le;
      else if (f == "binary_big_endian")
        h.format = PlyFormat::binary_be;
      else
        in.fail("unknown PLY format \"" + std::string(f.substr(0, 40)) + "\"");
      in.token();  // version
      have_format = true;
      continue;
    }
    if (key == "element") {
      PlyElement e;
      e.name = std::string(in.token());
      if (e.name.empty()) in.fail("element without a name");
      e.count = in.integer("element count");
      if (e.count < 0) in.fail("negative element count " + std::to_string(e.count));
      e.line = in.line_number();
      h.elements.push_back(std::move(e));
      continue;
    }
    if (key == "property") {
      if (h.elements.empty()) in.fail("property before any element");
      PlyProperty p;
      std::string_view t = in.token();
      if (t == "list") {
        p.is_list = true;
        std::string_view ct = in.token();
        if (!parse_type(ct, p.count_type))
          in.fail("unknown list count type \"" + std::string(ct.substr(0, 40)) + "\"");
        if (!is_integer(p.count_type)) in.fail("list count type must be an integer type");
        t = in.token();
      }
      if (!parse_type(t, p.type))
        in.fail("unknown property type \"" + std::string(t.substr(0, 40)) + "\"");
      p.name = std::string(in.token());
      if (p.name.empty()) in.fail("property without a name");
      h.elements.back().props.push_back(std::move(p));
      continue;
    }
    in.fail("unknown PLY header keyword \"" + std::string(key.substr(0, 40)) + "\"");
  }
  if (!have_format) in.fail("PLY header has no \"format\" line");
  h.data_offset = in.next_line_offset();
  h.data_line = in.line_number() + 1;
  return h;
}

// Where the vertex and face data go while reading.
struct Targets {
  int vertex_element = -1, face_element = -1;
  int x = -1, y = -1, z = -1;  // property positions in the vertex element
  int indices = -1, tag = -1;  // property positions in the face element
  long long num_vertices = 0;
};

Targets find_targets(const PlyHeader& h, const std::string& file) {
  Targets t;
  for (std::size_t e = 0; e < h.elements.size(); ++e) {
    const PlyElement& el = h.elements[e];
    if (el.name == "vertex" && t.vertex_element < 0) t.vertex_element = static_cast<int>(e);
    if (el.name == "face" && t.face_element < 0) t.face_element = static_cast<int>(e);
  }
  if (t.vertex_element < 0)
    throw InputError("PLY header has no \"vertex\" element", {.file = file});
  if (t.face_element < 0) throw InputError("PLY header has no \"face\" element", {.file = file});
  const PlyElement& ve = h.elements[static_cast<std::size_t>(t.vertex_element)];
  for (std::size_t p = 0; p < ve.props.size(); ++p) {
    const auto& prop = ve.props[p];
    int* slot = prop.name == "x"   ? &t.x
                : prop.name == "y" ? &t.y
                : prop.name == "z" ? &t.z
                                   : nullptr;
    if (slot && *slot < 0) {
      if (prop.is_list)
        throw InputError("vertex property \"" + prop.name + "\" must not be a list",
                         {.file = file, .line = ve.line});
      *slot = static_cast<int>(p);
    }
  }
  if (t.x < 0 || t.y < 0 || t.z < 0)
    throw InputError("vertex element lacks one of the properties x, y, z",
                     {.file = file, .line = ve.line});
  t.num_vertices = ve.count;
  const PlyElement& fe = h.elements[static_cast<std::size_t>(t.face_element)];
  static constexpr std::array<std::string_view, 7> k_tag_names = {
      "tag", "tags", "label", "region", "group", "physical", "material_index"};
  int first_int = -1, named = -1;
  for (std::size_t p = 0; p < fe.props.size(); ++p) {
    const auto& prop = fe.props[p];
    if ((prop.name == "vertex_indices" || prop.name == "vertex_index") && t.indices < 0) {
      if (!prop.is_list)
        throw InputError("face property \"" + prop.name + "\" must be a list",
                         {.file = file, .line = fe.line});
      if (!is_integer(prop.type))
        throw InputError("face indices must have an integer type", {.file = file, .line = fe.line});
      t.indices = static_cast<int>(p);
      continue;
    }
    if (prop.is_list || !is_integer(prop.type)) continue;
    if (first_int < 0) first_int = static_cast<int>(p);
    if (named < 0 &&
        std::find(k_tag_names.begin(), k_tag_names.end(), prop.name) != k_tag_names.end())
      named = static_cast<int>(p);
  }
  if (t.indices < 0)
    throw InputError("face element has no list property \"vertex_indices\" or \"vertex_index\"",
                     {.file = file, .line = fe.line});
  t.tag = named >= 0 ? named : first_int;
  return t;
}

// Minimum bytes one instance of `el` takes in the data section.
std::size_t min_element_bytes(const PlyElement& el, bool binary) {
  std::size_t n = 0;
  for (const auto& p : el.props) n += binary ? type_size(p.is_list ? p.count_type : p.type) : 2;
  return std::max<std::size_t>(n, binary ? 0 : 1);
}

// Reads values of either representation behind one interface.
class ValueSource {
 public:
  virtual ~ValueSource() = default;
  virtual void begin_element(long long index, std::string_view element) = 0;
  virtual void end_element() = 0;
  virtual double real(PlyType type, std::string_view what) = 0;
  virtual long long integer(PlyType type, std::string_view what) = 0;
  /// Consumes a value that is not stored (any content, even NaN).
  virtual void skip(PlyType type, std::string_view what) = 0;
  [[noreturn]] virtual void fail(const std::string& defect) const = 0;
};

class AsciiSource final : public ValueSource {
 public:
  AsciiSource(std::string_view data, const std::string& file, std::size_t offset, long long line)
      : m_in(data, file, offset, line) {}
  void begin_element(long long index, std::string_view element) override {
    if (!m_in.next_content_line('\0'))
      m_in.fail("truncated: expected " + std::string(element) + " " + std::to_string(index));
  }
  void end_element() override { m_in.expect_line_end("the element's properties"); }
  double real(PlyType type, std::string_view what) override {
    if (is_integer(type)) return static_cast<double>(integer(type, what));
    return m_in.real(what);
  }
  long long integer(PlyType type, std::string_view what) override {
    if (!is_integer(type)) {
      double v = m_in.real(what);
      if (v != std::floor(v) || std::abs(v) > 9e15)
        m_in.fail(std::string(what) + " is not an integer");
      return static_cast<long long>(v);
    }
    return m_in.integer(what);
  }
  void skip(PlyType, std::string_view what) override {
    if (m_in.token().empty()) m_in.fail("missing " + std::string(what) + " (line ends early)");
  }
  void fail(const std::string& defect) const override { m_in.fail(defect); }
  bool trailing_content() { return m_in.next_content_line('\0'); }

 private:
  detail::TextScanner m_in;
};

class BinarySource final : public ValueSource {
 public:
  BinarySource(std::string_view data, const std::string& file, std::size_t offset, bool swap)
      : m_in(data, file, offset, swap) {}
  void begin_element(long long, std::string_view) override {}
  void end_element() override {}
  double real(PlyType type, std::string_view what) override {
    m_last = m_in.offset();
    switch (type) {
      case PlyType::f32:
        return m_in.read<float>(what);
      case PlyType::f64:
        return m_in.read<double>(what);
      default:
        return static_cast<double>(integer(type, what));
    }
  }
  long long integer(PlyType type, std::string_view what) override {
    m_last = m_in.offset();
    switch (type) {
      case PlyType::i8:
        return m_in.read<std::int8_t>(what);
      case PlyType::u8:
        return m_in.read<std::uint8_t>(what);
      case PlyType::i16:
        return m_in.read<std::int16_t>(what);
      case PlyType::u16:
        return m_in.read<std::uint16_t>(what);
      case PlyType::i32:
        return m_in.read<std::int32_t>(what);
      case PlyType::u32:
        return m_in.read<std::uint32_t>(what);
      case PlyType::f32:
      case PlyType::f64: {
        double v = type == PlyType::f32 ? m_in.read<float>(what) : m_in.read<double>(what);
        if (!(v == std::floor(v)) || std::abs(v) > 9e15)
          m_in.fail_at(m_last, std::string(what) + " is not an integer");
        return static_cast<long long>(v);
      }
    }
    return 0;
  }
  void skip(PlyType type, std::string_view what) override {
    m_last = m_in.offset();
    m_in.skip(type_size(type), what);
  }
  // Binary defects point at the value just read.
  void fail(const std::string& defect) const override { m_in.fail_at(m_last, defect); }
  std::size_t remaining() const { return m_in.remaining(); }
  std::size_t offset() const { return m_in.offset(); }

 private:
  detail::BinaryReader m_in;
  std::size_t m_last = 0;  // offset of the last value read
};

}  // namespace

SurfaceMesh read_ply(const std::filesystem::path& path) {
  const std::string file = path.string();
  const std::string data = detail::read_file_bytes(path);
  if (data.empty()) throw InputError("empty file", {.file = file});
  const PlyHeader h = parse_header(data, file);
  const Targets t = find_targets(h, file);
  const bool binary = h.format != PlyFormat::ascii;

  // No element count may exceed what the data section can hold.
  std::size_t left = data.size() - h.data_offset;
  for (const auto& el : h.elements) {
    const std::size_t each = min_element_bytes(el, binary);
    detail::check_count(el.count, each, left, el.name + " elements", file, el.line);
    left -= static_cast<std::size_t>(el.count) * each;
  }

  std::unique_ptr<ValueSource> src;
  AsciiSource* ascii = nullptr;
  BinarySource* bin = nullptr;
  if (binary) {
    const bool swap =
        (h.format == PlyFormat::binary_be) != (std::endian::native == std::endian::big);
    auto b = std::make_unique<BinarySource>(data, file, h.data_offset, swap);
    bin = b.get();
    src = std::move(b);
  } else {
    auto a = std::make_unique<AsciiSource>(data, file, h.data_offset, h.data_line);
    ascii = a.get();
    src = std::move(a);
  }

  std::vector<double> xyz(static_cast<std::size_t>(t.num_vertices) * 3);
  const long long nf = h.elements[static_cast<std::size_t>(t.face_element)].count;
  std::vector<int> tri(static_cast<std::size_t>(nf) * 3);
  std::vector<int> tags(t.tag >= 0 ? static_cast<std::size_t>(nf) : 0);

  for (std::size_t e = 0; e < h.elements.size(); ++e) {
    const PlyElement& el = h.elements[e];
    const bool is_vertex = static_cast<int>(e) == t.vertex_element;
    const bool is_face = static_cast<int>(e) == t.face_element;
    if (el.props.empty()) continue;  // nothing stored, nothing to read (and no count bound)
    for (long long i = 0; i < el.count; ++i) {
      src->begin_element(i, el.name);
      for (std::size_t p = 0; p < el.props.size(); ++p) {
        const PlyProperty& prop = el.props[p];
        const int pi = static_cast<int>(p);
        if (prop.is_list) {
          const long long n = src->integer(prop.count_type, "list count");
          if (is_face && pi == t.indices) {
            if (n > 3)
              src->fail("face " + std::to_string(i) + " has " + std::to_string(n) +
                        " vertices; curvefem needs triangles (split polygons before meshing)");
            if (n < 3)
              src->fail("face " + std::to_string(i) + " has " + std::to_string(n) +
                        " vertices; a face needs 3");
            for (int c = 0; c < 3; ++c) {
              const long long v = src->integer(prop.type, "face vertex index");
              if (v < 0)
                src->fail("negative vertex index " + std::to_string(v) + " in face " +
                          std::to_string(i));
              if (v >= t.num_vertices)
                src->fail("vertex index " + std::to_string(v) + " out of range in face " +
                          std::to_string(i) + " (the file has " + std::to_string(t.num_vertices) +
                          " vertices)");
              tri[static_cast<std::size_t>(3 * i + c)] = static_cast<int>(v);
            }
          } else {
            if (n < 0) src->fail("negative list count " + std::to_string(n));
            // Skipped list: its items must exist (bounded by the file, never allocated).
            if (bin && static_cast<unsigned long long>(n) * type_size(prop.type) > bin->remaining())
              src->fail("truncated: list of " + std::to_string(n) + " items runs past the end");
            for (long long k = 0; k < n; ++k) src->skip(prop.type, "list item");
          }
          continue;
        }
        if (is_vertex && (pi == t.x || pi == t.y || pi == t.z)) {
          const char* what = pi == t.x ? "vertex x" : pi == t.y ? "vertex y" : "vertex z";
          const double v = src->real(prop.type, what);
          if (!std::isfinite(v))
            src->fail(std::string(what) + " of vertex " + std::to_string(i) + " is NaN/inf");
          xyz[static_cast<std::size_t>(3 * i + (pi == t.x ? 0 : pi == t.y ? 1 : 2))] = v;
        } else if (is_face && pi == t.tag) {
          const long long v = src->integer(prop.type, "face tag");
          if (v < -2147483647LL || v > 2147483647LL) src->fail("face tag out of the int range");
          tags[static_cast<std::size_t>(i)] = static_cast<int>(v);
        } else {
          src->skip(prop.type, prop.name);
        }
      }
      src->end_element();
    }
  }
  if (ascii && ascii->trailing_content())
    ascii->fail("unexpected content after the elements announced in the header (count mismatch?)");
  // Binary data may be followed by a stray end of line, nothing else.
  if (bin && !detail::trim(std::string_view(data).substr(bin->offset())).empty())
    throw InputError(std::to_string(bin->remaining()) +
                         " unexpected bytes after the elements announced in the header (count "
                         "mismatch?)",
                     {.file = file, .byte_offset = static_cast<long long>(bin->offset())});

  SurfaceMesh mesh = detail::make_surface(xyz, tri, tags, file);
  if (mesh.has_tags()) mesh.tag_names = h.tag_names;
  return mesh;
}

}  // namespace curvefem::io
