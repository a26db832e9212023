#include "meshing/io/vtu_binary_check.hpp"

#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <optional>
#include <string_view>
#include <vector>

#include "meshing/core/error.hpp"

namespace curvefem::io::detail {
namespace {

using u64 = std::uint64_t;
using u128 = unsigned __int128;
constexpr auto npos = std::string_view::npos;

// No VTK writer uses blocks anywhere near this (the default is 32 KiB).
constexpr u64 k_max_block_size = u64{1} << 30;
// Largest plausible uncompressed / compressed size of one block (zlib ≤ 1032:1, LZ4 ≤ 255:1,
// LZMA on 32 KiB blocks far below): bounds what a corrupted header can make VTK allocate.
constexpr u64 k_max_ratio = 2048;
constexpr u64 k_block_slack = 65536;
// Element counts beyond this are corrupt whatever the file size (and would overflow VTK's sizes).
constexpr u64 k_max_count = u64{1} << 50;

// As isspace() in the C locale, which VTK's XML parser uses.
bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

/// Value of attribute `name` in the start tag `tag` (nullopt if absent).
std::optional<std::string> attribute(std::string_view tag, std::string_view name) {
  for (std::size_t pos = tag.find(name); pos != npos; pos = tag.find(name, pos + 1)) {
    if (pos == 0 || !is_space(tag[pos - 1])) continue;
    std::size_t p = pos + name.size();
    while (p < tag.size() && is_space(tag[p])) ++p;
    if (p >= tag.size() || tag[p] != '=') continue;
    ++p;
    while (p < tag.size() && is_space(tag[p])) ++p;
    if (p >= tag.size() || (tag[p] != '"' && tag[p] != '\'')) continue;
    const std::size_t end = tag.find(tag[p], p + 1);
    if (end == npos) return std::nullopt;
    return std::string(tag.substr(p + 1, end - p - 1));
  }
  return std::nullopt;
}

/// Leading decimal digits of `text` (after blanks); nullopt if none or beyond k_max_count.
std::optional<u64> parse_count(std::string_view text) {
  std::size_t p = 0;
  while (p < text.size() && is_space(text[p])) ++p;
  if (p < text.size() && text[p] == '+') ++p;
  u64 value = 0;
  bool any = false;
  for (; p < text.size() && text[p] >= '0' && text[p] <= '9'; ++p) {
    value = value * 10 + static_cast<u64>(text[p] - '0');
    any = true;
    if (value > k_max_count) return std::nullopt;
  }
  if (!any) return std::nullopt;
  return value;
}

int base64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

/// Decoded length of the base64 chunk at the start of `text` ('=' padding or any other character
/// ends it).
u64 base64_length(std::string_view text) {
  std::size_t chars = 0;
  while (chars < text.size() && base64_value(text[chars]) >= 0) ++chars;
  return static_cast<u64>(chars) * 3 / 4;
}

/// Bytes [begin, begin + count) of the base64 chunk at the start of `text`.
std::optional<std::string> base64_range(std::string_view text, u64 begin, u64 count) {
  if (count > base64_length(text) || begin > base64_length(text) - count) return std::nullopt;
  std::string out;
  out.reserve(count);
  u64 skip = begin % 3;
  for (u64 c = begin / 3 * 4; out.size() < count; c += 4) {
    if (c + 4 > text.size()) return std::nullopt;
    std::uint32_t w = 0;
    for (int i = 0; i < 4; ++i) {
      const int v = text[c + i] == '=' ? 0 : base64_value(text[c + i]);
      if (v < 0) return std::nullopt;
      w = (w << 6) | static_cast<std::uint32_t>(v);
    }
    const char bytes[3] = {static_cast<char>(w >> 16), static_cast<char>(w >> 8),
                           static_cast<char>(w)};
    for (u64 k = skip; k < 3 && out.size() < count; ++k) out += bytes[k];
    skip = 0;
  }
  return out;
}

/// A byte stream: raw bytes, or one base64 chunk.
struct Stream {
  std::string_view text;
  bool base64 = false;

