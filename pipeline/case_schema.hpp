// The case schema as data: one table of every key a case file may hold (its JSON path, type,
// default, allowed values or range, and its documentation). It drives
//   - the case parser (pipeline/case_file.cpp): the keys accepted in every object of a case are
//     exactly the children of that object's path in this table, and enums and numeric ranges are
//     checked against it where the parser says so;
//   - cases/README.md's key table, which is generated (`curvefem schema --markdown`, or
//     `curvefem schema --update cases/README.md`) between `<!-- schema:begin -->` and
//     `<!-- schema:end -->`; a test fails when the two differ;
//   - the Python module's `curvefem.schema()`.
//
// Paths: dot-separated object keys from the case's root; a component ending in `[]` is an array
// whose elements are objects with the keys below it ("boundary_conditions[].select.box"). The
// selection keys under "boundary_conditions[].select" also apply to nested selections (and, or,
// not) and to the boundary conditions of load_cases. Defaults are JSON text, as resolved_case.json
// writes them (a test parses minimal cases and compares); a key without a fixed default (required,
// optional or depending on other keys) has none and a `default_text` saying what happens.
#pragma once

#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace curvefem::pipeline {

/// What a key holds (for tools and Python; the parser checks the details).
enum class CaseKeyType {
  object,       ///< a JSON object (a section, or a parameter object)
  array,        ///< a JSON array
  string,       ///< a string (with `allowed`: one of them)
  number,       ///< a real number
  integer,      ///< an integer
  boolean,      ///< true / false
  path,         ///< a file or folder, relative to the case file's folder
  expression,   ///< a muparser expression (string or number), or an array of three
  selection,    ///< a boundary selection object (exactly one kind)
  number_list,  ///< a number or an array of numbers
  any,          ///< several forms (see the documentation)
};

/// Numeric bounds; an infinite bound is absent.
struct CaseKeyRange {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false, hi_open = false;
  /// "(0, 0.5]", "1..4" (integers), "> 0" (one bound).
  std::string text(bool integer) const;
  bool contains(double v) const;
};

/// A rule between two keys: the key it belongs to applies only while another key of the table,
/// resolved (given, or its default), equals one of `values`, or — with `values` empty — is given
/// (`given` true) or absent (`given` false). A path below the same `[]` as the key refers to the
/// same array element. A key whose rules do not all hold is refused when given (with the first
/// failing rule's `error`) and is absent from resolved_case.json.
struct CaseKeyWhen {
  std::string_view path;                 ///< the other key ("meshing.method")
  std::vector<std::string_view> values;  ///< JSON texts ("\"curved\""); empty: presence
  bool given = true;                     ///< with `values` empty: must be given / absent
  std::string_view error;                ///< "only for method \"curved\""
};

/// A default that depends on other keys: the first entry of a key's `defaults` whose rules all
/// hold (an entry without rules always does) gives the key's value.
struct CaseKeyDefault {
  std::vector<CaseKeyWhen> when;
  std::string_view value;  ///< JSON text
};

struct CaseKey {
  std::string_view path;  ///< "meshing.eps"
  CaseKeyType type = CaseKeyType::any;
  std::string_view default_json;          ///< "" = no fixed default
  std::vector<std::string_view> allowed;  ///< string values allowed (empty: any)
  std::optional<CaseKeyRange> range;      ///< numeric bounds (numbers, integers, list elements)
  std::string_view range_note;            ///< appended to the range error ("(0: off)")
  std::vector<CaseKeyWhen> when;          ///< the key applies only where all of these hold
  std::vector<CaseKeyDefault> defaults;  ///< defaults depending on other keys (before default_json)
  std::string_view default_from;         ///< else: the resolved value of this other key
};

/// One row of the documented table: one key, or several documented together
/// (`physics.E`, `physics.nu`).
struct CaseKeyRow {
  std::vector<CaseKey> keys;
  std::string_view type;          ///< Markdown: the type column
  std::string_view default_text;  ///< Markdown; "" = the keys' default_json (or "—" without)
  std::string_view doc;           ///< Markdown: the meaning column
};

/// Every row, in the documented order.
const std::vector<CaseKeyRow>& case_schema();

/// The key at `path`; throws curvefem::Error when the table has no such key.
const CaseKey& case_key(std::string_view path);

/// The keys allowed in the object at schema path `section` ("" = the case's root, "meshing",
/// "boundary_conditions[]", "boundary_conditions[].select"): the next component of every path
/// below it, without `[]`.
std::set<std::string> case_section_keys(std::string_view section);

/// The Markdown key table (header and rows), as in cases/README.md between the markers.
std::string case_schema_markdown();

/// The table as a JSON array of objects {path, type, default (JSON or null), default_text,
/// allowed, minimum, maximum, minimum_exclusive, maximum_exclusive, type_text, doc}; one object
/// per key (the rows' documentation repeated for keys documented together).
nlohmann::json case_schema_json();

/// "boundary_conditions[].select.box" → {"boundary_conditions[]", "select", "box"}.
std::vector<std::string> case_path_components(std::string_view path);

/// The case `given` (a case file's JSON) resolved by the table: every section and every key that
/// applies (its rules hold), with its given value (passed through `normalize`, which may rewrite
/// paths or expressions) or its default (`defaults`, `default_json`, `default_from`, in that
/// order); keys without a value stay absent. Objects of keys with children in the table
/// (builtin_surface, features as an object) and the elements of `[]` arrays are resolved key by
/// key; selections are copied (the parser reads them). Throws InputError naming the JSON path (and
/// `file`) for an unknown key, a non-object where keys are expected, a bad value of a key other
/// rules depend on, or a key given where one of its rules does not hold. Checks no other value:
/// the parser reads the resolved case.
nlohmann::json resolve_case(
    const nlohmann::json& given, const std::string& file,
    const std::function<nlohmann::json(const CaseKey&, const nlohmann::json&)>& normalize = {});

inline constexpr std::string_view k_schema_begin = "<!-- schema:begin -->";
inline constexpr std::string_view k_schema_end = "<!-- schema:end -->";

/// The study file of `curvefem study` as a table of the same form (paths from the study's root;
/// `sweep` holds JSON pointers into the case, not fixed keys): it gives the keys study_file.cpp
/// accepts and the table of cases/README.md's "Studies" between the study markers.
const std::vector<CaseKeyRow>& study_schema();
std::set<std::string> study_section_keys(std::string_view section);
/// The study key at `path`; throws curvefem::Error when the study table has no such key.
const CaseKey& study_key(std::string_view path);
std::string study_schema_markdown();
nlohmann::json study_schema_json();

inline constexpr std::string_view k_study_schema_begin = "<!-- study-schema:begin -->";
inline constexpr std::string_view k_study_schema_end = "<!-- study-schema:end -->";

/// `readme` with the part between the markers replaced by a blank line, `table` and a blank
/// line; throws curvefem::Error if a marker is missing.
std::string replace_schema_block(const std::string& readme, const std::string& table,
                                 std::string_view begin_marker = k_schema_begin,
                                 std::string_view end_marker = k_schema_end);

std::string_view to_string(CaseKeyType t);

}  // namespace curvefem::pipeline
