// Wavefront OBJ reader: `v` and `f` statements, `g` / `usemtl` groups as face tags.
#include <algorithm>
#include <array>
#include <limits>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/io/text_scanner.hpp"

namespace curvefem::io {

namespace {

// Statements that carry no triangle geometry: accepted and ignored.
bool is_ignored_statement(std::string_view key) {
  static constexpr std::array<std::string_view, 17> k_ignored = {
      "vt",     "vn",     "vp",         "o",         "s",  "mtllib", "l",        "p",       "lod",
      "maplib", "usemap", "shadow_obj", "trace_obj", "mg", "bevel",  "c_interp", "d_interp"};
  return std::find(k_ignored.begin(), k_ignored.end(), key) != k_ignored.end();
}

bool is_free_form_statement(std::string_view key) {
  static constexpr std::array<std::string_view, 16> k_free_form = {
      "cstype", "deg",  "bmat", "step", "curv", "curv2", "surf",  "parm",
      "trim",   "hole", "scrv", "sp",   "end",  "con",   "ctech", "stech"};
  return std::find(k_free_form.begin(), k_free_form.end(), key) != k_free_form.end();
}

// Face groups named by `g` or `usemtl`: ids 1.. in order of first appearance; 0 = no group.
struct GroupTable {
  std::unordered_map<std::string, int> ids;
  std::vector<std::string> names;  // names[id - 1]
  int current = 0;
  bool used = false;  // some face was read while a named group was current

  void select(std::string_view name) {
    if (name.empty()) {
      current = 0;
      return;
    }
    auto [it, inserted] = ids.try_emplace(std::string(name), static_cast<int>(names.size()) + 1);
    if (inserted) names.emplace_back(name);
    current = it->second;
  }
};

}  // namespace

SurfaceMesh read_obj(const std::filesystem::path& path) {
  const std::string file = path.string();
  const std::string text = detail::read_file_bytes(path);
  if (detail::trim(text).empty()) throw InputError("empty file", {.file = file});

  detail::TextScanner in(text, file);
  std::vector<double> xyz;
  std::vector<int> tri;
  std::vector<int> group_tags, material_tags;
  GroupTable groups, materials;
  xyz.reserve(text.size() / 40 * 3);
  tri.reserve(text.size() / 40 * 3);

  // Positive indices may (unusually) refer to vertices defined later: check them at the end.
  long long max_index = -1, max_index_line = -1;

  while (in.next_line()) {
    in.strip_comment('#');
    std::string_view key = in.token();
    if (key.empty()) continue;
    if (key == "v") {
      if (xyz.size() / 3 >= static_cast<std::size_t>(std::numeric_limits<int>::max()))
        in.fail("too many vertices");
      for (const char* what : {"vertex x", "vertex y", "vertex z"}) xyz.push_back(in.real(what));
      // An optional w or r g b may follow: ignored.
    } else if (key == "f") {
      int corners = 0;
      int face[3] = {0, 0, 0};
      const long long nv = static_cast<long long>(xyz.size() / 3);
      for (std::string_view t = in.token(); !t.empty(); t = in.token()) {
        std::string_view index_text = t.substr(0, t.find('/'));
        long long k;
        if (!detail::parse_int(index_text, k))
          in.fail("bad face vertex \"" + std::string(t.substr(0, 40)) +
                  "\" (expected v, v/vt, v//vn or v/vt/vn)");
        long long index;
        if (k > 0) {
          index = k - 1;
          if (index > max_index) {
            max_index = index;
            max_index_line = in.line_number();
          }
        } else if (k < 0) {
          index = nv + k;  // relative to the vertices read so far
          if (index < 0)
            in.fail("relative vertex index " + std::to_string(k) +
                    " points before the first vertex (" + std::to_string(nv) + " vertices so far)");
        } else {
          in.fail("vertex index 0 in face (OBJ indices start at 1)");
        }
        if (index > std::numeric_limits<int>::max()) in.fail("vertex index too large");
        if (corners < 3) face[corners] = static_cast<int>(index);
        ++corners;
      }
      if (corners > 3)
        in.fail("face has " + std::to_string(corners) +
                " vertices; curvefem needs triangles (split polygons before meshing)");
      if (corners < 3) in.fail("face has " + std::to_string(corners) + " vertices; a face needs 3");
      if (tri.size() / 3 >= static_cast<std::size_t>(std::numeric_limits<int>::max()))
        in.fail("too many faces");
      tri.insert(tri.end(), face, face + 3);
      group_tags.push_back(groups.current);
      material_tags.push_back(materials.current);
      groups.used |= groups.current != 0;
      materials.used |= materials.current != 0;
    } else if (key == "g") {
      groups.select(detail::trim(in.rest()));
    } else if (key == "usemtl") {
      materials.select(detail::trim(in.rest()));
    } else if (is_ignored_statement(key)) {
      continue;
    } else if (is_free_form_statement(key)) {
      in.fail("free-form geometry (\"" + std::string(key) +
              "\") is not supported; export triangles");
    } else {
      in.fail("unknown OBJ statement \"" + std::string(key.substr(0, 40)) + "\"");
    }
  }

  const long long nv = static_cast<long long>(xyz.size() / 3);
  if (max_index >= nv)
    throw InputError("vertex index " + std::to_string(max_index + 1) +
                         " out of range (the file has " + std::to_string(nv) + " vertices)",
                     {.file = file, .line = max_index_line});

  // Groups from `g` if any face has one, else from `usemtl`.
  GroupTable* table = groups.used ? &groups : materials.used ? &materials : nullptr;
  std::vector<int> no_tags;
  SurfaceMesh mesh = detail::make_surface(xyz, tri,
                                          table == &groups      ? group_tags
                                          : table == &materials ? material_tags
                                                                : no_tags,
                                          file);
  if (table)
    for (std::size_t i = 0; i < table->names.size(); ++i)
      mesh.tag_names[static_cast<int>(i) + 1] = table->names[i];
  return mesh;
}

}  // namespace curvefem::io
