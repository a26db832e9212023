// Errors with context, and the always-on / debug-only check macros.
//
// Convention (STYLE.md "Errors"): bad input, missing files and failed algorithms are typed
// exceptions carrying context (file, line or byte offset, vertex/face/element id). They are caught
// once, in the tool's main, which prints one line and returns the exit code of DESIGN.md §3:
//   InputError 2, MeshingError 3, SolverError 3, IoError 4, any other Error 3.
// An invariant rejecting a local operation is data (return false), never an exception.
#pragma once

#include <stdexcept>
#include <string>

namespace curvefem {

/// Where a defect is. Every field is optional (negative / empty = unknown).
struct ErrorContext {
  std::string file;
  long long line = -1;         ///< 1-based line in a text file
  long long byte_offset = -1;  ///< 0-based offset in a binary file
  long long vertex = -1;       ///< 0-based vertex id
  long long face = -1;         ///< 0-based face id
  long long element = -1;      ///< 0-based element (cell) id

  /// "file:line: " / "file: byte 12: " prefix, empty if nothing is known.
  std::string location_prefix() const;
  /// " (vertex 3, face 7)" suffix, empty if no id is known.
  std::string id_suffix() const;
};

class Error : public std::runtime_error {
 public:
  Error(const std::string& what, ErrorContext context = {});
  const ErrorContext& context() const { return m_context; }
  /// The message without location decorations.
  const std::string& defect() const { return m_defect; }
  virtual int exit_code() const { return 3; }

 private:
  ErrorContext m_context;
  std::string m_defect;
};

/// Invalid input: malformed file, invalid mesh, invalid case. Exit code 2.
class InputError : public Error {
 public:
  using Error::Error;
  int exit_code() const override { return 2; }
};

/// A meshing algorithm could not meet its guarantees. Exit code 3.
class MeshingError : public Error {
 public:
  using Error::Error;
  int exit_code() const override { return 3; }
};

/// Factorization failure, non-convergence, inverted element during a solve. Exit code 3.
class SolverError : public Error {
 public:
  using Error::Error;
  int exit_code() const override { return 3; }
};

/// A file could not be opened, written or renamed. Exit code 4.
class IoError : public Error {
 public:
  using Error::Error;
  int exit_code() const override { return 4; }
};

namespace detail {
[[noreturn]] void verify_failed(const char* cond, const std::string& msg, const char* file,
                                int line);
}  // namespace detail

}  // namespace curvefem

/// Always-on check; throws curvefem::Error("file:line: check `cond` failed: msg").
#define CF_VERIFY(cond, msg)                                                          \
  do {                                                                                \
    if (!(cond)) ::curvefem::detail::verify_failed(#cond, (msg), __FILE__, __LINE__); \
  } while (0)

/// Internal invariant, compiled out when NDEBUG is defined (Release, RelWithDebInfo).
#ifdef NDEBUG
#define CF_ASSERT(cond, msg) \
  do {                       \
  } while (0)
#else
#define CF_ASSERT(cond, msg) CF_VERIFY(cond, msg)
#endif
