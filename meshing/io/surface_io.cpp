// Dispatch of the surface readers by extension, and the writers of every SurfaceFormat.
#include "meshing/io/surface_io.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
#include "meshing/io/text_scanner.hpp"

namespace curvefem::io {

namespace {

std::string lower_extension(const std::filesystem::path& path) {
  return detail::to_lower(path.extension().string());
}

// Shortest decimal text that reads back to exactly the same double.
void put(std::string& out, double x) {
  char buf[32];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, x);
  out.append(buf, ptr);
}
void put(std::string& out, long long i) {
  char buf[24];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, i);
  out.append(buf, ptr);
}
void put(std::string& out, int i) { put(out, static_cast<long long>(i)); }
void put(std::string& out, std::string_view s) { out.append(s); }
void put(std::string& out, const char* s) { out.append(s); }
void put(std::string& out, char c) { out.push_back(c); }

template <class... Args>
void line(std::string& out, const Args&... args) {
  (put(out, args), ...);
  out.push_back('\n');
}

// Little-endian raw bytes of a number.
template <class T>
void put_le(std::string& out, T value) {
  static_assert(std::endian::native == std::endian::little, "big-endian hosts not supported");
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

void check_writable(const SurfaceMesh& mesh) {
  CF_VERIFY(mesh.V.cols() == 3 || mesh.V.rows() == 0, "V must be #V x 3");
  CF_VERIFY(mesh.F.cols() == 3 || mesh.F.rows() == 0, "F must be #F x 3");
  CF_VERIFY(mesh.tags.size() == 0 || mesh.tags.size() == mesh.F.rows(), "tags must be empty or #F");
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f)
    for (int c = 0; c < 3; ++c)
      CF_VERIFY(mesh.F(f, c) >= 0 && mesh.F(f, c) < mesh.V.rows(), "face index out of range");
}

int tag_of(const SurfaceMesh& mesh, Eigen::Index f) { return mesh.has_tags() ? mesh.tags(f) : 0; }

// A group / physical name usable on one line: no line breaks, no quotes.
std::string clean_name(const std::string& name) {
  std::string out;
  for (char c : name) out.push_back(c == '\n' || c == '\r' || c == '"' ? '_' : c);
  return std::string(detail::trim(out));
}

// ------------------------------------------------------------------------------------ OBJ, OFF

std::string obj_text(const SurfaceMesh& mesh) {
  std::string out;
  out.reserve(static_cast<std::size_t>(mesh.V.rows() * 60 + mesh.F.rows() * 30));
  line(out, "# written by curvefem: ", mesh.num_vertices(), " vertices, ", mesh.num_faces(),
       " faces");
  for (Eigen::Index v = 0; v < mesh.V.rows(); ++v)
    line(out, "v ", mesh.V(v, 0), ' ', mesh.V(v, 1), ' ', mesh.V(v, 2));
  // Group names: tag_names where unique, else "tag_<t>"; tag 0 is the unnamed group "g".
  std::map<int, std::string> names;
  std::set<std::string> used;
  if (mesh.has_tags()) {
    for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
      int t = mesh.tags(f);
      if (t == 0 || names.count(t)) continue;
      auto it = mesh.tag_names.find(t);
      std::string name = it != mesh.tag_names.end() ? clean_name(it->second) : std::string();
      if (name.empty() || used.count(name)) name = "tag_" + std::to_string(t);
      while (used.count(name)) name += "_";
      used.insert(name);
      names[t] = name;
    }
  }
  int current = 0;
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    int t = tag_of(mesh, f);
    if (t != current) {
      line(out, t == 0 ? std::string("g") : "g " + names[t]);
      current = t;
    }
    line(out, "f ", mesh.F(f, 0) + 1, ' ', mesh.F(f, 1) + 1, ' ', mesh.F(f, 2) + 1);
  }
  return out;
}

