// Writing the OBJ with texture coordinates.
#include "meshing/param/uv_obj.hpp"

#include <charconv>
#include <string>

#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"

namespace curvefem::meshing::param {

namespace {
void put(std::string& out, double x) {
  char buf[32];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, x);
  out.append(buf, ptr);
}
void put(std::string& out, int i) {
  char buf[16];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, i);
  out.append(buf, ptr);
}
}  // namespace

void write_uv_obj(const std::filesystem::path& path, const SurfaceMesh& mesh, const CutMesh& cut,
                  const Eigen::MatrixXd& uv) {
  CF_VERIFY(cut.num_faces() == mesh.num_faces() && uv.rows() == cut.num_uv_vertices(),
            "write_uv_obj: mesh, cut and uv do not match");
  std::string out = "# curvefem param: bijective UV map (SCAF)\n";
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    out += "v ";
    put(out, mesh.V(v, 0));
    out += ' ';
    put(out, mesh.V(v, 1));
    out += ' ';
    put(out, mesh.V(v, 2));
    out += '\n';
  }
  for (int u = 0; u < uv.rows(); ++u) {
    out += "vt ";
    put(out, uv(u, 0));
    out += ' ';
    put(out, uv(u, 1));
    out += '\n';
  }
  int group = -1;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    if (mesh.has_tags() && mesh.tags[f] != group) {
      group = mesh.tags[f];
      auto it = mesh.tag_names.find(group);
      out +=
          "g " + (it != mesh.tag_names.end() ? it->second : "tag_" + std::to_string(group)) + "\n";
    }
    out += 'f';
    for (int k = 0; k < 3; ++k) {
      out += ' ';
      put(out, mesh.F(f, k) + 1);
      out += '/';
      put(out, cut.F(f, k) + 1);
    }
    out += '\n';
  }
  write_text_file_atomic(path, out);
}

}  // namespace curvefem::meshing::param
