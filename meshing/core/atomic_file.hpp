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

/// Output directory of a subcommand, all-or-nothing: files are written into a hidden staging
/// folder inside `dir` and moved into `dir` by commit() (report.json, if staged, moved last). If
/// the run fails before commit(), the staging folder is removed and `dir` holds no new file; a
/// `dir` this object created is removed too when it is left empty.
class StagedOutputDir {
 public:
  explicit StagedOutputDir(std::filesystem::path dir);
  ~StagedOutputDir();
  StagedOutputDir(const StagedOutputDir&) = delete;
  StagedOutputDir& operator=(const StagedOutputDir&) = delete;

  /// Where to write file `name` now (inside the staging folder).
  std::filesystem::path path(const std::string& name) const { return m_staging / name; }
  /// Where file `name` will be after commit().
  std::filesystem::path final_path(const std::string& name) const { return m_dir / name; }
  const std::filesystem::path& dir() const { return m_dir; }
  void commit();

 private:
  std::filesystem::path m_dir;
  std::filesystem::path m_staging;
  bool m_created_dir = false;
  bool m_committed = false;
};

/// Writes `text` to `path` atomically (throws IoError).
void write_text_file_atomic(const std::filesystem::path& path, const std::string& text);

}  // namespace curvefem
