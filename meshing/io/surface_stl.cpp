// STL reader, ascii and binary; bit-identical vertices are welded.
//
// Binary vs ascii is decided by content: a file whose size is exactly 84 + 50·n (n = the count at
// byte 80) is binary even if its 80-byte header starts with "solid" (many exporters do that);
// otherwise a file starting with "solid" is ascii.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <unordered_map>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/io/text_scanner.hpp"

namespace curvefem::io {

namespace {

struct BitKey {
  std::uint64_t x, y, z;
  bool operator==(const BitKey&) const = default;
};

struct BitKeyHash {
  std::size_t operator()(const BitKey& k) const {
    std::uint64_t h = k.x * 0x9E3779B97F4A7C15ULL;
    h ^= (k.y + 0x7F4A7C159E3779B9ULL + (h << 6) + (h >> 2));
    h ^= (k.z + 0x94D049BB133111EBULL + (h << 6) + (h >> 2));
    return static_cast<std::size_t>(h ^ (h >> 31));
  }
};

// Welds vertices by their exact bit pattern, numbering them in order of first appearance.
class Welder {
 public:
  explicit Welder(std::size_t expected_corners) {
    m_index.reserve(expected_corners / 4 + 16);
    m_xyz.reserve(expected_corners / 2 * 3 + 16);
  }
  int add(double x, double y, double z) {
    BitKey key{bits(x), bits(y), bits(z)};
    auto [it, inserted] = m_index.try_emplace(key, static_cast<int>(m_xyz.size() / 3));
    if (inserted) m_xyz.insert(m_xyz.end(), {x, y, z});
    return it->second;
  }
  const std::vector<double>& xyz() const { return m_xyz; }

 private:
  static std::uint64_t bits(double v) {
    std::uint64_t b;
    std::memcpy(&b, &v, sizeof b);
    return b;
  }
  std::unordered_map<BitKey, int, BitKeyHash> m_index;
  std::vector<double> m_xyz;
};

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    char x = a[i], y = b[i];
    if (x >= 'A' && x <= 'Z') x = static_cast<char>(x - 'A' + 'a');
    if (y >= 'A' && y <= 'Z') y = static_cast<char>(y - 'A' + 'a');
    if (x != y) return false;
  }
  return true;
}

// Tokens across lines, with the line number of the last token for messages.
class StlTokens {
 public:
  StlTokens(std::string_view text, const std::string& file) : m_in(text, file) {}
  std::string_view next() {
    for (;;) {
      std::string_view t = m_in.token();
      if (!t.empty()) return t;
      if (!m_in.next_line()) return {};
    }
  }
  void skip_rest_of_line() {
    while (!m_in.at_line_end()) m_in.token();
  }
  void expect(std::string_view keyword, std::string_view context) {
    std::string_view t = next();
    if (t.empty())
      fail("truncated: expected \"" + std::string(keyword) + "\" " + std::string(context));
    if (!iequals(t, keyword))
      fail("expected \"" + std::string(keyword) + "\" " + std::string(context) + ", got \"" +
           std::string(t.substr(0, 40)) + "\"");
  }
  double number(std::string_view what, bool finite) {
    std::string_view t = next();
    if (t.empty()) fail("truncated: expected " + std::string(what));
    double v;
    if (!detail::parse_double(t, v))
      fail("expected a number for " + std::string(what) + ", got \"" +
           std::string(t.substr(0, 40)) + "\"");
    if (finite && !std::isfinite(v)) fail(std::string(what) + " is NaN/inf");
    return v;
  }
  [[noreturn]] void fail(const std::string& msg) const { m_in.fail(msg); }

 private:
  detail::TextScanner m_in;
};

