// Garbage robustness of the surface readers: truncated and byte-flipped versions of valid files
// (procedural meshes written by write_surface, binary MSH written by Gmsh, and real meshes of
// ../shared/data when present) must either read into a valid mesh or throw curvefem::InputError.
// Any other exception, an invalid result or a crash (run it under CURVEFEM_SANITIZE) is a failure.
#include <gmsh.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/io/gmsh_session.hpp"
#include "meshing/io/surface_io.hpp"
#include "tests/support/test_support.hpp"

namespace curvefem::io {
namespace {

namespace fs = std::filesystem;

constexpr unsigned k_seed = 20240611u;
constexpr int k_truncations = 250;  // per sample file (fewer for files over 64 KiB)
constexpr int k_flips = 500;        // per sample file: 1..4 bytes changed, or digits inserted

struct Reader {
  const char* name;
  SurfaceFormat format;  // how the samples are produced
  const char* extension;
  bool gmsh_binary = false;  // produce binary MSH through Gmsh (msh22 / msh41 = version)
};

const Reader k_readers[] = {
    {"obj", SurfaceFormat::obj, ".obj"},
    {"off", SurfaceFormat::off, ".off"},
    {"stl_ascii", SurfaceFormat::stl_ascii, ".stl"},
    {"stl_binary", SurfaceFormat::stl_binary, ".stl"},
    {"ply_ascii", SurfaceFormat::ply_ascii, ".ply"},
    {"ply_binary", SurfaceFormat::ply_binary, ".ply"},
    {"msh22_ascii", SurfaceFormat::msh22, ".msh"},
    {"msh41_ascii", SurfaceFormat::msh41, ".msh"},
    {"msh22_binary", SurfaceFormat::msh22, ".msh", true},
    {"msh41_binary", SurfaceFormat::msh41, ".msh", true},
};

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

SurfaceMesh tagged_sphere() {
  SurfaceMesh m = make_icosphere(1, 2.0);
  m.tags.resize(m.F.rows());
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) m.tags(f) = 1 + static_cast<int>(f % 3);
  m.tag_names[2] = "middle";
  return m;
}

// The bytes of `mesh` written as `reader` expects.
std::string sample_bytes(const SurfaceMesh& mesh, const Reader& reader, const fs::path& dir) {
  const fs::path path = dir / (std::string("sample_") + reader.name + reader.extension);
  write_surface(path, mesh, reader.gmsh_binary ? SurfaceFormat::msh41 : reader.format);
  if (reader.gmsh_binary) {
    const fs::path bin = dir / (std::string("sample_bin_") + reader.name + reader.extension);
    {
      GmshSession session;
      gmsh::open(path.string());
      gmsh::option::setNumber("Mesh.Binary", 1);
      gmsh::option::setNumber("Mesh.MshFileVersion",
                              reader.format == SurfaceFormat::msh22 ? 2.2 : 4.1);
      gmsh::option::setNumber("Mesh.SaveAll", 1);
      gmsh::write(bin.string());
      gmsh::option::setNumber("Mesh.Binary", 0);
      gmsh::option::setNumber("Mesh.SaveAll", 0);
    }
    return read_bytes(bin);
  }
  return read_bytes(path);
}

// A mesh returned by a reader must be structurally valid whatever the input was.
void expect_valid(const SurfaceMesh& m, const std::string& what) {
  ASSERT_EQ(m.V.cols(), 3) << what;
  ASSERT_EQ(m.F.cols(), 3) << what;
  ASSERT_GT(m.F.rows(), 0) << what;
  ASSERT_TRUE(m.tags.size() == 0 || m.tags.size() == m.F.rows()) << what;
  ASSERT_TRUE(m.V.allFinite()) << what;
  ASSERT_GE(m.F.minCoeff(), 0) << what;
  ASSERT_LT(m.F.maxCoeff(), m.V.rows()) << what;
}

struct Tally {
  int accepted = 0, rejected = 0;
};

// Reads `bytes` through `path`: success (valid mesh) or InputError; anything else fails the test.
void try_read(const fs::path& path, const std::string& bytes, const std::string& what,
              Tally& tally) {
  write_bytes(path, bytes);
  try {
    const SurfaceMesh m = read_surface(path);
    expect_valid(m, what);
    ++tally.accepted;
  } catch (const InputError&) {
    ++tally.rejected;
  } catch (const std::exception& e) {
    ADD_FAILURE() << what << ": exception other than InputError: " << e.what();
  } catch (...) {
    ADD_FAILURE() << what << ": non-std exception";
  }
}

void mutate_and_read(const std::string& sample, const std::string& label, const fs::path& path,
                     std::mt19937& rng, Tally& tally) {
  ASSERT_FALSE(sample.empty());
  std::uniform_int_distribution<std::size_t> any_len(0, sample.size() - 1);
  // Large samples (real meshes) get fewer mutations to keep the test short.
  const int divisor = static_cast<int>(std::clamp<std::size_t>(sample.size() >> 15, 1, 16));
  const int truncations = k_truncations / divisor, flips = k_flips / divisor;
  // Truncations: random lengths, plus the very short and the almost complete ones.
  for (int i = 0; i < truncations; ++i) {
    std::size_t len = any_len(rng);
    if (i < 8) len = static_cast<std::size_t>(i);
    if (i >= 8 && i < 16 && sample.size() > static_cast<std::size_t>(i - 7))
      len = sample.size() - static_cast<std::size_t>(i - 7);
    try_read(path, sample.substr(0, len), label + " truncated to " + std::to_string(len), tally);
  }
  // Flips: 1..4 bytes set to random or syntax-relevant values; or a run of digits inserted.
  static const std::string k_special = std::string("09-+.eE \n\r\t$/#") + '\0' + "\xff\x7f" + "nai";
  std::uniform_int_distribution<int> count(1, 4), byte(0, 255), coin(0, 3),
      special(0, static_cast<int>(k_special.size()) - 1), digits(1, 14);
  for (int i = 0; i < flips; ++i) {
    std::string bytes = sample;
    std::ostringstream what;
    what << label << " mutated:";
    if (coin(rng) == 0) {
      const std::size_t at = any_len(rng);
      const std::string run(static_cast<std::size_t>(digits(rng)), '9');
      bytes.insert(at, run);
      what << " inserted " << run.size() << " '9' at " << at;
    } else {
      for (int k = count(rng); k > 0; --k) {
        const std::size_t at = any_len(rng);
        const char value = coin(rng) < 2 ? k_special[static_cast<std::size_t>(special(rng))]
                                         : static_cast<char>(byte(rng));
        bytes[at] = value;
        what << " [" << at << "]=" << static_cast<int>(static_cast<unsigned char>(value));
      }
    }
    try_read(path, bytes, what.str(), tally);
  }
}

// Where the mutated files go: thousands of rewrites of one small file cost ~3 ms each on the
// build disk here and ~20 us in memory, so use /dev/shm when it exists.
class MutantFile {
 public:
  MutantFile(const fs::path& fallback_dir, const std::string& name) {
    std::error_code ec;
    if (fs::is_directory("/dev/shm", ec)) {
      m_dir = fs::path("/dev/shm") / ("curvefem-garbage-" + std::to_string(::getpid()));
      fs::create_directories(m_dir, ec);
      if (ec) m_dir.clear();
    }
    m_path = (m_dir.empty() ? fallback_dir : m_dir) / name;
  }
  ~MutantFile() {
    std::error_code ec;
    if (!m_dir.empty()) fs::remove_all(m_dir, ec);
  }
  const fs::path& path() const { return m_path; }

