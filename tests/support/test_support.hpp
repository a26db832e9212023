// Helpers shared by the test suites: where ../shared/data is, scratch directories.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

namespace curvefem::test {

/// ../shared/data (or $CURVEFEM_DATA), or nullopt when absent: tests then GTEST_SKIP() with
/// k_no_data_message.
std::optional<std::filesystem::path> shared_data_dir();
inline constexpr const char* k_no_data_message =
    "../shared/data is absent (set CURVEFEM_DATA to a copy): real-mesh test skipped";

/// A fresh empty directory under the build tree for this test (removed at the start, kept after).
std::filesystem::path scratch_dir(const std::string& name);

/// The project's source folder (for cases/ and tools/).
std::filesystem::path source_dir();

/// Path of the built `curvefem` executable.
std::filesystem::path curvefem_executable();

/// Runs a shell command, returns its exit code; stdout+stderr go to `output` if given.
int run_command(const std::string& command, std::string* output = nullptr);

}  // namespace curvefem::test
