// The case schema as data (pipeline/case_schema.hpp): the table is consistent, its defaults are
// the parser's (resolved_case.json of minimal cases), the parser accepts exactly its keys and
// checks its enums and ranges, and cases/README.md's key table is the generated one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "meshing/core/error.hpp"
#include "pipeline/case_file.hpp"
#include "pipeline/case_schema.hpp"
#include "tests/support/test_support.hpp"

using namespace curvefem;
using namespace curvefem::pipeline;
using json = nlohmann::json;

namespace {

std::vector<std::string> split(std::string_view path) { return case_path_components(path); }

/// The value at schema path `path` in `j` (first element of every `[]` array before the last
/// component; the array itself for a last `[]` component), or nullptr.
const json* lookup(const json& j, std::string_view path) {
  const json* at = &j;
  const auto parts = split(path);
  for (std::size_t i = 0; i < parts.size(); ++i) {
    std::string key = parts[i];
    const bool array = key.size() > 2 && key.substr(key.size() - 2) == "[]";
    if (array) key.resize(key.size() - 2);
    if (!at->is_object() || !at->contains(key)) return nullptr;
    at = &(*at)[key];
    if (array && i + 1 < parts.size()) {
      if (!at->is_array() || at->empty()) return nullptr;
      at = &(*at)[0];
    }
  }
  return at;
}

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The InputError message of reading `j`, or "" when it reads.
std::string error_of(const json& j) {
  try {
    // One folder per test: ctest runs this file's tests as parallel processes, and scratch_dir
    // empties the folder it returns.
    const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    read_case_json(j, test::scratch_dir("case_schema_" + name) / "case.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

/// A curved exterior case on the built-in sphere solved on both sides (so that every physics and
/// meshing key applies).
json sphere_case(const std::string& physics) {
  return {{"geometry", {{"builtin_surface", {{"shape", "sphere"}}}}},
          {"meshing", {{"exterior", true}, {"solve_on", "both"}}},
          {"physics", {{"type", physics}}}};
}

}  // namespace

TEST(CaseSchema, TableIsConsistent) {
  std::set<std::string> paths;
  for (const CaseKeyRow& row : case_schema()) {
    ASSERT_FALSE(row.keys.empty());
    EXPECT_FALSE(row.type.empty()) << row.keys[0].path;
    EXPECT_FALSE(row.doc.empty()) << row.keys[0].path;
    // Every allowed value is documented in the row.
    const std::string text =
        std::string(row.type) + " " + std::string(row.default_text) + " " + std::string(row.doc);
    for (const CaseKey& k : row.keys) {
      SCOPED_TRACE(std::string(k.path));
      EXPECT_TRUE(paths.insert(std::string(k.path)).second) << "two rows for the key";
      const auto parts = split(k.path);
      if (parts.size() > 1) {  // the parent is a key of its own, or a top-level section
        std::string parent(k.path.substr(0, k.path.rfind('.')));
        if (parts.size() > 2 || parent.find("[]") != std::string::npos)
          EXPECT_NO_THROW(case_key(parent)) << "no row for the parent " << parent;
      }
      for (const auto a : k.allowed)
        EXPECT_NE(text.find(std::string(a)), std::string::npos)
            << "allowed value '" << a << "' is not in the row's documentation";
      if (k.default_json.empty()) continue;
      json d;
      ASSERT_NO_THROW(d = json::parse(k.default_json)) << k.default_json;
      if (k.range && d.is_number()) {
        EXPECT_TRUE(k.range->contains(d.get<double>())) << "default outside the range";
      }
      if (!k.allowed.empty() && d.is_string())
        EXPECT_NE(std::find(k.allowed.begin(), k.allowed.end(), d.get<std::string>()),
                  k.allowed.end())
            << "default not among the allowed values";
    }
  }
  EXPECT_THROW(case_key("meshing.not_a_key"), Error);
}

// Minimal cases (only what each needs), read; wherever the resolved case holds a key the case did
// not give and the table has a default for, the two agree; every such key is checked somewhere.
TEST(CaseSchema, DefaultsAreTheResolvedCasesDefaults) {
  const json dirichlet_vector =
      json::array({{{"type", "dirichlet"}, {"select", {{"all", true}}}, {"value", {0, 0, 0}}}});
  const json normal_neumann = json::array(
      {{{"type", "neumann"}, {"select", {{"normal", {{"direction", {0, 0, 1}}}}}}, {"value", 1}}});
  const std::vector<json> minimal = {
      {{"geometry", {{"builtin", {{"shape", "cube"}}}}}},
      {{"geometry", {{"builtin", {{"shape", "ball"}}}}}},
      {{"geometry", {{"builtin_surface", {{"shape", "sphere"}}}}}},
      {{"geometry", {{"builtin_surface", {{"shape", "torus"}}}}}},
      {{"geometry", {{"builtin_surface", {{"shape", "box"}}}}}},
      {{"geometry", {{"builtin_surface", {{"shape", "sphere"}}}}},
       {"meshing", {{"exterior", true}}}},
      {{"geometry", {{"builtin", {{"shape", "cube"}}}}},
       {"physics", {{"type", "linear_elasticity"}}},
       {"boundary_conditions", dirichlet_vector}},
      {{"geometry", {{"builtin", {{"shape", "cube"}}}}}, {"physics", {{"type", "neo_hookean"}}}},
      {{"geometry", {{"builtin_surface", {{"shape", "sphere"}}}}},
       {"boundary_conditions", normal_neumann}},
      {{"geometry", {{"builtin", {{"shape", "cube"}}}}},
       {"load_cases", json::array({{{"name", "a"}}})}},
  };
  const auto dir = test::scratch_dir("case_schema_defaults");
  std::map<std::string, int> checked;
  for (const json& m : minimal) {
    SCOPED_TRACE(m.dump());
    CaseSpec c;
    ASSERT_NO_THROW(c = read_case_json(m, dir / "case.json"));
    for (const CaseKeyRow& row : case_schema())
      for (const CaseKey& k : row.keys) {
        if (k.default_json.empty()) continue;
        const json* given = lookup(m, k.path);
        const json* resolved = lookup(c.resolved, k.path);
        if (given || !resolved) continue;
        json expected = json::parse(k.default_json);
        if (k.type == CaseKeyType::path)  // relative to the case file's folder
          expected = (dir / expected.get<std::string>()).string();
        EXPECT_EQ(*resolved, expected) << k.path;
        ++checked[std::string(k.path)];
      }
  }
  for (const CaseKeyRow& row : case_schema())
    for (const CaseKey& k : row.keys)
      if (!k.default_json.empty())
        EXPECT_GT(checked[std::string(k.path)], 0)
            << k.path << " has a default but no minimal case resolves it: add one";
}

TEST(CaseSchema, ParserAcceptsExactlyTheTablesKeys) {
  // An unknown key in each object is refused with the table's keys for that object.
  struct Where {
    std::string section, pointer;
    json base;
  };
  const json cube = {{"geometry", {{"builtin", {{"shape", "cube"}}}}}};
  const json bc = {{"type", "dirichlet"}, {"select", {{"all", true}}}, {"value", 0}};
  std::vector<Where> where;
  for (const char* section : {"meshing", "physics", "discretization", "solver", "output"})
    where.push_back({section, std::string("/") + section, cube});
  where.push_back({"", "", cube});
  where.push_back({"geometry", "/geometry", cube});
  where.push_back({"geometry.builtin", "/geometry/builtin", cube});
  json with_bc = cube;
  with_bc["boundary_conditions"] = json::array({bc});
  where.push_back({"boundary_conditions[]", "/boundary_conditions/0", with_bc});
  where.push_back({"boundary_conditions[].select", "/boundary_conditions/0/select", with_bc});
  json with_load = cube;
  with_load["load_cases"] = json::array({{{"name", "a"}}});
  where.push_back({"load_cases[]", "/load_cases/0", with_load});
  for (const auto& w : where) {
    SCOPED_TRACE(w.section);
    json j = w.base;
    j[json::json_pointer(w.pointer + "/not_a_key")] = 1;
    std::string list;
    for (const auto& k : case_section_keys(w.section)) list += (list.empty() ? "" : ", ") + k;
    EXPECT_NE(error_of(j).find(w.pointer + "/not_a_key: unknown key (allowed here: " + list + ")"),
              std::string::npos)
        << error_of(j);
  }
  // Every documented top-level section is accepted.
  for (const auto& section : case_section_keys("")) {
    const std::string message = error_of({{section, "?"}});
    EXPECT_EQ(message.find("/" + section + ": unknown key"), std::string::npos) << message;
  }
}

TEST(CaseSchema, ParserChecksTheTablesEnumsAndRanges) {
  const std::vector<json> bases = {sphere_case("poisson"), sphere_case("linear_elasticity"),
                                   sphere_case("neo_hookean")};
  int enums = 0, ranges = 0;
  for (const CaseKeyRow& row : case_schema())
    for (const CaseKey& k : row.keys) {
      const auto parts = split(k.path);
      if (parts.size() != 2 || k.path.find("[]") != std::string_view::npos) continue;
      const std::string pointer = "/" + parts[0] + "/" + parts[1];
      SCOPED_TRACE(pointer);
      if (!k.allowed.empty()) {
        json j = bases[0];
        j[json::json_pointer(pointer)] = "zz";
        const std::string message = error_of(j);
        EXPECT_NE(message.find(pointer + ": 'zz': expected "), std::string::npos) << message;
        for (const auto a : k.allowed)
          EXPECT_NE(message.find(std::string(a)), std::string::npos) << message;
        ++enums;
      }
      if (k.range && (k.type == CaseKeyType::number || k.type == CaseKeyType::integer) &&
          std::isfinite(k.range->lo)) {
        // Just below the range: refused (by at least one of the physics the key is for).
        const double below = k.range->lo_open ? k.range->lo : k.range->lo - 1;
        std::string messages;
        bool refused = false;
        for (const json& base : bases) {
          json j = base;
          if (k.type == CaseKeyType::integer)
            j[json::json_pointer(pointer)] = static_cast<int>(below);
          else
            j[json::json_pointer(pointer)] = below;
          const std::string message = error_of(j);
          messages += message + "\n";
          refused |= message.find(pointer + ": must be") != std::string::npos;
        }
        EXPECT_TRUE(refused) << messages;
        ++ranges;
      }
    }
  EXPECT_GE(enums, 8);
  EXPECT_GE(ranges, 12);
}

TEST(CaseSchema, ReadmeKeyTableIsTheGeneratedOne) {
  const auto readme = test::source_dir() / "cases/README.md";
  const std::string text = read_text(readme);
  ASSERT_FALSE(text.empty()) << readme;
  std::string generated;
  ASSERT_NO_THROW(generated = replace_schema_block(text, case_schema_markdown()))
      << readme << " has no " << k_schema_begin << " ... " << k_schema_end << " block";
  ASSERT_NO_THROW(generated = replace_schema_block(generated, study_schema_markdown(),
                                                   k_study_schema_begin, k_study_schema_end))
      << readme << " has no " << k_study_schema_begin << " ... " << k_study_schema_end
      << " block (Studies)";
  if (generated == text) return;
  // Name the first line that differs.
  std::istringstream a(text), b(generated);
  std::string la, lb;
  int line = 0;
  while (true) {
    ++line;
    const bool more_a = static_cast<bool>(std::getline(a, la));
    const bool more_b = static_cast<bool>(std::getline(b, lb));
    if (la != lb || more_a != more_b) break;
  }
  ADD_FAILURE() << "cases/README.md's key tables are not the ones generated from "
                   "pipeline/case_schema.cpp (first difference at line "
                << line << ":\n  README:    " << la << "\n  generated: " << lb
                << "\nRegenerate it: build/tools/curvefem/curvefem schema --update cases/README.md";
}

TEST(CaseSchema, MarkdownHasOneRowPerTableRow) {
  const std::string md = case_schema_markdown();
  EXPECT_EQ(md.rfind("| key | type | default | meaning |\n|---|---|---|---|\n", 0), 0u);
  EXPECT_EQ(static_cast<std::size_t>(std::count(md.begin(), md.end(), '\n')),
            case_schema().size() + 2);
  // The defaults column comes from the keys' defaults unless the row says otherwise.
  EXPECT_NE(md.find("| `meshing.order` | 1..4 | 3 |"), std::string::npos);
  EXPECT_NE(md.find("| `solver.rtol`, `solver.max_iterations` | number, integer | 1e-10, 5000 |"),
            std::string::npos);
  EXPECT_THROW(replace_schema_block("no markers", md), Error);
}

TEST(StudySchema, TheStudyTableHasTheKeysTheStudyParserAccepts) {
  EXPECT_EQ(study_section_keys(""),
            (std::set<std::string>{"base", "description", "output", "refine", "sweep", "x"}));
  EXPECT_EQ(study_section_keys("output"), std::set<std::string>{"dir"});
  const std::string md = study_schema_markdown();
  EXPECT_EQ(static_cast<std::size_t>(std::count(md.begin(), md.end(), '\n')),
            study_schema().size() + 2);
  EXPECT_NE(md.find("| `x` | `\"dofs\"` \\| `\"tets\"` | `\"dofs\"` |"), std::string::npos) << md;
  const auto j = study_schema_json();
  ASSERT_TRUE(j.is_array());
  EXPECT_EQ(j.size(), 7u);
}

// Every enum of CaseSpec spells exactly the values its schema key allows (case_enums.hpp), so a
// value added to one and not the other fails here, not at run time.
template <class E>
void expect_enum_spells(std::string_view key, std::set<std::string> extra = {}) {
  std::set<std::string> names;
  for (const auto n : EnumNames<E>::names)
    if (!n.empty()) names.insert(std::string(n));
  std::set<std::string> allowed(extra);
  for (const auto a : case_key(key).allowed) allowed.insert(std::string(a));
  EXPECT_EQ(names, allowed) << key;
  for (const auto& n : names) EXPECT_EQ(to_string(enum_from<E>(n)), n) << key;
}

TEST(CaseSchema, TheEnumsSpellTheAllowedValues) {
  expect_enum_spells<BuiltinVolume>("geometry.builtin.shape");
  expect_enum_spells<BuiltinSurface>("geometry.builtin_surface.shape");
  // features: "auto" | "none" as strings, {"angle": ...} | {"file": ...} as objects.
  expect_enum_spells<FeatureMode>("geometry.features", {"angle", "file"});
  expect_enum_spells<MeshingMethod>("meshing.method");
  expect_enum_spells<SolveOn>("meshing.solve_on");
  expect_enum_spells<Physics>("physics.type");
  expect_enum_spells<PartialDirichlet>("discretization.partial_dirichlet");
  expect_enum_spells<SolveGeometry>("discretization.geometry");
  expect_enum_spells<SolverType>("solver.type");
  expect_enum_spells<Preconditioner>("solver.preconditioner");
  expect_enum_spells<BoundaryType>("boundary_conditions[].type");
  EXPECT_THROW(enum_from<Physics>("poison"), Error);
  // JSON gets the spelling, not the number.
  EXPECT_EQ(nlohmann::json(Physics::linear_elasticity), nlohmann::json("linear_elasticity"));
  EXPECT_EQ(nlohmann::json("cg").get<SolverType>(), SolverType::cg);
}

// The rules between keys (CaseKey::when) are well formed: they name keys of the table, compare
// with values those keys can hold, and a key compared by value comes before the keys whose rules
// compare it (the resolver reads it resolved); defaults that depend on other keys are documented.
TEST(CaseSchema, TheRulesNameKeysAndValuesOfTheTable) {
  std::map<std::string, std::size_t> order;
  std::size_t n = 0;
  for (const CaseKeyRow& row : case_schema())
    for (const CaseKey& k : row.keys) order[std::string(k.path)] = n++;
  int rules = 0;
  auto check = [&](const CaseKey& k, const CaseKeyWhen& w, bool needs_error) {
    SCOPED_TRACE(std::string(k.path) + " <- " + std::string(w.path));
    ASSERT_TRUE(order.count(std::string(w.path))) << "not a key of the table";
    EXPECT_NE(w.path, k.path);
    if (needs_error) {
      EXPECT_FALSE(w.error.empty());
    }
    if (w.values.empty()) return;
    EXPECT_LT(order[std::string(w.path)], order[std::string(k.path)]);
    const CaseKey& target = case_key(w.path);
    for (const auto text : w.values) {
      json v;
      ASSERT_NO_THROW(v = json::parse(text)) << text;
      if (!target.allowed.empty()) {
        ASSERT_TRUE(v.is_string()) << text;
        EXPECT_NE(std::find(target.allowed.begin(), target.allowed.end(), v.get<std::string>()),
                  target.allowed.end())
            << text;
      }
      if (target.type == CaseKeyType::boolean) {
        EXPECT_TRUE(v.is_boolean()) << text;
      }
    }
    ++rules;
  };
  for (const CaseKeyRow& row : case_schema())
    for (const CaseKey& k : row.keys) {
      for (const CaseKeyWhen& w : k.when) check(k, w, true);
      for (const CaseKeyDefault& d : k.defaults) {
        json parsed;
        ASSERT_NO_THROW(parsed = json::parse(d.value)) << k.path;
        for (const CaseKeyWhen& w : d.when) check(k, w, false);
      }
      if (!k.defaults.empty() || !k.default_from.empty()) {
        EXPECT_FALSE(row.default_text.empty()) << k.path << ": document the default";
        EXPECT_TRUE(k.default_json.empty()) << k.path;
      }
      if (!k.default_from.empty()) {  // read resolved: it comes first
        ASSERT_TRUE(order.count(std::string(k.default_from))) << k.path;
        EXPECT_LT(order[std::string(k.default_from)], order[std::string(k.path)]) << k.path;
      }
    }
  EXPECT_GE(rules, 40);
}

// Every rule of every geometry, meshing and physics key, against the cases a user can write:
// the key is given in each of them; where its rules hold on the case (judged here on the resolved
// case, by a lookup of this file, not the resolver's), it is read and resolved as given; where one
// fails, the case is refused naming the key's JSON path and the first failing rule. Each such key
// is seen both ways.
TEST(CaseSchema, AKeyIsReadWhereItsRulesHoldAndRefusedWhereOneFails) {
  const auto dir = test::scratch_dir("case_schema_rules");
  std::ofstream(dir / "s.obj") << "# a surface the parser only checks exists\n";
  std::filesystem::create_directories(dir / "saved");
  std::ofstream(dir / "saved" / "mesh.msh") << "";
  std::ofstream(dir / "saved" / "boundary_map.json") << "{}";
  auto with = [](json j, const std::string& pointer, const json& v) {
    j[json::json_pointer(pointer)] = v;
    return j;
  };
  const json sphere = {{"geometry", {{"builtin_surface", {{"shape", "sphere"}}}}}};
  const json cube = {{"geometry", {{"builtin", {{"shape", "cube"}}}}}};
  std::vector<json> bases = {
      sphere,
      with(sphere, "/physics/type", "linear_elasticity"),
      with(sphere, "/physics/type", "neo_hookean"),
      sphere_case("poisson"),
      sphere_case("linear_elasticity"),
      sphere_case("neo_hookean"),
      with(with(sphere, "/meshing/exterior", true), "/meshing/method", "dense"),
      with(sphere, "/meshing/method", "dense"),
      {{"geometry", {{"builtin_surface", {{"shape", "torus"}}}}}},
      {{"geometry", {{"builtin_surface", {{"shape", "box"}}}}}},
      cube,
      with(cube, "/physics/type", "linear_elasticity"),
      {{"geometry", {{"builtin", {{"shape", "ball"}}}}}},
      {{"geometry", {{"surface", "s.obj"}}}},
      {{"geometry", {{"mesh", "m.msh"}}}},
      {{"geometry", {{"mesh_dir", "saved"}}}},
  };
  // A valid value for keys without a fixed default.
  const std::map<std::string, json> samples = {{"geometry.data_surface", "s.obj"},
                                               {"meshing.eps_field", "0.01"},
                                               {"meshing.eps_by_tag", {{"1", 0.01}}},
                                               {"physics.kappa_inside", "2"},
                                               {"physics.E_inside", 2.0},
                                               {"physics.nu_inside", 0.2},
                                               // true: false would exclude the cases' own solve_on.
                                               {"meshing.exterior", true}};
  int keys = 0;
  for (const CaseKeyRow& row : case_schema())
    for (const CaseKey& k : row.keys) {
      const std::string section = std::string(k.path.substr(0, k.path.find('.')));
      if (k.when.empty() || (section != "geometry" && section != "meshing" && section != "physics"))
        continue;
      SCOPED_TRACE(std::string(k.path));
      json value;
      if (samples.count(std::string(k.path)))
        value = samples.at(std::string(k.path));
      else if (!k.default_json.empty())
        value = json::parse(k.default_json);
      ASSERT_FALSE(value.is_null()) << "give the test a value for the key";
      std::string pointer;
      for (const auto& part : split(k.path)) pointer += "/" + part;
      const std::string parent(k.path.substr(0, k.path.rfind('.')));
      int read = 0, refused = 0;
      for (const json& base : bases) {
        // Keys of a shape's object only where that object is.
        if (split(k.path).size() > 2 && !lookup(base, parent)) continue;
        CaseSpec c;
        ASSERT_NO_THROW(c = read_case_json(base, dir / "case.json")) << base.dump();
        const CaseKeyWhen* failing = nullptr;
        for (const CaseKeyWhen& w : k.when) {
          const json* v = lookup(c.resolved, w.path);
          bool holds = w.values.empty() ? (v != nullptr) == w.given : false;
          for (const auto text : w.values) holds = holds || (v && *v == json::parse(text));
          if (!holds) {
            failing = &w;
            break;
          }
        }
        const json j = with(base, pointer, value);
        std::string message;
        CaseSpec r;
        try {
          r = read_case_json(j, dir / "case.json");
        } catch (const InputError& e) {
          message = e.what();
        }
        if (!failing) {
          EXPECT_EQ(message, "") << j.dump();
          const json* got = lookup(r.resolved, k.path);
          EXPECT_TRUE(got != nullptr) << j.dump();
          if (got && k.type != CaseKeyType::path && k.type != CaseKeyType::expression) {
            EXPECT_EQ(*got, value) << j.dump();
          }
          ++read;
        } else {
          EXPECT_NE(message.find(pointer + ": " + std::string(failing->error)), std::string::npos)
              << j.dump() << "\n"
              << message;
          ++refused;
        }
      }
      EXPECT_GT(read, 0) << "no case where the key applies";
      EXPECT_GT(refused, 0) << "no case where it does not";
      ++keys;
    }
  EXPECT_GE(keys, 30);
}

// A case file named by a relative path: its relative paths resolve against its folder once
// (the resolved case holds them absolute, and the parser reads those), as `curvefem run
// cases/x.json` from the repository root does.
TEST(CaseSchema, RelativePathsOfACaseNamedRelativelyResolveOnce) {
  const auto dir = test::scratch_dir("case_schema_relative");
  std::filesystem::create_directories(dir / "data");
  std::ofstream(dir / "data" / "s.obj") << "# the parser only checks it exists\n";
  const auto relative = std::filesystem::relative(dir / "case.json");
  ASSERT_TRUE(relative.is_relative());
  const json j = {{"geometry", {{"surface", "data/s.obj"}}}, {"output", {{"dir", "out"}}}};
  CaseSpec c;
  ASSERT_NO_THROW(c = read_case_json(j, relative)) << error_of(j);
  EXPECT_TRUE(std::filesystem::is_regular_file(c.surface)) << c.surface;
  EXPECT_TRUE(c.surface.is_absolute()) << c.surface;
  EXPECT_EQ(std::filesystem::weakly_canonical(c.surface),
            std::filesystem::weakly_canonical(dir / "data" / "s.obj"));
  EXPECT_EQ(std::filesystem::weakly_canonical(c.resolved["geometry"]["surface"].get<std::string>()),
            std::filesystem::weakly_canonical(dir / "data" / "s.obj"));
  EXPECT_EQ(std::filesystem::weakly_canonical(c.output_dir),
            std::filesystem::weakly_canonical(dir / "out"));
}