std::string off_text(const SurfaceMesh& mesh) {
  std::string out;
  out.reserve(static_cast<std::size_t>(mesh.V.rows() * 60 + mesh.F.rows() * 30));
  line(out, "OFF");
  line(out, mesh.num_vertices(), ' ', mesh.num_faces(), " 0");
  for (Eigen::Index v = 0; v < mesh.V.rows(); ++v)
    line(out, mesh.V(v, 0), ' ', mesh.V(v, 1), ' ', mesh.V(v, 2));
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f)
    line(out, "3 ", mesh.F(f, 0), ' ', mesh.F(f, 1), ' ', mesh.F(f, 2));
  return out;
}

// ------------------------------------------------------------------------------------------ STL

Eigen::Vector3d face_normal(const SurfaceMesh& mesh, Eigen::Index f) {
  Eigen::Vector3d a = mesh.V.row(mesh.F(f, 0)), b = mesh.V.row(mesh.F(f, 1)),
                  c = mesh.V.row(mesh.F(f, 2));
  Eigen::Vector3d n = (b - a).cross(c - a);
  double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

std::string stl_ascii_text(const SurfaceMesh& mesh) {
  std::string out;
  out.reserve(static_cast<std::size_t>(mesh.F.rows() * 250));
  line(out, "solid curvefem");
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    Eigen::Vector3d n = face_normal(mesh, f);
    line(out, "facet normal ", n.x(), ' ', n.y(), ' ', n.z());
    line(out, "  outer loop");
    for (int c = 0; c < 3; ++c) {
      auto v = mesh.F(f, c);
      line(out, "    vertex ", mesh.V(v, 0), ' ', mesh.V(v, 1), ' ', mesh.V(v, 2));
    }
    line(out, "  endloop");
    line(out, "endfacet");
  }
  line(out, "endsolid curvefem");
  return out;
}

std::string stl_binary_bytes(const SurfaceMesh& mesh) {
  std::string out;
  out.reserve(static_cast<std::size_t>(84 + 50 * mesh.F.rows()));
  std::string header = "binary STL written by curvefem";
  header.resize(80, ' ');
  out += header;
  put_le(out, static_cast<std::uint32_t>(mesh.F.rows()));
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    Eigen::Vector3d n = face_normal(mesh, f);
    for (int k = 0; k < 3; ++k) put_le(out, static_cast<float>(n(k)));
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) put_le(out, static_cast<float>(mesh.V(mesh.F(f, c), k)));
    put_le(out, std::uint16_t{0});
  }
  return out;
}

// ------------------------------------------------------------------------------------------ PLY

std::string ply_bytes(const SurfaceMesh& mesh, bool binary) {
  std::string out;
  out.reserve(static_cast<std::size_t>(200 + mesh.V.rows() * 60 + mesh.F.rows() * 30));
  line(out, "ply");
  line(out, binary ? "format binary_little_endian 1.0" : "format ascii 1.0");
  line(out, "comment written by curvefem");
  for (const auto& [tag, name] : mesh.tag_names)
    if (mesh.has_tags()) line(out, "comment tag_name ", tag, ' ', clean_name(name));
  line(out, "element vertex ", mesh.num_vertices());
  line(out, "property double x");
  line(out, "property double y");
  line(out, "property double z");
  line(out, "element face ", mesh.num_faces());
  line(out, "property list uchar int vertex_indices");
  if (mesh.has_tags()) line(out, "property int tag");
  line(out, "end_header");
  for (Eigen::Index v = 0; v < mesh.V.rows(); ++v) {
    if (binary)
      for (int k = 0; k < 3; ++k) put_le(out, mesh.V(v, k));
    else
      line(out, mesh.V(v, 0), ' ', mesh.V(v, 1), ' ', mesh.V(v, 2));
  }
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    if (binary) {
      put_le(out, std::uint8_t{3});
      for (int c = 0; c < 3; ++c) put_le(out, static_cast<std::int32_t>(mesh.F(f, c)));
      if (mesh.has_tags()) put_le(out, static_cast<std::int32_t>(mesh.tags(f)));
    } else if (mesh.has_tags()) {
      line(out, "3 ", mesh.F(f, 0), ' ', mesh.F(f, 1), ' ', mesh.F(f, 2), ' ', mesh.tags(f));
    } else {
      line(out, "3 ", mesh.F(f, 0), ' ', mesh.F(f, 1), ' ', mesh.F(f, 2));
    }
  }
  return out;
}

