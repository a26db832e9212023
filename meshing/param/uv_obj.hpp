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

}  // namespace curvefem::meshing::param