  u64 size() const { return base64 ? base64_length(text) : text.size(); }
  std::optional<std::string> bytes(u64 begin, u64 count) const {
    if (base64) return base64_range(text, begin, count);
    if (begin > text.size() || count > text.size() - begin) return std::nullopt;
    return std::string(text.substr(begin, count));
  }
};

/// What a data array can deliver: `size` uncompressed bytes, read through `read`.
struct Payload {
  u64 size = 0;
  std::function<std::optional<std::string>(u64 begin, u64 count)> read;
};

enum class Compressor { none, zlib, other };
enum class Section { other, points, cells, point_data, cell_data, field_data };
enum class Storage { appended, binary, ascii };

struct Array {
  std::string_view tag;          ///< the start tag
  std::size_t position;          ///< of the tag in the file
  std::string_view inline_text;  ///< content up to the next '<' (inline formats)
  Section section;
  int piece;  ///< index into pieces, -1 outside a Piece
};

struct Piece {
  std::optional<u64> points, cells;
};

int word_size(const std::string& type) {
  if (type == "Int8" || type == "UInt8") return 1;
  if (type == "Int16" || type == "UInt16") return 2;
  if (type == "Int32" || type == "UInt32" || type == "Float32") return 4;
  if (type == "Int64" || type == "UInt64" || type == "Float64") return 8;
  return 0;  // String, Bit, unknown: not checked
}

class Checker {
 public:
  Checker(const std::string& bytes, const std::string& file) : m_all(bytes), m_file(file) {}

  void run() {
    const std::size_t root = m_all.find("<VTKFile");
    if (root == npos) return;
    const std::size_t root_end = m_all.find('>', root);
    if (root_end == npos) return;
    const std::string_view tag = m_all.substr(root, root_end - root);
    const auto compressor = attribute(tag, "compressor");
    // Like vtkXMLReader::SetupCompressor: an unknown name is an error VTK reports but reads on,
    // without a compressor.
    m_compressor = !compressor                              ? Compressor::none
                   : *compressor == "vtkZLibDataCompressor" ? Compressor::zlib
                   : *compressor == "vtkLZ4DataCompressor" || *compressor == "vtkLZMADataCompressor"
                       ? Compressor::other
                       : Compressor::none;
    const auto header_type = attribute(tag, "header_type");
    if (header_type && *header_type == "UInt64")
      m_header_size = 8;
    else if (header_type && *header_type != "UInt32")
      return;  // VTK rejects it
    m_big_endian = attribute(tag, "byte_order").value_or("") == "BigEndian";

    const std::size_t appended_tag = m_all.find("<AppendedData", root_end);
    if (appended_tag != npos) {
      const std::size_t tag_end = m_all.find('>', appended_tag);
      // Like vtkXMLDataParser::FindAppendedDataPosition: after the '>', skip blanks; the data
      // start after the '_' marker, or at the first non-blank character if it is not a '_'.
      std::size_t p = tag_end == npos ? m_all.size() : tag_end + 1;
      while (p < m_all.size() && is_space(m_all[p])) ++p;
      if (p < m_all.size()) {
        m_appended_start = m_all[p] == '_' ? p + 1 : p;
        m_appended_base64 =
            attribute(m_all.substr(appended_tag, tag_end - appended_tag), "encoding")
                .value_or("base64") != "raw";
      }
    }
    scan(m_all.substr(0, appended_tag));
    for (int p = -1; p < static_cast<int>(m_pieces.size()); ++p) check_piece(p);
  }

 private:
  [[noreturn]] void fail(std::size_t position, const std::string& what) const {
    throw InputError("truncated or corrupted VTU file: " + what,
                     {.file = m_file, .byte_offset = static_cast<long long>(position)});
  }

  u64 word(const std::string& bytes, u64 index, int size) const {
    u64 w = 0;
    for (int b = 0; b < size; ++b) {
      const auto byte = static_cast<unsigned char>(bytes[index * size + b]);
      w |= static_cast<u64>(byte) << (m_big_endian ? 8 * (size - 1 - b) : 8 * b);
    }
    return w;
  }