 private:
  fs::path m_dir, m_path;
};

class ReaderGarbage : public ::testing::TestWithParam<Reader> {};

TEST_P(ReaderGarbage, TruncatedAndFlippedFilesReadOrThrowInputError) {
  const Reader& reader = GetParam();
  const fs::path dir = test::scratch_dir(std::string("reader_garbage_") + reader.name);
  std::mt19937 rng(k_seed);
  std::vector<std::pair<std::string, SurfaceMesh>> meshes;
  meshes.emplace_back("box", make_box(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 2, 3), 1));
  meshes.emplace_back("sphere", tagged_sphere());
  if (const auto data = test::shared_data_dir()) {
    meshes.emplace_back("open_blob_1hole", read_surface(*data / "bad" / "open_blob_1hole.off"));
    meshes.emplace_back("spot", read_surface(*data / "dev" / "spot.obj"));
  } else {
    std::cout << "[ garbage  ] " << test::k_no_data_message << "\n";
  }
  const MutantFile mutant(dir, std::string("garbage") + reader.extension);
  const fs::path& path = mutant.path();
  Tally tally;
  for (const auto& [name, mesh] : meshes) {
    const std::string sample = sample_bytes(mesh, reader, dir);
    // The unmodified sample reads back.
    write_bytes(path, sample);
    ASSERT_EQ(read_surface(path).num_faces(), mesh.num_faces()) << name;
    mutate_and_read(sample, std::string(reader.name) + "/" + name, path, rng, tally);
    if (HasFailure()) break;
  }
  std::cout << "[ garbage  ] " << reader.name << ": " << tally.accepted << " accepted, "
            << tally.rejected << " rejected with InputError\n";
  EXPECT_GT(tally.rejected, 0);
}

INSTANTIATE_TEST_SUITE_P(AllReaders, ReaderGarbage, ::testing::ValuesIn(k_readers),
                         [](const ::testing::TestParamInfo<Reader>& info) {
                           return std::string(info.param.name);
                         });

}  // namespace
}  // namespace curvefem::io
