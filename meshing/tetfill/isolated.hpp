// Running a piece of work in a forked child process, so that a crash in it (a failed assertion in
// gmsh 4.8's boundary recovery, abort(), a segfault) becomes a MeshingError in the caller instead
// of killing the process. fill_interior uses it for gmsh when TetFillOptions::isolate is set;
// declared here (detail) so that tests exercise the same code path. POSIX only (fork, pipe).
//
// Protocol: the child runs `body`, which returns a byte string (the caller serializes its
// result), writes one tag byte ('\0' success, '\1' error) and then the payload or the error text
// to a pipe, and leaves with _exit (the parent's destructors and atexit handlers never run in the
// child; stdout/stderr are flushed before the fork so nothing is printed twice). The parent reads
// the pipe to its end before waiting for the child, so payloads of any size (larger than the pipe
// buffer) do not deadlock.
#pragma once

#include <functional>
#include <string>

namespace curvefem::meshing::tetfill::detail {

/// The texts of the MeshingErrors that run_isolated raises itself (errors thrown by `body` keep
/// their own text):
///   crash (signal):      failed + name + " crashed (signal " + N + " " + strsignal(N) + note + ")"
///   other child exit:    failed + "the " + name + " child process exited with status " + S
///   non-std exception:   failed + "unknown error in " + name
///   pipe/fork failure:   failed + "cannot create a pipe: ..." / "cannot fork: ..."
struct IsolationText {
  std::string failed = "isolated run failed: ";
  std::string name = "worker";
  std::string note;  ///< e.g. "; gmsh 4.8's boundary recovery aborts on ..."
};

/// Runs `body` in a forked child process and returns the bytes it returned, unchanged.
/// A std::exception thrown by `body` in the child is rethrown here as MeshingError(e.what())
/// (the type is not kept); a child killed by a signal, or one that exits without reporting
/// (e.g. calls exit()), throws MeshingError with the texts of `text`. Side effects of `body` on
/// memory stay in the child. Blocks until the child has exited.
std::string run_isolated(const std::function<std::string()>& body, const IsolationText& text = {});

}  // namespace curvefem::meshing::tetfill::detail
