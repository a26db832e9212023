// Writing the OBJ with texture coordinates.
#include "meshing/param/uv_obj.hpp"

#include <charconv>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

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

ObjTexture read_obj_texture(const std::filesystem::path& path) {
  std::ifstream in(path);
  ErrorContext ctx;
  ctx.file = path.string();
  if (!in) throw IoError("cannot open", ctx);
  std::vector<Eigen::Vector2d> vt;
  std::vector<Eigen::Vector3i> ft;
  std::string line;
  for (long long n = 1; std::getline(in, line); ++n) {
    std::istringstream s(line);
    std::string kind;
    s >> kind;
    ctx.line = n;
    if (kind == "vt") {
      Eigen::Vector2d x;
      if (!(s >> x.x() >> x.y()) || !x.allFinite())
        throw InputError("vt needs two finite numbers", ctx);
      vt.push_back(x);
    } else if (kind == "f") {
      Eigen::Vector3i t = Eigen::Vector3i::Constant(-1);
      std::string corner;
      for (int k = 0; k < 3 && s >> corner; ++k) {
        const auto slash = corner.find('/');
        if (slash == std::string::npos || slash + 1 >= corner.size() || corner[slash + 1] == '/')
          continue;
        long long id = 0;
        try {
          id = std::stoll(corner.substr(slash + 1));
        } catch (const std::exception&) {
          throw InputError("bad vt index in '" + corner + "'", ctx);
        }
        const long long resolved = id < 0 ? (long long)vt.size() + id : id - 1;
        if (id == 0 || resolved < 0 || resolved >= (long long)vt.size())
          throw InputError("vt index " + std::to_string(id) + " out of range", ctx);
        t[k] = int(resolved);
      }
      ft.push_back(t);
    }
  }
  ObjTexture r;
  r.vt.resize(Eigen::Index(vt.size()), 2);
  for (std::size_t i = 0; i < vt.size(); ++i) r.vt.row(Eigen::Index(i)) = vt[i].transpose();
  r.Ft.resize(Eigen::Index(ft.size()), 3);
  for (std::size_t i = 0; i < ft.size(); ++i) r.Ft.row(Eigen::Index(i)) = ft[i].transpose();
  return r;
}

Eigen::MatrixXd uv_from_texture(const CutMesh& cut, const ObjTexture& texture) {
  if (texture.Ft.rows() != cut.num_faces())
    throw InputError("the texture coordinates list " + std::to_string(texture.Ft.rows()) +
                     " faces, the surface " + std::to_string(cut.num_faces()));
  Eigen::MatrixXd uv(cut.num_uv_vertices(), 2);
  std::vector<int> from(cut.num_uv_vertices(), -1);
  for (int f = 0; f < cut.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      ErrorContext ctx;
      ctx.face = f;
      const int t = texture.Ft(f, k), u = cut.F(f, k);
      if (t < 0) throw InputError("a face corner has no texture coordinate (vt)", ctx);
      if (from[u] < 0) {
        from[u] = t;
        uv.row(u) = texture.vt.row(t);
      } else if (uv.row(u) != texture.vt.row(t)) {
        ctx.vertex = cut.parent[u];
        throw InputError(
            "the given texture coordinates are cut at a vertex that is not on a seam (add the "
            "seam, or give the same vt)",
            ctx);
      }
    }
  return uv;
}

}  // namespace curvefem::meshing::param
