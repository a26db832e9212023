// Internal helpers shared by the mesh readers: the whole file in memory, a line-tracking text
// tokenizer and a bounds-checked binary reader that knows its byte offset.
//
// Every defect is reported as InputError with the file name and the 1-based line (text) or the
// 0-based byte offset (binary). Nothing here reads past the end of the buffer, and counts read from
// a file are checked against the bytes that remain before anything is allocated from them
// (check_count), so a header announcing 10^12 faces in a 100-byte file is an error, not a
// multi-terabyte allocation.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "meshing/core/surface_mesh.hpp"

namespace curvefem::io::detail {

/// The whole file (binary mode). Throws IoError when it cannot be opened or read.
std::string read_file_bytes(const std::filesystem::path& path);

/// Parses a whole token as a double (accepts a leading '+', "nan", "inf"); false if the token is
/// not entirely a number or is out of the double range.
bool parse_double(std::string_view token, double& value);
/// Parses a whole token as a base-10 integer (accepts a leading '+'); false otherwise.
bool parse_int(std::string_view token, long long& value);

/// Lower-case copy of an ASCII string.
std::string to_lower(std::string_view s);
/// `s` without leading and trailing blanks (space, tab, \r, \n, \v, \f).
std::string_view trim(std::string_view s);

inline bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

/// Line-oriented tokenizer over text held in memory; tracks the 1-based line number of the line
/// being read. Lines end at '\n'; a trailing '\r' is removed.
class TextScanner {
 public:
  /// `offset`: byte where scanning starts (the line count starts at `first_line`).
  TextScanner(std::string_view text, std::string file, std::size_t offset = 0,
              long long first_line = 1);

  /// Moves to the next line; false (and an empty line) at the end of the text.
  bool next_line();
  /// Moves to the next line that is neither blank nor a comment (first non-blank character is
  /// `comment`); false at the end of the text.
  bool next_content_line(char comment = '#');

  long long line_number() const { return m_line_no; }
  /// The current line (without its end of line), and the part not consumed yet.
  std::string_view line() const { return m_line; }
  std::string_view rest() const { return m_line.substr(m_pos); }
  /// Cuts the current line at the first `comment` character (an end-of-line comment).
  void strip_comment(char comment);
  /// Skips blanks; true if nothing is left on the current line.
  bool at_line_end();
  /// Next blank-separated token of the current line; empty at the end of the line.
  std::string_view token();
  /// Next token as a finite double / an integer; throws InputError naming `what` otherwise.
  double real(std::string_view what);
  long long integer(std::string_view what);
  /// Next token as an integer in [lo, hi]; throws InputError naming `what` otherwise.
  long long integer_in(std::string_view what, long long lo, long long hi);
  /// Throws InputError unless the current line is fully consumed.
  void expect_line_end(std::string_view what);

  /// Byte offset of the first byte after the current line (where the next line starts).
  std::size_t next_line_offset() const { return m_next; }
  /// Bytes after the current line.
  std::size_t bytes_left() const { return m_text.size() - m_next; }  // m_next <= size
  bool at_end() const { return m_next >= m_text.size(); }
  const std::string& file() const { return m_file; }

  /// Byte offset where the current line starts.
  std::size_t line_offset() const { return m_line_start; }
  /// Errors name the byte offset of the current line instead of its number (text embedded in a
  /// binary file, where line numbers mean little).
  void set_report_byte_offsets(bool on) { m_report_offsets = on; }

  /// Throws InputError("file:line: defect") (or "file: byte N: defect").
  [[noreturn]] void fail(const std::string& defect) const;

 private:
  std::string_view m_text;
  std::string m_file;
  std::size_t m_next = 0;        // start of the next line
  std::size_t m_line_start = 0;  // start of the current line
  std::string_view m_line;
  std::size_t m_pos = 0;  // cursor in m_line
  long long m_line_no = 0;
  bool m_past_end = false;  // next_line() already returned false once
  bool m_report_offsets = false;
};

/// Bounds-checked reader of binary data held in memory, optionally byte-swapping numbers.
class BinaryReader {
 public:
  BinaryReader(std::string_view data, std::string file, std::size_t offset = 0,
               bool swap_bytes = false);

  std::size_t offset() const { return m_pos; }
  std::size_t remaining() const { return m_data.size() - m_pos; }
  std::size_t size() const { return m_data.size(); }
  void set_swap_bytes(bool swap) { m_swap = swap; }
  bool swap_bytes() const { return m_swap; }
  void seek(std::size_t offset);

  /// Throws InputError ("truncated ...") unless `n` more bytes are available.
  void need(std::size_t n, std::string_view what) const;
  void skip(std::size_t n, std::string_view what) {
    need(n, what);
    m_pos += n;
  }

  /// Reads one arithmetic value of type T (byte-swapped if requested).
  template <class T>
  T read(std::string_view what) {
    static_assert(std::is_arithmetic_v<T>);
    need(sizeof(T), what);
    T value;
    if (m_swap) {
      unsigned char bytes[sizeof(T)];
      for (std::size_t i = 0; i < sizeof(T); ++i) bytes[i] = m_data[m_pos + sizeof(T) - 1 - i];
      std::memcpy(&value, bytes, sizeof(T));
    } else {
      std::memcpy(&value, m_data.data() + m_pos, sizeof(T));
    }
    m_pos += sizeof(T);
    return value;
  }

  /// Throws InputError("file: byte N: defect") at the current offset or at `offset`.
  [[noreturn]] void fail(const std::string& defect) const;
  [[noreturn]] void fail_at(std::size_t offset, const std::string& defect) const;
  const std::string& file() const { return m_file; }

 private:
  std::string_view m_data;
  std::string m_file;
  std::size_t m_pos = 0;
  bool m_swap = false;
};

/// Throws InputError (at `line` if >= 0, else at `byte_offset` if >= 0) unless
/// 0 <= count <= max_count and count * min_bytes_each <= bytes_left: a count announced by a header
/// can never be larger than what the rest of the file can hold.
void check_count(long long count, std::size_t min_bytes_each, std::size_t bytes_left,
                 std::string_view what, const std::string& file, long long line,
                 long long byte_offset = -1, long long max_count = 2147483647LL);

/// SurfaceMesh from flat row-major arrays: xyz (3 per vertex), tri (3 per face, 0-based, already
/// range-checked), tags (empty or one per face). Throws InputError naming `file` if there is no
/// face at all: a reader never returns an empty surface.
SurfaceMesh make_surface(const std::vector<double>& xyz, const std::vector<int>& tri,
                         const std::vector<int>& tags, const std::string& file);

}  // namespace curvefem::io::detail