SurfaceMesh read_stl_ascii(std::string_view text, const std::string& file,
                           const std::string& binary_hint) {
  try {
    StlTokens in(text, file);
    Welder welder(text.size() / 80);
    std::vector<int> tri;
    in.expect("solid", "at the start of an ascii STL");
    in.skip_rest_of_line();  // the solid's name
    for (;;) {
      std::string_view t = in.next();
      if (t.empty()) in.fail("truncated: missing \"endsolid\"");
      if (iequals(t, "endsolid")) {
        in.skip_rest_of_line();
        std::string_view after = in.next();
        if (after.empty()) break;
        if (!iequals(after, "solid"))
          in.fail("unexpected \"" + std::string(after.substr(0, 40)) + "\" after \"endsolid\"");
        in.skip_rest_of_line();
        continue;
      }
      if (!iequals(t, "facet"))
        in.fail("expected \"facet\" or \"endsolid\", got \"" + std::string(t.substr(0, 40)) + "\"");
      in.expect("normal", "after \"facet\"");
      for (const char* what : {"normal x", "normal y", "normal z"}) in.number(what, false);
      in.expect("outer", "after the facet normal");
      in.expect("loop", "after \"outer\"");
      int face[3];
      for (int c = 0; c < 3; ++c) {
        std::string_view k = in.next();
        if (k.empty()) in.fail("truncated: expected \"vertex\"");
        if (iequals(k, "endloop"))
          in.fail("facet has " + std::to_string(c) + " vertices; a face needs 3");
        if (!iequals(k, "vertex"))
          in.fail("expected \"vertex\", got \"" + std::string(k.substr(0, 40)) + "\"");
        double x = in.number("vertex x", true);
        double y = in.number("vertex y", true);
        double z = in.number("vertex z", true);
        face[c] = welder.add(x, y, z);
      }
      std::string_view k = in.next();
      if (iequals(k, "vertex"))
        in.fail(
            "facet has more than 3 vertices; curvefem needs triangles (split polygons before "
            "meshing)");
      if (k.empty()) in.fail("truncated: expected \"endloop\"");
      if (!iequals(k, "endloop"))
        in.fail("expected \"endloop\", got \"" + std::string(k.substr(0, 40)) + "\"");
      in.expect("endfacet", "after \"endloop\"");
      tri.insert(tri.end(), face, face + 3);
      if (tri.size() / 3 >= 2147483647u) in.fail("too many facets");
    }
    return detail::make_surface(welder.xyz(), tri, {}, file);
  } catch (const InputError& e) {
    if (binary_hint.empty()) throw;
    throw InputError(e.defect() + binary_hint, e.context());
  }
}

SurfaceMesh read_stl_binary(std::string_view data, const std::string& file) {
  detail::BinaryReader in(data, file);
  in.skip(80, "the 80-byte binary STL header");
  const std::uint32_t n = in.read<std::uint32_t>("the triangle count");
  const unsigned long long expected = 84ULL + 50ULL * n;
  if (expected != data.size())
    in.fail_at(80, "binary STL header announces " + std::to_string(n) + " triangles (84 + 50*" +
                       std::to_string(n) + " = " + std::to_string(expected) +
                       " bytes) but the file has " + std::to_string(data.size()) +
                       " bytes (truncated or not an STL)");
  if (n > 2147483647u) in.fail_at(80, "too many triangles");
  Welder welder(static_cast<std::size_t>(n) * 3);
  std::vector<int> tri(static_cast<std::size_t>(n) * 3);
  for (std::uint32_t f = 0; f < n; ++f) {
    in.skip(12, "facet normal");
    for (int c = 0; c < 3; ++c) {
      double p[3];
      for (double& x : p) {
        const std::size_t at = in.offset();
        x = in.read<float>("vertex coordinate");
        if (!std::isfinite(x))
          throw InputError("vertex coordinate is NaN/inf",
                           {.file = file,
                            .byte_offset = static_cast<long long>(at),
                            .face = static_cast<long long>(f)});
      }
      tri[3 * static_cast<std::size_t>(f) + c] = welder.add(p[0], p[1], p[2]);
    }
    in.skip(2, "facet attribute");
  }
  return detail::make_surface(welder.xyz(), tri, {}, file);
}

}  // namespace

SurfaceMesh read_stl(const std::filesystem::path& path) {
  const std::string file = path.string();
  const std::string data = detail::read_file_bytes(path);
  if (data.empty()) throw InputError("empty file", {.file = file});
  std::string_view head = detail::trim(std::string_view(data).substr(0, 512));
  const bool starts_solid = head.size() >= 5 && iequals(head.substr(0, 5), "solid");
  if (data.size() >= 84) {
    std::uint32_t n;
    std::memcpy(&n, data.data() + 80, sizeof n);
    if (84ULL + 50ULL * n == data.size()) return read_stl_binary(data, file);
  }
  if (starts_solid) {
    // A binary file whose header starts with "solid" but whose size is wrong would give a
    // confusing ascii error: say what the binary interpretation found too.
    std::string hint;
    if (data.size() >= 84 && std::memchr(data.data(), '\0', data.size()) != nullptr) {
      std::uint32_t n;
      std::memcpy(&n, data.data() + 80, sizeof n);
      hint = " (the file contains NUL bytes: if it is a binary STL, its header announces " +
             std::to_string(n) + " triangles = " + std::to_string(84ULL + 50ULL * n) +
             " bytes, but the file has " + std::to_string(data.size()) + ")";
    }
    return read_stl_ascii(data, file, hint);
  }
  if (data.size() < 84)
    throw InputError("not an STL: too short for a binary STL (" + std::to_string(data.size()) +
                         " bytes < 84) and no ascii \"solid\" header",
                     {.file = file, .byte_offset = 0});
  return read_stl_binary(data, file);  // reports the size mismatch
}

}  // namespace curvefem::io
