// RAII access to the Gmsh API, which is global state and not thread-safe (STYLE.md).
//
// A GmshSession holds a process-wide mutex for its lifetime, initializes gmsh on first use
// (terminal output off, verbosity from the log level) and clears the model on destruction, so
// every user starts from an empty model. gmsh.h itself is only included in .cpp files.
#pragma once

#include <memory>
#include <string>

namespace curvefem::io {

class GmshSession {
 public:
  /// new_model: start from an empty model named model_name, cleared again on destruction.
  /// keep_model: only lock and initialize, leaving any current model alone (for queries such as
  /// element properties made while an outer session builds a model on the same thread).
  enum class Mode { new_model, keep_model };
  explicit GmshSession(const std::string& model_name = "curvefem", Mode mode = Mode::new_model);
  ~GmshSession();
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace curvefem::io
