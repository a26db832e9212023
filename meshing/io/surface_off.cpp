// Object File Format (OFF) reader: header, counts, vertex lines, "3 i j k" face lines.
#include <string>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/io/text_scanner.hpp"

namespace curvefem::io {

namespace {

// "OFF" with the optional ST/C/N prefixes (texture, colour, normal: extra numbers per vertex that
// we ignore). "4OFF" / "nOFF" (other dimensions) are rejected by the caller.
bool is_off_keyword(std::string_view key) {
  if (key.size() < 3 || key.substr(key.size() - 3) != "OFF") return false;
  std::string_view prefix = key.substr(0, key.size() - 3);
  if (prefix.substr(0, 2) == "ST") prefix.remove_prefix(2);
  if (!prefix.empty() && prefix[0] == 'C') prefix.remove_prefix(1);
  if (!prefix.empty() && prefix[0] == 'N') prefix.remove_prefix(1);
  return prefix.empty();
}

}  // namespace

SurfaceMesh read_off(const std::filesystem::path& path) {
  const std::string file = path.string();
  const std::string text = detail::read_file_bytes(path);
  if (detail::trim(text).empty()) throw InputError("empty file", {.file = file});

  detail::TextScanner in(text, file);
  if (!in.next_content_line()) throw InputError("empty file (only comments)", {.file = file});
  in.strip_comment('#');
  std::string_view key = in.token();
  if (key.find("OFF") != std::string_view::npos && !is_off_keyword(key))
    in.fail("unsupported OFF variant \"" + std::string(key.substr(0, 20)) +
            "\" (only 3D OFF, COFF, NOFF, STOFF)");
  if (!is_off_keyword(key)) in.fail("missing OFF header (the file must start with \"OFF\")");
  if (!in.at_line_end()) {
    if (detail::to_lower(in.rest()).find("binary") != std::string::npos)
      in.fail("binary OFF is not supported");
  } else if (!in.next_content_line()) {
    in.fail("truncated: missing the \"#vertices #faces #edges\" line");
  } else {
    in.strip_comment('#');
  }
  // Counts: on the header line or on the next content line.
  const long long nv = in.integer("vertex count");
  const long long nf = in.integer("face count");
  if (!in.at_line_end()) in.integer("edge count");
  in.expect_line_end("the counts");
  const long long counts_line = in.line_number();
  detail::check_count(nv, 6, in.bytes_left(), "vertices", file, counts_line);  // "0 0 0\n"
  detail::check_count(nf, 8, in.bytes_left(), "faces", file, counts_line);     // "3 0 1 2\n"

  std::vector<double> xyz(static_cast<std::size_t>(nv) * 3);
  for (long long v = 0; v < nv; ++v) {
    if (!in.next_content_line())
      in.fail("truncated: header announces " + std::to_string(nv) + " vertices, found " +
              std::to_string(v));
    for (int c = 0; c < 3; ++c)
      xyz[static_cast<std::size_t>(3 * v + c)] = in.real(c == 0   ? "vertex x"
                                                         : c == 1 ? "vertex y"
                                                                  : "vertex z");
    // Colours, normals, texture coordinates may follow: ignored.
  }

  std::vector<int> tri(static_cast<std::size_t>(nf) * 3);
  for (long long f = 0; f < nf; ++f) {
    if (!in.next_content_line())
      in.fail("truncated: header announces " + std::to_string(nf) + " faces, found " +
              std::to_string(f));
    const long long n = in.integer("face vertex count");
    if (n > 3)
      in.fail("face has " + std::to_string(n) +
              " vertices; curvefem needs triangles (split polygons before meshing)");
    if (n < 3) in.fail("face has " + std::to_string(n) + " vertices; a face needs 3");
    for (int c = 0; c < 3; ++c) {
      const long long i = in.integer("face vertex index");
      if (i < 0) in.fail("negative vertex index " + std::to_string(i) + " in face");
      if (i >= nv)
        in.fail("vertex index " + std::to_string(i) + " out of range (the file has " +
                std::to_string(nv) + " vertices, numbered from 0)");
      tri[static_cast<std::size_t>(3 * f + c)] = static_cast<int>(i);
    }
    // A face colour may follow: ignored.
  }
  if (in.next_content_line())
    in.fail("unexpected content after the " + std::to_string(nf) +
            " faces announced in the header (count mismatch?)");
  return detail::make_surface(xyz, tri, {}, file);
}

}  // namespace curvefem::io
