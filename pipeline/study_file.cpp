#include "pipeline/study_file.hpp"

#include <algorithm>
#include <fstream>
#include <map>
#include <set>

#include "meshing/core/error.hpp"
#include "pipeline/case_schema.hpp"

namespace curvefem::pipeline {
namespace {

using json = nlohmann::json;
using ordered_json = nlohmann::ordered_json;

[[noreturn]] void fail(const std::string& path, const std::string& what,
                       const std::filesystem::path& file) {
  throw InputError((path.empty() ? std::string("/") : path) + ": " + what, {.file = file.string()});
}

/// "/sweep/<key>" with the key escaped as a JSON pointer token (RFC 6901: ~ → ~0, / → ~1).
std::string sweep_path(const std::string& key) {
  std::string token;
  for (const char c : key) {
    if (c == '~')
      token += "~0";
    else if (c == '/')
      token += "~1";
    else
      token += c;
  }
  return "/sweep/" + token;
}

/// A folder-name-safe version of `text`: anything but [A-Za-z0-9._=+-] becomes '-'.
std::string folder_safe(const std::string& text) {
  std::string out = text;
  for (char& c : out) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == '_' || c == '=' || c == '+' || c == '-';
    if (!ok) c = '-';
  }
  return out;
}

/// Column names of study.csv that a sweep key may not take (degree and order may: they are the
/// same quantity as the report's).
const std::set<std::string>& reserved_names() {
  static const std::set<std::string> names = {"name",
                                              "status",
                                              "exit_code",
                                              "dofs",
                                              "tets",
                                              "l2_error",
                                              "h1_semi_error",
                                              "h1_error",
                                              "message",
                                              "meshing_s",
                                              "solve_s",
                                              "total_s",
                                              "surface_l2_error",
                                              "surface_max_error"};
  return names;
}

json parse_base_file(const std::filesystem::path& base, const std::filesystem::path& study) {
  std::ifstream in(base);
  if (!in) fail("/base", "cannot open case file " + base.string(), study);
  try {
    return json::parse(in);
  } catch (const json::parse_error& e) {
    fail("/base", "invalid JSON in " + base.string() + ": " + e.what(), study);
  }
}

}  // namespace

std::string sweep_value_text(const json& value) {
  return value.is_string() ? value.get<std::string>() : value.dump();
}

StudySpec read_study(const std::filesystem::path& file, const std::string& output_override) {
  std::ifstream in(file);
  if (!in) throw IoError("cannot open study file", {.file = file.string()});
  ordered_json j;
  try {
    j = ordered_json::parse(in);
  } catch (const ordered_json::parse_error& e) {
    throw InputError(std::string("invalid JSON: ") + e.what(), {.file = file.string()});
  }
  return read_study_json(j, file, output_override);
}

