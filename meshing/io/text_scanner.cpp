#include "meshing/io/text_scanner.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "meshing/core/error.hpp"

namespace curvefem::io::detail {

std::string read_file_bytes(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw IoError("is a directory, not a mesh file", {.file = path.string()});
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw IoError("cannot open file for reading", {.file = path.string()});
  std::string data;
  char buffer[1 << 16];
  for (;;) {
    std::size_t n = std::fread(buffer, 1, sizeof buffer, f.get());
    data.append(buffer, n);
    if (n < sizeof buffer) break;
  }
  if (std::ferror(f.get())) throw IoError("read error", {.file = path.string()});
  return data;
}

bool parse_double(std::string_view token, double& value) {
  if (token.empty()) return false;
  const char* first = token.data();
  const char* last = first + token.size();
  if (*first == '+') {
    ++first;
    if (first == last || *first == '-' || *first == '+') return false;
  }
  auto [ptr, ec] = std::from_chars(first, last, value);
  if (ec == std::errc::result_out_of_range && ptr == last && token.size() < 64) {
    // Underflow (e.g. 1e-400) reads as 0 or a subnormal; overflow stays an error.
    char buf[64];
    std::memcpy(buf, token.data(), token.size());
    buf[token.size()] = '\0';
    const double v = std::strtod(buf, nullptr);
    if (!std::isfinite(v)) return false;
    value = v;
    return true;
  }
  return ec == std::errc() && ptr == last;
}

bool parse_int(std::string_view token, long long& value) {
  if (token.empty()) return false;
  const char* first = token.data();
  const char* last = first + token.size();
  if (*first == '+') {
    ++first;
    if (first == last || *first == '-') return false;
  }
  auto [ptr, ec] = std::from_chars(first, last, value);
  return ec == std::errc() && ptr == last;
}

std::string to_lower(std::string_view s) {
  std::string out(s);
  for (char& c : out)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return out;
}

std::string_view trim(std::string_view s) {
  std::size_t b = 0, e = s.size();
  while (b < e && is_blank(s[b])) ++b;
  while (e > b && is_blank(s[e - 1])) --e;
  return s.substr(b, e - b);
}

namespace {
// Printable excerpt of a token for messages (bounded length, control bytes escaped).
std::string quote(std::string_view token) {
  std::string out = "\"";
  std::size_t n = 0;
  for (char c : token) {
    if (++n > 40) {
      out += "...";
      break;
    }
    auto u = static_cast<unsigned char>(c);
    if (u < 32 || u >= 127) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", u);
      out += hex;
    } else {
      out += c;
    }
  }
  return out + "\"";
}
}  // namespace

// ---------------------------------------------------------------------------------------------
// TextScanner

TextScanner::TextScanner(std::string_view text, std::string file, std::size_t offset,
                         long long first_line)
    : m_text(text),
      m_file(std::move(file)),
      m_next(offset < text.size() ? offset : text.size()),
      m_line_start(m_next),
      m_line_no(first_line - 1) {}

bool TextScanner::next_line() {
  if (m_next >= m_text.size()) {
    m_line = {};
    m_pos = 0;
    m_line_start = m_text.size();
    if (!m_past_end) {
      // A reader failing now points at the last line (line 1 of an empty text).
      if (m_line_no < 1) m_line_no = 1;
      m_past_end = true;
    }
    return false;
  }
  m_line_start = m_next;
  const char* begin = m_text.data() + m_next;
  std::size_t left = m_text.size() - m_next;
  const void* nl = std::memchr(begin, '\n', left);
  std::size_t len = nl ? static_cast<std::size_t>(static_cast<const char*>(nl) - begin) : left;
  m_next += nl ? len + 1 : len;
  if (len > 0 && begin[len - 1] == '\r') --len;
  m_line = std::string_view(begin, len);
  m_pos = 0;
  ++m_line_no;
  return true;
}

bool TextScanner::next_content_line(char comment) {
  while (next_line()) {
    if (at_line_end()) continue;
    if (m_line[m_pos] == comment) continue;
    return true;
  }
  return false;
}

void TextScanner::strip_comment(char comment) {
  const std::size_t at = m_line.find(comment, m_pos);
  if (at != std::string_view::npos) m_line = m_line.substr(0, at);
}

bool TextScanner::at_line_end() {
  while (m_pos < m_line.size() && is_blank(m_line[m_pos])) ++m_pos;
  return m_pos >= m_line.size();
}

std::string_view TextScanner::token() {
  if (at_line_end()) return {};
  std::size_t b = m_pos;
  while (m_pos < m_line.size() && !is_blank(m_line[m_pos])) ++m_pos;
  return m_line.substr(b, m_pos - b);
}