  void scan(std::string_view xml) {
    Section section = Section::other;
    for (std::size_t lt = xml.find('<'); lt != npos; lt = xml.find('<', lt + 1)) {
      const std::size_t gt = xml.find('>', lt);
      if (gt == npos) return;
      const std::string_view tag = xml.substr(lt, gt - lt);
      const bool closing = tag.size() > 1 && tag[1] == '/';
      std::size_t name_end = closing ? 2 : 1;
      while (name_end < tag.size() && !is_space(tag[name_end]) && tag[name_end] != '/') ++name_end;
      const std::string_view name = tag.substr(closing ? 2 : 1, name_end - (closing ? 2 : 1));
      const Section named = name == "Points"      ? Section::points
                            : name == "Cells"     ? Section::cells
                            : name == "PointData" ? Section::point_data
                            : name == "CellData"  ? Section::cell_data
                            : name == "FieldData" ? Section::field_data
                                                  : Section::other;
      if (closing) {
        if (named != Section::other) section = Section::other;
        if (name == "Piece") m_in_piece = false;
        continue;
      }
      const bool self_closing = tag.back() == '/';
      if (name == "Piece") {
        Piece piece;
        if (const auto v = attribute(tag, "NumberOfPoints")) piece.points = count_or_fail(*v, lt);
        if (const auto v = attribute(tag, "NumberOfCells")) piece.cells = count_or_fail(*v, lt);
        m_pieces.push_back(piece);
        m_in_piece = !self_closing;
      } else if (named != Section::other) {
        if (!self_closing) section = named;
      } else if (name == "DataArray") {
        std::string_view text;
        if (!self_closing) {
          const std::size_t end = xml.find('<', gt + 1);
          text = xml.substr(gt + 1, end == npos ? npos : end - gt - 1);
        }
        m_arrays.push_back(
            {tag, lt, text, section, m_in_piece ? static_cast<int>(m_pieces.size()) - 1 : -1});
      }
    }
  }

  u64 count_or_fail(const std::string& text, std::size_t position) const {
    const auto v = parse_count(text);
    if (!v) fail(position, "count '" + text.substr(0, 40) + "' is not a plausible number");
    return *v;
  }

  /// As vtkXMLReader decides: appended iff the element has an "offset" attribute (whatever its
  /// format says), else inline binary iff format="binary", else ascii.
  static Storage storage(const Array& a) {
    if (attribute(a.tag, "offset")) return Storage::appended;
    return attribute(a.tag, "format").value_or("") == "binary" ? Storage::binary : Storage::ascii;
  }