// ------------------------------------------------------------------------------------------ MSH

void check_msh_tags(const SurfaceMesh& mesh, const std::filesystem::path& path) {
  if (!mesh.has_tags()) return;
  if (mesh.tags.minCoeff() < 0)
    throw InputError(
        "MSH physical tags must be >= 0 (tag " + std::to_string(mesh.tags.minCoeff()) + ")",
        {.file = path.string()});
}

void msh_physical_names(std::string& out, const SurfaceMesh& mesh) {
  if (!mesh.has_tags() || mesh.tag_names.empty()) return;
  std::set<int> present(mesh.tags.data(), mesh.tags.data() + mesh.tags.size());
  std::vector<std::pair<int, std::string>> names;
  for (const auto& [tag, name] : mesh.tag_names)
    if (tag > 0 && present.count(tag)) names.emplace_back(tag, clean_name(name));
  if (names.empty()) return;
  line(out, "$PhysicalNames");
  line(out, static_cast<int>(names.size()));
  for (const auto& [tag, name] : names) line(out, "2 ", tag, " \"", name, '"');
  line(out, "$EndPhysicalNames");
}

std::string msh22_text(const SurfaceMesh& mesh) {
  std::string out;
  out.reserve(static_cast<std::size_t>(200 + mesh.V.rows() * 60 + mesh.F.rows() * 40));
  line(out, "$MeshFormat");
  line(out, "2.2 0 8");
  line(out, "$EndMeshFormat");
  msh_physical_names(out, mesh);
  line(out, "$Nodes");
  line(out, mesh.num_vertices());
  for (Eigen::Index v = 0; v < mesh.V.rows(); ++v)
    line(out, static_cast<long long>(v + 1), ' ', mesh.V(v, 0), ' ', mesh.V(v, 1), ' ',
         mesh.V(v, 2));
  line(out, "$EndNodes");
  line(out, "$Elements");
  line(out, mesh.num_faces());
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    const int t = tag_of(mesh, f);
    // id type #tags physical elementary nodes (elementary entity = tag, 1 when untagged)
    line(out, static_cast<long long>(f + 1), " 2 2 ", t, ' ', t > 0 ? t : 1, ' ', mesh.F(f, 0) + 1,
         ' ', mesh.F(f, 1) + 1, ' ', mesh.F(f, 2) + 1);
  }
  line(out, "$EndElements");
  return out;
}

