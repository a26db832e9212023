#include "tests/support/test_support.hpp"

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>

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

}  // namespace curvefem::test
