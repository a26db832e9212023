#include "meshing/core/atomic_file.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <system_error>
#include <vector>

#include "meshing/core/error.hpp"

namespace curvefem {

AtomicFile::AtomicFile(std::filesystem::path target) : m_target(std::move(target)) {
  static std::atomic<int> counter{0};
  std::filesystem::path dir = m_target.parent_path();
  if (!dir.empty() && !std::filesystem::is_directory(dir))
    throw IoError("output directory does not exist", {.file = dir.string()});
  // Keep the target's extension last: some writers (gmsh) choose the format from it.
  m_temp = m_target;
  m_temp.replace_filename(".tmp-" + std::to_string(getpid()) + "-" + std::to_string(counter++) +
                          "-" + m_target.filename().string());
}

AtomicFile::~AtomicFile() {
  if (!m_committed) {
    std::error_code ec;
    std::filesystem::remove(m_temp, ec);
  }
}

void AtomicFile::commit() {
  std::error_code ec;
  if (!std::filesystem::exists(m_temp, ec))
    throw IoError("nothing was written", {.file = m_target.string()});
  std::filesystem::rename(m_temp, m_target, ec);
  if (ec) throw IoError("cannot rename into place: " + ec.message(), {.file = m_target.string()});
  m_committed = true;
}

StagedOutputDir::StagedOutputDir(std::filesystem::path dir) : m_dir(std::move(dir)) {
  std::error_code ec;
  m_created_dir = !std::filesystem::exists(m_dir, ec);
  std::filesystem::create_directories(m_dir, ec);
  if (ec || !std::filesystem::is_directory(m_dir))
    throw IoError("cannot create output directory: " + ec.message(), {.file = m_dir.string()});
  m_staging = m_dir / (".staging-" + std::to_string(getpid()));
  std::filesystem::remove_all(m_staging, ec);
  std::filesystem::create_directory(m_staging, ec);
  if (ec)
    throw IoError("cannot create staging folder: " + ec.message(), {.file = m_staging.string()});
}

StagedOutputDir::~StagedOutputDir() {
  std::error_code ec;
  std::filesystem::remove_all(m_staging, ec);
  if (!m_committed && m_created_dir && std::filesystem::is_empty(m_dir, ec) && !ec)
    std::filesystem::remove(m_dir, ec);
}

void StagedOutputDir::commit() {
  m_committed = true;
  std::error_code ec;
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(m_staging, ec))
    files.push_back(entry.path());
  if (ec)
    throw IoError("cannot list staging folder: " + ec.message(), {.file = m_staging.string()});
  // report.json last: its presence means the directory is complete.
  std::stable_partition(files.begin(), files.end(),
                        [](const auto& p) { return p.filename() != "report.json"; });
  for (const auto& f : files) {
    std::filesystem::rename(f, m_dir / f.filename(), ec);
    if (ec)
      throw IoError("cannot move into place: " + ec.message(),
                    {.file = (m_dir / f.filename()).string()});
  }
}

void write_text_file_atomic(const std::filesystem::path& path, const std::string& text) {
  AtomicFile file(path);
  {
    std::ofstream out(file.temp_path(), std::ios::binary);
    if (!out) throw IoError("cannot open for writing", {.file = path.string()});
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.close();
    if (!out) throw IoError("write failed (disk full?)", {.file = path.string()});
  }
  file.commit();
}

}  // namespace curvefem