  /// Validates the binary header of `a` and describes its payload; nullopt for ascii arrays.
  std::optional<Payload> payload(const Array& a) const {
    const Storage kind = storage(a);
    Stream s;
    std::size_t at = a.position;  // for messages
    if (kind == Storage::appended) {
      if (!m_appended_start) return std::nullopt;  // VTK reports the missing section
      // VTK parses the offset with operator>>: blanks, a sign, digits; no digits reads as 0.
      const std::string text = attribute(a.tag, "offset").value_or("");
      std::size_t p = 0;
      while (p < text.size() && is_space(text[p])) ++p;
      if (p < text.size() && text[p] == '-') fail(a.position, "negative appended data offset");
      const u64 offset = parse_count(text).value_or(0);
      if (offset > m_all.size() - *m_appended_start)
        fail(a.position, "appended data offset outside the file");
      at = *m_appended_start + offset;
      s = Stream{m_all.substr(at), m_appended_base64};
    } else if (kind == Storage::binary) {
      std::size_t skip = 0;
      while (skip < a.inline_text.size() && is_space(a.inline_text[skip])) ++skip;
      s = Stream{a.inline_text.substr(skip), true};
    } else {
      return std::nullopt;
    }
    const u64 h = m_header_size;
    if (m_compressor == Compressor::none) {
      // [#bytes][data], one stream.
      const auto head = s.bytes(0, h);
      if (!head) fail(at, "truncated data array header");
      const u64 size = word(*head, 0, m_header_size);
      if (size > s.size() - h) fail(at, "data array extends past the end of the file");
      return Payload{size, [s, h](u64 begin, u64 count) { return s.bytes(h + begin, count); }};
    }
    // [#blocks][block size][last block size][compressed sizes...], then the blocks; base64: the
    // header and the blocks are separate chunks.
    const auto head = s.bytes(0, 3 * h);
    if (!head) fail(at, "truncated compression header");
    const u64 blocks = word(*head, 0, m_header_size);
    const u64 block_size = word(*head, 1, m_header_size);
    const u64 last_size = word(*head, 2, m_header_size);
    if (blocks == 0) {
      // VTK computes blocks × size − size + last for a partial last block: with no blocks that
      // wraps around and it reads block 0.
      if (last_size != 0) fail(at, "compression header with no blocks but a partial last block");
      return Payload{0, {}};
    }
    if (block_size == 0 || block_size > k_max_block_size)
      fail(at, "compression block size " + std::to_string(block_size));
    if (last_size > block_size) fail(at, "last compression block larger than a block");
    if (blocks > s.size() / h) fail(at, "more compression blocks than the file can hold");
    const auto sizes = s.bytes(0, (3 + blocks) * h);
    if (!sizes) fail(at, "truncated compression header");
    Stream data = s;
    if (s.base64) {
      const u64 header_chars = ((3 + blocks) * h + 2) / 3 * 4;
      data.text = header_chars <= s.text.size() ? s.text.substr(header_chars) : std::string_view();
    } else {
      data.text = s.text.substr((3 + blocks) * h);
    }
    std::vector<u64> start(blocks + 1, 0), compressed(blocks);
    u64 remaining = data.size();
    for (u64 b = 0; b < blocks; ++b) {
      compressed[b] = word(*sizes, 3 + b, m_header_size);
      if (compressed[b] > remaining) fail(at, "compressed block extends past the end of the file");
      remaining -= compressed[b];
      start[b + 1] = start[b] + compressed[b];
      const u64 uncompressed = b + 1 == blocks && last_size != 0 ? last_size : block_size;
      if (uncompressed > k_max_ratio * compressed[b] + k_block_slack)
        fail(at, "implausible compression ratio in block " + std::to_string(b));
    }
    const u64 total = (blocks - 1) * block_size + (last_size != 0 ? last_size : block_size);
    if (m_compressor != Compressor::zlib) return Payload{total, {}};
    auto read = [data, start, compressed, blocks, block_size, last_size](
                    u64 begin, u64 count) -> std::optional<std::string> {
      std::string out;
      for (u64 b = begin / block_size; out.size() < count && b < blocks; ++b) {
        const auto packed = data.bytes(start[b], compressed[b]);
        if (!packed) return std::nullopt;
        std::string block(b + 1 == blocks && last_size != 0 ? last_size : block_size, '\0');
        uLongf length = block.size();
        if (uncompress(reinterpret_cast<Bytef*>(block.data()), &length,
                       reinterpret_cast<const Bytef*>(packed->data()), packed->size()) != Z_OK ||
            length != block.size())
          return std::nullopt;
        const u64 from = b == begin / block_size ? begin % block_size : 0;
        out += block.substr(from, count - out.size());
      }
      if (out.size() != count) return std::nullopt;
      return out;
    };
    return Payload{total, read};
  }

  /// Number of values an ascii array holds.
  static u64 ascii_values(std::string_view text) {
    u64 n = 0;
    bool in_token = false;
    for (char c : text) {
      if (is_space(c)) {
        in_token = false;
      } else if (!in_token) {
        in_token = true;
        ++n;
      }
    }
    return n;
  }

  /// Value `index` of an integer array (the last cell offset), nullopt if it cannot be decoded.
  std::optional<long long> integer_value(const Array& a, const std::optional<Payload>& p,
                                         u64 index) const {
    const std::string type = attribute(a.tag, "type").value_or("");
    const int size = word_size(type);
    if (size == 0 || type.rfind("Float", 0) == 0) return std::nullopt;
    if (!p) {  // ascii: the index-th token
      if (storage(a) != Storage::ascii) return std::nullopt;
      u64 n = 0;
      bool in_token = false;
      for (std::size_t i = 0; i < a.inline_text.size(); ++i) {
        if (is_space(a.inline_text[i])) {
          in_token = false;
        } else if (!in_token) {
          in_token = true;
          if (n++ == index) {
            std::string_view token = a.inline_text.substr(i);
            if (!token.empty() && token[0] == '-') return -1;
            if (!token.empty() && token[0] == '+') token.remove_prefix(1);
            u64 value = 0;
            std::size_t digits = 0;
            for (; digits < token.size() && token[digits] >= '0' && token[digits] <= '9'; ++digits)
              value = std::min<u64>(value * 10 + static_cast<u64>(token[digits] - '0'),
                                    k_max_count + 1);  // saturates: huge stays huge
            if (digits == 0) return std::nullopt;
            return static_cast<long long>(value);
          }
        }
      }
      return std::nullopt;
    }
    if (!p->read) return std::nullopt;
    const auto bytes = p->read(index * size, size);
    if (!bytes) return std::nullopt;
    u64 w = word(*bytes, 0, size);
    if (type[0] == 'I' && size < 8 && (w >> (8 * size - 1)) != 0) return -1;  // negative
    return static_cast<long long>(w);
  }

