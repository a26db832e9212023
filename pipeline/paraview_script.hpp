// open_in_paraview.py, written by `curvefem run --paraview`: a ParaView Python state script
// (paraview.simple, ParaView ≥ 5.9) that opens volume.vtu — and surface.vtu for the dense-surface
// methods — colours them by the solution (u, or the magnitude of the displacement), shows the
// error on the input surface when an exact solution is known, and resets the camera.
// Run it with `paraview --script=open_in_paraview.py` or `pvpython open_in_paraview.py`; it finds
// the VTU files next to itself (or, without __file__, in the directory it was written for).
#pragma once

#include <filesystem>
#include <string>

namespace curvefem::pipeline {

struct ParaviewScriptOptions {
  std::filesystem::path dir;  ///< absolute output directory (fallback when __file__ is unset)
  std::string field = "u";    ///< solution point field: "u" or "displacement"
  int components = 1;         ///< 1 (scalar) or 3 (coloured by magnitude)
  bool surface = false;       ///< surface.vtu exists (methods curved and dense)
  bool exact = false;         ///< volume.vtu and surface.vtu hold `exact` and `error`
};

/// The text of the script (UTF-8, ends with a newline).
std::string paraview_state_script(const ParaviewScriptOptions& options);

/// `text` as a single-quoted Python string literal (backslashes, quotes, control characters
/// escaped).
std::string python_string_literal(const std::string& text);

}  // namespace curvefem::pipeline
