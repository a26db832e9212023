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
  explicit GmshSession(const std::string& model_name = "curvefem");
  ~GmshSession();
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace curvefem::io