  void check_piece(int piece) {
    std::optional<u64> connectivity;  // required length, from the last offset
    for (const Array& a : m_arrays) {
      if (a.piece != piece) continue;
      const std::string name = attribute(a.tag, "Name").value_or("");
      if (a.section == Section::cells && name == "offsets") {
        const auto p = payload(a);
        const auto cells = piece >= 0 ? m_pieces[piece].cells : std::nullopt;
        check_length(a, p, cells);
        if (cells && *cells > 0) {
          const auto last = integer_value(a, p, *cells - 1);
          if (last && (*last < 0 || static_cast<u64>(*last) > k_max_count))
            fail(a.position,
                 "last cell offset " +
                     (*last < 0 ? std::to_string(*last) : "beyond " + std::to_string(k_max_count)));
          if (last) connectivity = static_cast<u64>(*last);
        } else if (cells) {
          connectivity = 0;
        }
      }
    }
    for (const Array& a : m_arrays) {
      if (a.piece != piece) continue;
      const std::string name = attribute(a.tag, "Name").value_or("");
      const auto counts = piece >= 0 ? m_pieces[piece] : Piece{};
      std::optional<u64> tuples;
      switch (a.section) {
        case Section::points:
        case Section::point_data:
          tuples = counts.points;
          break;
        case Section::cell_data:
          tuples = counts.cells;
          break;
        case Section::cells:
          if (name == "types") tuples = counts.cells;
          if (name == "connectivity") tuples = connectivity;
          if (name == "offsets") continue;  // checked above
          break;
        case Section::field_data:
          if (const auto v = attribute(a.tag, "NumberOfTuples"))
            tuples = count_or_fail(*v, a.position);
          break;
        case Section::other:
          break;
      }
      check_length(a, payload(a), tuples);
    }
  }

  /// The file must hold `tuples` × components values for `a`, or VTK allocates what it says and
  /// then writes past what it could allocate.
  void check_length(const Array& a, const std::optional<Payload>& p,
                    std::optional<u64> tuples) const {
    if (!tuples) return;
    u64 components = 1;
    if (const auto c = attribute(a.tag, "NumberOfComponents"))
      components = count_or_fail(*c, a.position);
    const u128 needed = static_cast<u128>(*tuples) * components;
    u64 held = 0;
    if (p) {
      const int size = word_size(attribute(a.tag, "type").value_or(""));
      if (size == 0) return;
      held = p->size / size;
    } else if (storage(a) == Storage::ascii) {
      held = ascii_values(a.inline_text);
    } else {
      return;  // appended without an AppendedData section: VTK reports it
    }
    if (needed > held)
      fail(a.position, "data array '" + attribute(a.tag, "Name").value_or("?") + "' needs " +
                           std::to_string(static_cast<unsigned long long>(
                               needed > k_max_count ? k_max_count : needed)) +
                           " values, the file holds " + std::to_string(held));
  }

  std::string_view m_all;
  std::string m_file;
  Compressor m_compressor = Compressor::none;
  int m_header_size = 4;
  bool m_big_endian = false;
  std::optional<std::size_t> m_appended_start;
  bool m_appended_base64 = true;
  bool m_in_piece = false;
  std::vector<Piece> m_pieces;
  std::vector<Array> m_arrays;
};

}  // namespace

void check_vtu_before_vtk(const std::string& bytes, const std::string& file) {
  Checker(bytes, file).run();
}

}  // namespace curvefem::io::detail
