// Reading seam files (see the header for the format).
#include "meshing/param/seam_file.hpp"

#include <fstream>
#include <sstream>
#include <string>

#include "meshing/core/error.hpp"

namespace curvefem::meshing::param {

std::vector<std::array<int, 2>> read_seam_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) {
    ErrorContext ctx;
    ctx.file = path.string();
    throw IoError("cannot open seam file", ctx);
  }
  std::vector<std::array<int, 2>> seams;
  std::string line;
  for (long long n = 1; std::getline(in, line); ++n) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream s(line);
    long long a = -1, b = -1;
    std::string rest;
    if (!(s >> a >> b) || (s >> rest) || a < 0 || b < 0 || a > 2147483647 || b > 2147483647) {
      ErrorContext ctx;
      ctx.file = path.string();
      ctx.line = n;
      throw InputError(
          "expected two non-negative vertex ids (0-based) per seam line, got '" + line + "'", ctx);
    }
    seams.push_back({int(a), int(b)});
  }
  return seams;
}

}  // namespace curvefem::meshing::param
