#include "pipeline/mesh_dir.hpp"

#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <vector>

#include "meshing/check/check_surface.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/curved/curved_validate.hpp"
#include "meshing/io/boundary_map_io.hpp"
#include "meshing/io/msh_io.hpp"
#include "meshing/io/surface_io.hpp"
#include "pipeline/input_floors.hpp"
#include "pipeline/mesh_validity.hpp"
#include "pipeline/report_json.hpp"

namespace curvefem::pipeline {

std::string file_checksum(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot read the file to checksum it", {.file = path.string()});
  std::uint64_t h = 0xcbf29ce484222325ull;
  std::vector<char> buffer(1 << 20);
  while (in) {
    in.read(buffer.data(), std::streamsize(buffer.size()));
    const std::streamsize n = in.gcount();
    for (std::streamsize i = 0; i < n; ++i) {
      h ^= static_cast<unsigned char>(buffer[std::size_t(i)]);
      h *= 0x100000001b3ull;
    }
  }
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h));
  return text;
}

void save_mesh_dir(const std::filesystem::path& dir, const LagrangeMesh& mesh,
                   const BoundaryMap& map, const ShellFibers& fibers, const std::string& input,
                   const std::string& input_checksum) {
  io::write_msh(dir / "mesh.msh", mesh);
  io::write_boundary_map(dir / "boundary_map.json", map, input, &fibers, input_checksum);
}

namespace {

/// The ε the saved mesh was made for: report.json's eps_rel (curvefem mesh) or meshing.eps_rel
/// (curvefem run). InputError when neither is there.
double saved_eps(const std::filesystem::path& dir) {
  const std::filesystem::path file = dir / "report.json";
  std::ifstream in(file);
  try {
    const nlohmann::json r = nlohmann::json::parse(in);
    if (r.contains("eps_rel")) return r.at("eps_rel").get<double>();  // curvefem mesh
    return r.at("meshing").at("eps_rel").get<double>();               // curvefem run
  } catch (const nlohmann::json::exception& e) {
    throw InputError(std::string("no eps_rel of the saved mesh in it: ") + e.what(),
                     {.file = file.string()});
  }
}

}  // namespace

Domain load_mesh_dir(const CaseSpec& spec, const StageContext& ctx) {
  std::optional<ScopedTimer> t;
  if (ctx.timings) t.emplace(*ctx.timings, "load_mesh");
  ctx.update("load saved mesh", 0.0);
  const std::filesystem::path& dir = spec.mesh_dir;
  const std::filesystem::path map_file = dir / "boundary_map.json";
  io::SavedBoundaryMap saved = io::read_boundary_map(map_file);
  if (!saved.fibers)
    throw InputError("holds no shell fibers (phi^-1 cannot be evaluated): re-run curvefem mesh",
                     {.file = map_file.string()});
  if (saved.input.empty())
    throw InputError("records no input surface", {.file = map_file.string()});
  std::filesystem::path input_path(saved.input);
  if (input_path.is_relative()) input_path = dir / input_path;
  input_path = std::filesystem::absolute(input_path).lexically_normal();
  if (!std::filesystem::is_regular_file(input_path))
    throw InputError("the input surface it was made from is gone: " + input_path.string(),
                     {.file = map_file.string()});
  const std::string checksum = file_checksum(input_path);
  if (saved.input_checksum.empty())
    throw InputError(
        "records no checksum of its input (written before mesh reuse existed): "
        "re-run curvefem mesh",
        {.file = map_file.string()});
  if (checksum != saved.input_checksum)
    throw InputError("the input surface changed since the mesh was made (checksum " + checksum +
                         ", saved " + saved.input_checksum + "): mesh it again",
                     {.file = input_path.string()});
  Domain d;
  d.method = MeshingMethod::curved;
  d.input = io::read_surface(input_path);
  d.mesh = io::read_msh(dir / "mesh.msh");
  if (d.mesh.kind != CellKind::tetrahedron)
    throw InputError("holds no tetrahedra", {.file = (dir / "mesh.msh").string()});
  for (Eigen::Index c = 0; c < d.mesh.cell_tags.size(); ++c)
    if (d.mesh.cell_tags[c] >= 3)
      throw InputError("an exterior mesh (cells tagged 3, 4) cannot be reused yet",
                       {.file = (dir / "mesh.msh").string()});
  if (saved.map.num_input_vertices() != d.input.num_vertices())
    throw InputError("its map has " + std::to_string(saved.map.num_input_vertices()) +
                         " input vertices, the input " + std::to_string(d.input.num_vertices()),
                     {.file = map_file.string()});
  d.curved_map = std::move(saved.map);
  d.fibers = std::make_shared<const ShellFibers>(std::move(*saved.fibers));
  d.report["reused"] = {
      {"mesh_dir", dir.string()}, {"input", input_path.string()}, {"input_checksum", checksum}};
  d.report["input_vertices"] = d.input.num_vertices();
  d.report["input_faces"] = d.input.num_faces();
  d.report["order"] = d.mesh.order;
  const double eps = saved_eps(dir);
  d.report["eps_rel"] = eps;
  if (spec.validate) {
    ctx.update("validate mesh", 0.0);
    validate_domain(d, eps);
  }
  return d;
}

}  // namespace curvefem::pipeline

namespace curvefem::pipeline {

void validate_domain(Domain& d, double eps_rel) {
  const meshing::curved::CurvedValidation v =
      meshing::curved::validate_curved_mesh(d.mesh, *d.curved_map, d.input);
  const MapRoundtrip trip = map_roundtrip(*d.curved_map, *d.fibers, d.input);
  nlohmann::json j = nlohmann::json::parse(curved_validation_json(v, eps_rel).dump());
  d.valid = curved_mesh_valid(v, eps_rel, trip);
  j["map_roundtrip_max_error_rel"] = trip.max_error_rel;
  j["map_roundtrip_failures"] = trip.failures;
  j["map_roundtrip_worst_vertex"] = trip.worst_vertex;
  j["map_roundtrip_first_failure"] = trip.first_failure;
  j["map_roundtrip_s"] = trip.seconds;
  j["valid"] = d.valid;  // the validation and the round trip (mesh_validity.hpp)
  d.report["validation"] = j;
  d.report["max_distance_rel"] = v.max_distance_rel;
  d.report["min_jacobian_certified"] = v.certified();
  const InputFloors floors =
      input_floors(d.input, *d.curved_map, d.mesh, v.cell_mips, v.cell_scaled_jacobian);
  d.report["input_floors"] = input_floors_json(floors);
  if (const std::string hint = merge_hint(floors, eps_rel); !hint.empty())
    log::warn("meshing: ", hint);
  d.cell_quality = curved_validation_cell_fields(v);
}

}  // namespace curvefem::pipeline
