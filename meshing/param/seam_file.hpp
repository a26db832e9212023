// Seam files: the edges to cut a surface along, one pair of 0-based vertex ids per line
// ("12 57"); blank lines and lines starting with '#' are ignored. Any other content (a missing or
// extra number, a negative id, text) is an InputError naming the file and line; a file that
// cannot be opened is an IoError. Whether each pair is an edge is checked by cut_into_charts.
#pragma once

#include <array>
#include <filesystem>
#include <vector>

namespace curvefem::meshing::param {

std::vector<std::array<int, 2>> read_seam_file(const std::filesystem::path& path);

}  // namespace curvefem::meshing::param
