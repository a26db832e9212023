// Study files of `curvefem study` (format in cases/README.md, "Studies"; the keys are the study
// table of case_schema.hpp): a base case with an exact solution, and a sweep — JSON pointers into
// the case, each with a list of values; the runs are the cartesian product (first key
// outermost). Parsing is strict and complete before anything runs: every run's case is built and
// validated with the case-file reader, so a bad study is an InputError naming its JSON path (e.g.
// "/sweep/~1discretization~1degree/2: 7 gives an invalid case: /discretization/degree: must be in
// 1..4"; a "/" inside a key is "~1", RFC 6901).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pipeline/case_file.hpp"

namespace curvefem::pipeline {

/// One swept parameter.
struct SweepKey {
  std::string pointer;  ///< JSON pointer into the case, e.g. "/discretization/degree"
  std::string name;     ///< label: the pointer's last token, the dotted pointer on a clash
  std::vector<nlohmann::json> values;  ///< scalars (numbers, strings, booleans), distinct
};

/// One run: a value per sweep key.
struct StudyRun {
  std::string name;                    ///< folder under runs/: "degree=1_divisions=4"
  std::vector<nlohmann::json> values;  ///< one per sweep key, in sweep order
  CaseSpec spec;                       ///< validated case; output_dir = <study dir>/runs/<name>
};

struct StudySpec {
  std::filesystem::path file;        ///< the study file
  std::filesystem::path base_file;   ///< case file of the base (the study file for an inline base)
  std::string description;           ///< optional free text
  std::vector<SweepKey> sweep;       ///< in file order
  int refine = 0;                    ///< index into sweep: the key that varies along a curve
  std::string x = "dofs";            ///< plot axis and legend rate: dofs | tets
  std::filesystem::path output_dir;  ///< resolved
  std::vector<StudyRun> runs;        ///< cartesian product, first sweep key outermost
  nlohmann::ordered_json resolved;   ///< the study with defaults (echoed into study.json)
};

/// Reads and validates a study file; `output_override` replaces output.dir when non-empty.
StudySpec read_study(const std::filesystem::path& file, const std::string& output_override = {});

/// The same for a study already parsed (e.g. a Python dict); `file` plays the study file's role:
/// errors name it, relative paths (base, output.dir) resolve against its folder, and the default
/// output folder is out/<its stem>.
StudySpec read_study_json(const nlohmann::ordered_json& j, const std::filesystem::path& file,
                          const std::string& output_override = {});

/// The text of a sweep value as used in run names and CSV cells: numbers as JSON writes them
/// (shortest round trip: 0.35, 1e-05), strings without quotes, true/false.
std::string sweep_value_text(const nlohmann::json& value);

}  // namespace curvefem::pipeline