double TextScanner::real(std::string_view what) {
  std::string_view t = token();
  if (t.empty()) fail("missing " + std::string(what) + " (line ends early)");
  double v;
  if (!parse_double(t, v)) fail("expected a number for " + std::string(what) + ", got " + quote(t));
  if (!std::isfinite(v)) fail(std::string(what) + " is " + quote(t) + " (NaN/inf not allowed)");
  return v;
}

long long TextScanner::integer(std::string_view what) {
  std::string_view t = token();
  if (t.empty()) fail("missing " + std::string(what) + " (line ends early)");
  long long v;
  if (!parse_int(t, v)) fail("expected an integer for " + std::string(what) + ", got " + quote(t));
  return v;
}

long long TextScanner::integer_in(std::string_view what, long long lo, long long hi) {
  long long v = integer(what);
  if (v < lo || v > hi)
    fail(std::string(what) + " " + std::to_string(v) + " out of range [" + std::to_string(lo) +
         ", " + std::to_string(hi) + "]");
  return v;
}

void TextScanner::expect_line_end(std::string_view what) {
  if (!at_line_end()) fail("unexpected " + quote(rest()) + " after " + std::string(what));
}

void TextScanner::fail(const std::string& defect) const {
  if (m_report_offsets)
    throw InputError(defect, {.file = m_file, .byte_offset = static_cast<long long>(m_line_start)});
  throw InputError(defect, {.file = m_file, .line = m_line_no});
}

// ---------------------------------------------------------------------------------------------
// BinaryReader

BinaryReader::BinaryReader(std::string_view data, std::string file, std::size_t offset,
                           bool swap_bytes)
    : m_data(data),
      m_file(std::move(file)),
      m_pos(offset < data.size() ? offset : data.size()),
      m_swap(swap_bytes) {}

void BinaryReader::seek(std::size_t offset) {
  if (offset > m_data.size()) fail_at(m_data.size(), "truncated (seek past the end)");
  m_pos = offset;
}

void BinaryReader::need(std::size_t n, std::string_view what) const {
  if (n > remaining())
    fail("truncated: " + std::string(what) + " needs " + std::to_string(n) + " bytes, only " +
         std::to_string(remaining()) + " left");
}

void BinaryReader::fail(const std::string& defect) const { fail_at(m_pos, defect); }

void BinaryReader::fail_at(std::size_t offset, const std::string& defect) const {
  throw InputError(defect, {.file = m_file, .byte_offset = static_cast<long long>(offset)});
}

void check_count(long long count, std::size_t min_bytes_each, std::size_t bytes_left,
                 std::string_view what, const std::string& file, long long line,
                 long long byte_offset, long long max_count) {
  auto fail = [&](const std::string& msg) {
    if (line >= 0) throw InputError(msg, {.file = file, .line = line});
    throw InputError(msg, {.file = file, .byte_offset = byte_offset});
  };
  if (count < 0)
    fail("negative number of " + std::string(what) + " (" + std::to_string(count) + ")");
  if (count > max_count)
    fail("header announces " + std::to_string(count) + " " + std::string(what) +
         ", more than the supported maximum " + std::to_string(max_count));
  if (min_bytes_each > 0 && static_cast<unsigned long long>(count) >
                                static_cast<unsigned long long>(bytes_left) / min_bytes_each)
    fail("header announces " + std::to_string(count) + " " + std::string(what) + " but only " +
         std::to_string(bytes_left) + " bytes follow (at least " + std::to_string(min_bytes_each) +
         " bytes each; truncated file or absurd count)");
}

SurfaceMesh make_surface(const std::vector<double>& xyz, const std::vector<int>& tri,
                         const std::vector<int>& tags, const std::string& file) {
  if (tri.empty()) throw InputError("no triangles in the file (empty surface)", {.file = file});
  using RowsD = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  using RowsI = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;
  SurfaceMesh mesh;
  const auto nv = static_cast<Eigen::Index>(xyz.size() / 3);
  const auto nf = static_cast<Eigen::Index>(tri.size() / 3);
  mesh.V = Eigen::Map<const RowsD>(xyz.data(), nv, 3);
  mesh.F = Eigen::Map<const RowsI>(tri.data(), nf, 3);
  if (!tags.empty()) {
    CF_VERIFY(static_cast<Eigen::Index>(tags.size()) == nf, "one tag per face");
    mesh.tags = Eigen::Map<const Eigen::VectorXi>(tags.data(), nf);
  }
  return mesh;
}

}  // namespace curvefem::io::detail
