// OBJ output of a parameterized surface: the input's `v` lines unchanged, one `vt` per UV vertex,
// and the input's faces in order as `f v/vt v/vt v/vt` (a vertex on a seam appears with several
// vt). Groups of the input (tags) are written as `g` lines. Atomic (temp file + rename); numbers
// in the shortest text that reads back to the same double.
#pragma once

#include <Eigen/Core>
#include <filesystem>

#include "meshing/core/surface_mesh.hpp"
#include "meshing/param/cut_mesh.hpp"

namespace curvefem::meshing::param {

void write_uv_obj(const std::filesystem::path& path, const SurfaceMesh& mesh, const CutMesh& cut,
                  const Eigen::MatrixXd& uv);

/// Texture coordinates of an OBJ file: the `vt` rows (#T × 2, extra numbers ignored) and, per
/// face in file order (the order of io::read_obj), the vt id of each corner (#F × 3, −1 where the
/// corner has none). Indices may be negative (relative), as in the format. A vt index out of
/// range is an InputError naming file and line.
struct ObjTexture {
  Eigen::MatrixXd vt;
  Eigen::MatrixXi Ft;
};
ObjTexture read_obj_texture(const std::filesystem::path& path);

/// The UV position of every UV vertex of `cut` from its corners' vt (#U × 2). InputError when a
/// face has no vt or when the corners of one UV vertex carry different vt positions (the given
/// map is cut where `cut` is not: add the seam).
Eigen::MatrixXd uv_from_texture(const CutMesh& cut, const ObjTexture& texture);

}  // namespace curvefem::meshing::param