StudySpec read_study_json(const ordered_json& j, const std::filesystem::path& file,
                          const std::string& output_override) {
  if (!j.is_object()) fail("", "expected an object with \"base\" and \"sweep\"", file);
  // The keys of an object, from the study table (case_schema.hpp).
  auto only_keys = [&](const ordered_json& o, const std::string& path, std::string_view section) {
    const std::set<std::string> allowed = study_section_keys(section);
    for (const auto& [key, value] : o.items())
      if (!allowed.count(key)) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(path + "/" + key, "unknown key (allowed here: " + list + ")", file);
      }
  };
  only_keys(j, "", "");

  StudySpec s;
  s.file = file;
  const auto folder = file.parent_path();
  auto resolve = [&](const std::string& p) {
    return std::filesystem::path(p).is_absolute() ? std::filesystem::path(p) : folder / p;
  };
  if (j.contains("description")) {
    if (!j["description"].is_string()) fail("/description", "expected a string", file);
    s.description = j["description"].get<std::string>();
  }

  // Base case: a case file (relative to the study file) or an inline case object.
  if (!j.contains("base"))
    fail("/base", "missing (a case file, e.g. \"ball_poisson_p3.json\", or an inline case)", file);
  json base;
  if (j["base"].is_string()) {
    s.base_file = resolve(j["base"].get<std::string>());
    base = parse_base_file(s.base_file, file);
  } else if (j["base"].is_object()) {
    s.base_file = file;
    base = json::parse(j["base"].dump());
  } else {
    fail("/base", "expected a case file name or an inline case object", file);
  }
  CaseSpec base_spec;
  try {
    base_spec = read_case_json(base, s.base_file, "unused");
  } catch (const InputError& e) {
    // Inline: the defect's path continues under /base; a file: name it.
    if (s.base_file == file) {
      const std::string d = e.defect();
      throw InputError(d.rfind("/:", 0) == 0  ? "/base" + d.substr(1)
                       : d.rfind('/', 0) == 0 ? "/base" + d
                                              : "/base: " + d,
                       {.file = file.string()});
    }
    fail("/base", "not a valid case: " + std::string(e.what()), file);
  }
  if (base_spec.exact.empty())
    fail("/base", "the case has no exact solution (key \"exact\"): a study fits error rates", file);

  // Sweep: {"/json/pointer": [values...], ...} in file order.
  if (!j.contains("sweep"))
    fail("/sweep", "missing (e.g. {\"/discretization/degree\": [1, 2, 3]})", file);
  const ordered_json& sweep = j["sweep"];
  if (!sweep.is_object() || sweep.empty())
    fail("/sweep", "expected a non-empty object {\"/json/pointer\": [values...]}", file);
  for (const auto& [key, values] : sweep.items()) {
    const std::string path = sweep_path(key);
    if (key.empty() || key[0] != '/')
      fail(path, "'" + key + "' is not a JSON pointer into the case (e.g. /discretization/degree)",
           file);
    json::json_pointer pointer;
    try {
      pointer = json::json_pointer(key);
    } catch (const json::exception& e) {
      fail(path, "'" + key + "' is not a valid JSON pointer: " + e.what(), file);
    }
    if (key == "/output" || key.rfind("/output/", 0) == 0)
      fail(path, "the output folder of each run is set by the study", file);
    if (!values.is_array() || values.empty())
      fail(path, "expected a non-empty array of values", file);
    SweepKey k;
    k.pointer = key;
    for (std::size_t i = 0; i < values.size(); ++i) {
      const auto& v = values[i];
      const std::string vp = path + "/" + std::to_string(i);
      if (!(v.is_number() || v.is_string() || v.is_boolean()))
        fail(vp, "expected a number, string or boolean", file);
      json value = json::parse(v.dump());
      for (const auto& previous : k.values)
        if (previous == value) fail(vp, "duplicate value " + value.dump(), file);
      k.values.push_back(std::move(value));
    }
    s.sweep.push_back(std::move(k));
  }
  // Labels: the pointer's last token unless two keys share it or it is a fixed CSV column.
  std::map<std::string, int> uses;
  auto last_token = [](const std::string& p) { return json::json_pointer(p).back(); };
  for (const auto& k : s.sweep) ++uses[last_token(k.pointer)];
  for (auto& k : s.sweep) {
    k.name = last_token(k.pointer);
    if (k.name.empty() || uses[k.name] > 1 || reserved_names().count(k.name)) {
      k.name = k.pointer.substr(1);
      std::replace(k.name.begin(), k.name.end(), '/', '.');
    }
  }

  // The key along which each curve runs (default: the last one).
  s.refine = static_cast<int>(s.sweep.size()) - 1;
  if (j.contains("refine")) {
    if (!j["refine"].is_string())
      fail("/refine", "expected a sweep key (its JSON pointer or its name)", file);
    const std::string r = j["refine"].get<std::string>();
    s.refine = -1;
    for (std::size_t i = 0; i < s.sweep.size(); ++i)
      if (s.sweep[i].pointer == r || s.sweep[i].name == r) s.refine = static_cast<int>(i);
    if (s.refine < 0) fail("/refine", "'" + r + "' is not a key of /sweep", file);
  }
  if (j.contains("x")) {
    const auto& allowed = study_key("x").allowed;
    std::string list;
    for (const auto a : allowed) list += (list.empty() ? "" : " or ") + std::string(a);
    if (!j["x"].is_string()) fail("/x", "expected " + list, file);
    s.x = j["x"].get<std::string>();
    if (std::find(allowed.begin(), allowed.end(), s.x) == allowed.end())
      fail("/x", "'" + s.x + "': expected " + list, file);
  }
  std::string out = "out/" + file.stem().string();
  if (j.contains("output")) {
    const ordered_json& o = j["output"];
    if (!o.is_object()) fail("/output", "expected an object {\"dir\": ...}", file);
    only_keys(o, "/output", "output");
    if (o.contains("dir")) {
      if (!o["dir"].is_string()) fail("/output/dir", "expected a string", file);
      out = o["dir"].get<std::string>();
    }
  }
  s.output_dir = output_override.empty() ? resolve(out) : std::filesystem::path(output_override);

  // Runs: the cartesian product, first key outermost; each case is validated now.
  std::size_t total = 1;
  for (const auto& k : s.sweep) total *= k.values.size();
  if (total > 10000) fail("/sweep", "more than 10000 runs", file);
  std::set<std::string> names;
  for (std::size_t r = 0; r < total; ++r) {
    StudyRun run;
    std::size_t rest = r;
    std::vector<std::size_t> index(s.sweep.size());
    for (std::size_t i = s.sweep.size(); i-- > 0;) {
      index[i] = rest % s.sweep[i].values.size();
      rest /= s.sweep[i].values.size();
    }
    json c = base;
    for (std::size_t i = 0; i < s.sweep.size(); ++i) {
      const SweepKey& k = s.sweep[i];
      const json& value = k.values[index[i]];
      const std::string vp = sweep_path(k.pointer) + "/" + std::to_string(index[i]);
      try {
        c[json::json_pointer(k.pointer)] = value;
      } catch (const json::exception& e) {
        fail(vp, "cannot set " + k.pointer + " in the case: " + e.what(), file);
      }
      run.values.push_back(value);
      run.name +=
          (run.name.empty() ? "" : "_") + folder_safe(k.name + "=" + sweep_value_text(value));
    }
    if (!names.insert(run.name).second)
      fail(sweep_path(s.sweep.back().pointer),
           "two runs get the same folder name '" + run.name + "'", file);
    const auto dir = s.output_dir / "runs" / run.name;
    try {
      run.spec = read_case_json(c, s.base_file, dir.string());
    } catch (const InputError& e) {
      // Name the sweep value that made the case invalid: the key whose pointer is closest to the
      // defect's JSON path (the first key if none is related).
      const std::string defect = e.defect();
      const std::string where = defect.substr(0, defect.find(':'));
      std::size_t culprit = 0, best = 0;
      for (std::size_t i = 0; i < s.sweep.size(); ++i) {
        const std::string& p = s.sweep[i].pointer;
        const bool related = where.rfind(p, 0) == 0 || p.rfind(where, 0) == 0;
        const std::size_t depth = std::min(p.size(), where.size());
        if (related && depth > best) culprit = i, best = depth;
      }
      std::string which;
      for (std::size_t i = 0; i < s.sweep.size(); ++i)
        which += (which.empty() ? "" : ", ") + s.sweep[i].pointer + " = " +
                 s.sweep[i].values[index[i]].dump();
      fail(sweep_path(s.sweep[culprit].pointer) + "/" + std::to_string(index[culprit]),
           "the run with " + which + " is not a valid case: " + defect, file);
    }
    s.runs.push_back(std::move(run));
  }

  // Resolved study, for study.json.
  ordered_json sw = ordered_json::object();
  for (const auto& k : s.sweep) {
    ordered_json values = ordered_json::array();
    for (const auto& v : k.values) values.push_back(ordered_json::parse(v.dump()));
    sw[k.pointer] = values;
  }
  ordered_json res;
  res["study"] = file.string();
  if (!s.description.empty()) res["description"] = s.description;
  res["base"] = s.base_file == file ? std::string("inline") : s.base_file.string();
  res["sweep"] = sw;
  res["refine"] = s.sweep[s.refine].pointer;
  res["x"] = s.x;
  res["output"] = {{"dir", s.output_dir.string()}};
  s.resolved = res;
  return s;
}

}  // namespace curvefem::pipeline
