// Helpers shared by the test suites: where ../shared/data is, scratch directories.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "meshing/core/surface_mesh.hpp"

namespace curvefem::test {

/// A crater: the pit vertex 1 surrounded by the rim 0, 5, 4, 7, 3, 2, 8 (heights 0.48 to 1.40,
/// most above the pit), closed below by the apex 6; 9 vertices, 14 faces. Star-shaped around the
/// origin, so embedded. The rim vertices 0 and 5 are singular (no direction sees all their
/// faces), so build_shell pinches the rim edge (0, 5) at its rounded midpoint m; the face
/// (5, 0, 6) across that edge then enters, by the rounding of m, the prisms of (0, m, 1) and
/// (m, 5, 1), whose pillar at the pit does not see it: 2 prisms fail the section condition
/// (tests/meshing/shell/test_shell_bevel.cpp).
SurfaceMesh crater_mesh();

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

/// CGAL's data mesh data/meshes/NAME.off from libcgal-dev's /usr/share/doc/libcgal-dev/data.tar.gz
/// (a Debian package file, not ../shared), extracted into `dir`; nullopt when the package file is
/// absent (tests then GTEST_SKIP() with k_no_cgal_data_message). Throws when tar fails.
std::optional<std::filesystem::path> cgal_data_mesh(const std::string& name,
                                                    const std::filesystem::path& dir);
inline constexpr const char* k_no_cgal_data_message =
    "/usr/share/doc/libcgal-dev/data.tar.gz is absent (libcgal-dev): CGAL data test skipped";

}  // namespace curvefem::test
