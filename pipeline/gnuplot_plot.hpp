// Log-log line plots drawn by Debian's gnuplot (package gnuplot-nox): the script is written as a
// file (data inline as datablocks, so it re-plots on its own: `gnuplot study.gp`) and gnuplot is
// run on it in the script's folder. Used by `curvefem study` for study.png.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace curvefem::pipeline {

struct PlotCurve {
  std::string title;  ///< legend entry (printed literally: no enhanced-text markup)
  std::vector<double> x, y;
  int color = 1;       ///< gnuplot line colour index (1, 2, ...)
  int dash = 1;        ///< dash type: 1 solid, 2 dashed, 3 dotted, ...
  int point_type = 7;  ///< gnuplot point type
};

struct LogLogPlot {
  std::string title, xlabel, ylabel;
  std::string output = "plot.png";  ///< PNG file name, relative to the script's folder
  std::vector<PlotCurve> curves;
};

/// The gnuplot script: pngcairo when this gnuplot has it, else the libgd png terminal.
std::string gnuplot_script(const LogLogPlot& plot);

/// Runs `gnuplot SCRIPT` in `dir` (stdin and stdout /dev/null). Returns an empty string on success,
/// otherwise why not (gnuplot missing, its error output, its exit status).
std::string run_gnuplot(const std::filesystem::path& dir, const std::string& script_name);

}  // namespace curvefem::pipeline