std::string msh41_text(const SurfaceMesh& mesh) {
  // One surface entity per tag value (entity tag = position + 1, physical = the tag, none for 0);
  // all nodes are written in the block of the first entity. Element ids are the 1-based face
  // positions, so a reader ordering by element id restores the face order.
  std::map<int, int> entity_of_tag;
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) entity_of_tag.try_emplace(tag_of(mesh, f), 0);
  int next_entity = 1;
  for (auto& [tag, entity] : entity_of_tag) entity = next_entity++;
  std::vector<std::vector<Eigen::Index>> faces_of_entity(entity_of_tag.size() + 1);
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f)
    faces_of_entity[static_cast<std::size_t>(entity_of_tag[tag_of(mesh, f)])].push_back(f);

  std::string out;
  out.reserve(static_cast<std::size_t>(400 + mesh.V.rows() * 70 + mesh.F.rows() * 40));
  line(out, "$MeshFormat");
  line(out, "4.1 0 8");
  line(out, "$EndMeshFormat");
  msh_physical_names(out, mesh);
  line(out, "$Entities");
  line(out, "0 0 ", static_cast<int>(entity_of_tag.size()), " 0");
  for (const auto& [tag, entity] : entity_of_tag) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(0), hi = Eigen::Vector3d::Constant(0);
    bool first = true;
    for (Eigen::Index f : faces_of_entity[static_cast<std::size_t>(entity)])
      for (int c = 0; c < 3; ++c) {
        Eigen::Vector3d p = mesh.V.row(mesh.F(f, c));
        lo = first ? p : Eigen::Vector3d(lo.cwiseMin(p));
        hi = first ? p : Eigen::Vector3d(hi.cwiseMax(p));
        first = false;
      }
    if (tag > 0)
      line(out, entity, ' ', lo.x(), ' ', lo.y(), ' ', lo.z(), ' ', hi.x(), ' ', hi.y(), ' ',
           hi.z(), " 1 ", tag, " 0");
    else
      line(out, entity, ' ', lo.x(), ' ', lo.y(), ' ', lo.z(), ' ', hi.x(), ' ', hi.y(), ' ',
           hi.z(), " 0 0");
  }
  line(out, "$EndEntities");
  line(out, "$Nodes");
  const int nv = mesh.num_vertices();
  line(out, nv > 0 ? 1 : 0, ' ', nv, ' ', nv > 0 ? 1 : 0, ' ', nv);
  if (nv > 0) {
    line(out, "2 1 0 ", nv);
    for (int v = 1; v <= nv; ++v) line(out, v);
    for (Eigen::Index v = 0; v < mesh.V.rows(); ++v)
      line(out, mesh.V(v, 0), ' ', mesh.V(v, 1), ' ', mesh.V(v, 2));
  }
  line(out, "$EndNodes");
  line(out, "$Elements");
  const int nf = mesh.num_faces();
  line(out, static_cast<int>(entity_of_tag.size()), ' ', nf, ' ', nf > 0 ? 1 : 0, ' ', nf);
  for (const auto& [tag, entity] : entity_of_tag) {
    const auto& faces = faces_of_entity[static_cast<std::size_t>(entity)];
    line(out, "2 ", entity, " 2 ", static_cast<long long>(faces.size()));
    for (Eigen::Index f : faces)
      line(out, static_cast<long long>(f + 1), ' ', mesh.F(f, 0) + 1, ' ', mesh.F(f, 1) + 1, ' ',
           mesh.F(f, 2) + 1);
  }
  line(out, "$EndElements");
  return out;
}

}  // namespace

SurfaceMesh read_surface(const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".obj") return read_obj(path);
  if (ext == ".off") return read_off(path);
  if (ext == ".stl") return read_stl(path);
  if (ext == ".ply") return read_ply(path);
  if (ext == ".msh") return read_msh_surface(path);
  throw InputError("unknown surface format \"" + path.extension().string() +
                       "\" (expected .obj .off .stl .ply .msh)",
                   {.file = path.string()});
}

SurfaceFormat surface_format_from_extension(const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".obj") return SurfaceFormat::obj;
  if (ext == ".off") return SurfaceFormat::off;
  if (ext == ".stl") return SurfaceFormat::stl_binary;
  if (ext == ".ply") return SurfaceFormat::ply_binary;
  if (ext == ".msh") return SurfaceFormat::msh41;
  throw InputError("unknown surface format \"" + path.extension().string() +
                       "\" (expected .obj .off .stl .ply .msh)",
                   {.file = path.string()});
}

void write_surface(const std::filesystem::path& path, const SurfaceMesh& mesh,
                   SurfaceFormat format) {
  check_writable(mesh);
  std::string bytes;
  switch (format) {
    case SurfaceFormat::obj:
      bytes = obj_text(mesh);
      break;
    case SurfaceFormat::off:
      bytes = off_text(mesh);
      break;
    case SurfaceFormat::stl_ascii:
      bytes = stl_ascii_text(mesh);
      break;
    case SurfaceFormat::stl_binary:
      bytes = stl_binary_bytes(mesh);
      break;
    case SurfaceFormat::ply_ascii:
      bytes = ply_bytes(mesh, false);
      break;
    case SurfaceFormat::ply_binary:
      bytes = ply_bytes(mesh, true);
      break;
    case SurfaceFormat::msh22:
      check_msh_tags(mesh, path);
      bytes = msh22_text(mesh);
      break;
    case SurfaceFormat::msh41:
      check_msh_tags(mesh, path);
      bytes = msh41_text(mesh);
      break;
  }
  write_text_file_atomic(path, bytes);
}

}  // namespace curvefem::io
