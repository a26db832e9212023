#include "meshing/core/atomic_file.hpp"

#include <unistd.h>

#include <atomic>
#include <fstream>
#include <system_error>

#include "meshing/core/error.hpp"

namespace curvefem {

AtomicFile::AtomicFile(std::filesystem::path target) : m_target(std::move(target)) {
  static std::atomic<int> counter{0};
  std::filesystem::path dir = m_target.parent_path();
  if (!dir.empty() && !std::filesystem::is_directory(dir))
    throw IoError("output directory does not exist", {.file = dir.string()});
  // Keep the target's extension last: some writers (gmsh) choose the format from it.
  m_temp = m_target;
  m_temp.replace_filename(".tmp-" + std::to_string(getpid()) + "-" +
                          std::to_string(counter++) + "-" + m_target.filename().string());
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
