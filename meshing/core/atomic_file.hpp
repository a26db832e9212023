// Atomic file output: write to "<target>.tmp-<pid>-<n>" in the same directory, then rename over
// the target on commit(). If the writer is destroyed without commit() (an exception, a failed
// check), the temporary file is removed and the target is untouched: no partial output, ever.
#pragma once

#include <filesystem>
#include <string>

namespace curvefem {

class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path target);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// Where to write (any API that takes a file name: std::ofstream, VTK, gmsh).
  const std::filesystem::path& temp_path() const { return m_temp; }
  const std::filesystem::path& target() const { return m_target; }
  /// Renames the temporary file onto the target; throws IoError on failure.
  void commit();

 private:
  std::filesystem::path m_target;
  std::filesystem::path m_temp;
  bool m_committed = false;
};

/// Writes `text` to `path` atomically (throws IoError).
void write_text_file_atomic(const std::filesystem::path& path, const std::string& text);

}  // namespace curvefem
