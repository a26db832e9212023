// ParaView collection files (.pvd): one file that opens several VTU parts (and time steps) at
// once. Paths are written relative to the .pvd's folder. Written atomically.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace curvefem::io {

struct PvdEntry {
  std::string file;  ///< relative to the .pvd file
  int part = 0;
  double timestep = 0.0;
  std::string name;  ///< optional block name shown by ParaView
};

void write_pvd(const std::filesystem::path& path, const std::vector<PvdEntry>& entries);

}  // namespace curvefem::io
