#include "tests/support/test_support.hpp"

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace curvefem::test {

std::optional<std::filesystem::path> shared_data_dir() {
  if (const char* env = std::getenv("CURVEFEM_DATA")) {
    if (std::filesystem::is_directory(env)) return std::filesystem::path(env);
    return std::nullopt;
  }
  const std::filesystem::path p = std::filesystem::path(CURVEFEM_SHARED_DIR) / "data";
  if (std::filesystem::is_directory(p / "dev")) return p;
  return std::nullopt;
}

std::filesystem::path scratch_dir(const std::string& name) {
  const auto dir = std::filesystem::path(CURVEFEM_BINARY_DIR) / "test-scratch" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::filesystem::path source_dir() { return std::filesystem::path(CURVEFEM_SOURCE_DIR); }

std::filesystem::path curvefem_executable() {
  return std::filesystem::path(CURVEFEM_BINARY_DIR) / "tools" / "curvefem" / "curvefem";
}

int run_command(const std::string& command, std::string* output) {
  const std::string full = command + " 2>&1";
  FILE* pipe = popen(full.c_str(), "r");
  if (!pipe) return -1;
  std::array<char, 4096> buf{};
  std::string out;
  while (std::fgets(buf.data(), buf.size(), pipe)) out += buf.data();
  const int status = pclose(pipe);
  if (output) *output = out;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

SurfaceMesh crater_mesh() {
  SurfaceMesh s;
  s.V.resize(9, 3);
  s.V << 0.44, 0, 1.40,    //
      -0.04, -0.11, 0.95,  //
      -0.55, -0.22, 0.97,  //
      -0.60, 0.70, 0.78,   //
      0.98, 0.57, 0.90,    //
      1.24, 0.30, 1.07,    //
      -0.08, 0.09, -1.45,  //
      0.92, 0.81, 0.48,    //
      -0.35, -0.48, 1.14;
  s.F.resize(14, 3);
  s.F << 0, 5, 1, 5, 4, 1, 4, 7, 1, 7, 3, 1, 3, 2, 1, 2, 8, 1, 8, 0, 1,  //
      5, 0, 6, 4, 5, 6, 7, 4, 6, 3, 7, 6, 2, 3, 6, 8, 2, 6, 0, 8, 6;
  return s;
}

std::optional<std::filesystem::path> cgal_data_mesh(const std::string& name,
                                                    const std::filesystem::path& dir) {
  const std::filesystem::path tarball = "/usr/share/doc/libcgal-dev/data.tar.gz";
  if (!std::filesystem::exists(tarball)) return std::nullopt;
  const std::string member = "data/meshes/" + name + ".off";
  std::string out;
  if (run_command("tar xzf " + tarball.string() + " -C " + dir.string() + " " + member, &out) != 0)
    throw std::runtime_error("cannot extract " + member + " from " + tarball.string() + ": " + out);
  return dir / member;
}

}  // namespace curvefem::test
