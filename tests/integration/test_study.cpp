// `curvefem study`: a degree × refinement sweep on the built-in cube with a known exact solution
// (fitted rates checked against p + 1), broken study files (exit 2, nothing created), and a run
// that fails inside a study (recorded, exit 3, everything else written).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tests/support/test_support.hpp"

using namespace curvefem;

namespace {
std::string cli() { return test::curvefem_executable().string(); }

nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

std::vector<std::vector<std::string>> read_csv(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::string cell;
    bool quoted = false;
    for (std::size_t i = 0; i < line.size(); ++i) {
      const char c = line[i];
      if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"')
        cell += '"', ++i;
      else if (c == '"')
        quoted = !quoted;
      else if (c == ',' && !quoted)
        cells.push_back(cell), cell.clear();
      else
        cell += c;
    }
    cells.push_back(cell);
    rows.push_back(cells);
  }
  return rows;
}

int column(const std::vector<std::string>& header, const std::string& name) {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return static_cast<int>(i);
  ADD_FAILURE() << "no column " << name;
  return 0;
}

int run_study(const std::filesystem::path& file, const std::filesystem::path& out,
              std::string* log) {
  return test::run_command(cli() + " study -q " + file.string() + " -o " + out.string(), log);
}

// −Δu = u for u = sin(x) cos(y) exp(z), Dirichlet data on the whole boundary of the unit cube.
const std::string k_cube_base = R"JSON({
    "geometry": {"builtin": {"shape": "cube", "divisions": 2}},
    "physics": {"type": "poisson"},
    "rhs": "sin(x)*cos(y)*exp(z)",
    "boundary_conditions": [
      {"type": "dirichlet", "select": {"all": true}, "value": "sin(x)*cos(y)*exp(z)"}],
    "exact": "sin(x)*cos(y)*exp(z)"})JSON";
}  // namespace

TEST(Study, DegreeTimesRefinementConvergesAtRatePPlusOne) {
  const auto dir = test::scratch_dir("study_cube");
  const auto file = dir / "study.json";
  std::ofstream(file) << R"({"description": "P1/P2 on the unit cube", "base": )" << k_cube_base
                      << R"(, "sweep": {"/discretization/degree": [1, 2],
                                      "/geometry/builtin/divisions": [3, 6, 12]}})";
  const auto out = dir / "out";
  std::string log;
  ASSERT_EQ(run_study(file, out, &log), 0) << log;

  const auto csv = read_csv(out / "study.csv");
  ASSERT_EQ(csv.size(), 7u);  // header + 2 × 3 runs
  const std::vector<std::string> header = {"name",      "degree",        "divisions", "status",
                                           "exit_code", "dofs",          "tets",      "order",
                                           "l2_error",  "h1_semi_error", "h1_error",  "meshing_s",
                                           "solve_s",   "total_s",       "message"};
  EXPECT_EQ(csv[0], header);
  const std::vector<std::string> names = {"degree=1_divisions=3",  "degree=1_divisions=6",
                                          "degree=1_divisions=12", "degree=2_divisions=3",
                                          "degree=2_divisions=6",  "degree=2_divisions=12"};
  for (std::size_t r = 1; r < csv.size(); ++r) {
    ASSERT_EQ(csv[r].size(), header.size()) << r;
    EXPECT_EQ(csv[r][0], names[r - 1]);
    EXPECT_EQ(csv[r][column(header, "status")], "ok");
    EXPECT_EQ(csv[r][column(header, "exit_code")], "0");
    EXPECT_GT(std::stod(csv[r][column(header, "l2_error")]), 0.0);
    EXPECT_TRUE(std::filesystem::exists(out / "runs" / names[r - 1] / "report.json"));
  }
  // The cube with n divisions has 6 n³ tets and (p n + 1)³ nodes.
  EXPECT_EQ(csv[3][column(header, "tets")], std::to_string(6 * 12 * 12 * 12));
  EXPECT_EQ(csv[6][column(header, "dofs")], std::to_string(25 * 25 * 25));
  // Each run's resolved case names the folder it ended up in (not the staging folder).
  const auto resolved = read_json(out / "runs" / names[0] / "resolved_case.json");
  EXPECT_EQ(resolved["output"]["dir"], (out / "runs" / names[0]).string());

  const auto study = read_json(out / "study.json");
  ASSERT_EQ(study["series"].size(), 2u);
  for (int p = 1; p <= 2; ++p) {
    const auto& s = study["series"][p - 1];
    EXPECT_EQ(s["parameters"]["degree"], p);
    EXPECT_EQ(s["along"], "divisions");
    const auto& l2 = s["rates"]["l2_error"];
    EXPECT_EQ(l2["points"], 3);
    // Measured: L2 rate_h_tets 1.99 (p = 1), 3.00 (p = 2); H1 1.00, 2.00. tets = 6 n³ exactly, so
    // this is the rate in h = 1/n, already asymptotic from n = 3 on this smooth solution: ±0.1
    // separates p + 1 from anything else.
    const double expected = p + 1;
    EXPECT_NEAR(l2["rate_h_tets"].get<double>(), expected, 0.1) << l2.dump();
    EXPECT_NEAR(s["rates"]["h1_error"]["rate_h_tets"].get<double>(), p, 0.1) << s.dump();
    // The rate in h ~ DOFs^(-1/3) overshoots at these small n because DOFs = (p n + 1)³, not
    // ∝ n³: over n = 3 → 12 it is (p + 1) · ln 4 / ln((12p + 1)/(3p + 1)) = 2.35 (p = 1), 3.27
    // (p = 2). Measured 2.34 and 3.26. Checked against that prediction, and loosely against p + 1.
    const double predicted = expected * std::log(4.0) / std::log((12.0 * p + 1) / (3.0 * p + 1));
    EXPECT_NEAR(l2["rate_h"].get<double>(), predicted, 0.1) << l2.dump();
    EXPECT_NEAR(l2["rate_h"].get<double>(), expected, 0.4) << l2.dump();
  }
  EXPECT_EQ(study["failed_runs"], 0);
  if (test::run_command("command -v gnuplot") == 0) {
    EXPECT_EQ(study["plot"], "study.png");
    ASSERT_TRUE(std::filesystem::exists(out / "study.png"));
    std::ifstream png(out / "study.png", std::ios::binary);
    char magic[8] = {};
    png.read(magic, 8);
    EXPECT_EQ(std::string(magic + 1, 3), "PNG");
    std::ifstream gp(out / "study.gp");
    std::stringstream text;
    text << gp.rdbuf();
    EXPECT_NE(text.str().find("degree=1  L2  rate "), std::string::npos) << text.str();
  }
  for (const auto& entry : std::filesystem::directory_iterator(out))
    EXPECT_NE(entry.path().filename().string().front(), '.') << entry.path();  // no staging left
}

TEST(Study, BrokenStudyFilesExitTwoNameTheJsonPathAndCreateNothing) {
  const auto dir = test::scratch_dir("study_bad");
  const std::string degrees = R"("sweep": {"/discretization/degree": [1, 2]})";
  struct Bad {
    std::string body, expected;
  } cases[] = {
      {R"({"base": )" + k_cube_base + R"(, "sweep": {"/discretization/degree": [1, 7]}})",
       "/sweep/~1discretization~1degree/1: the run with /discretization/degree = 7 is not a valid "
       "case: /discretization/degree: must be in 1..4"},
      {R"({"base": )" + k_cube_base + ", " + degrees + R"(, "sweeps": {}})",
       "/sweeps: unknown key"},
      {R"({"base": )" + k_cube_base + R"(, "sweep": {"discretization/degree": [1]}})",
       "/sweep/discretization~1degree: 'discretization/degree' is not a JSON pointer"},
      {R"({"base": )" + k_cube_base + R"(, "sweep": {"/discretization/degree": []}})",
       "/sweep/~1discretization~1degree: expected a non-empty array"},
      {R"({"base": )" + k_cube_base + R"(, "sweep": {"/discretization/degree": [1, 1]}})",
       "/sweep/~1discretization~1degree/1: duplicate value 1"},
      {R"({"base": )" + k_cube_base + R"(, "sweep": {"/output/dir": ["a", "b"]}})",
       "/sweep/~1output~1dir: the output folder of each run is set by the study"},
      {R"({"base": )" + k_cube_base + ", " + degrees + R"(, "refine": "/nope"})",
       "/refine: '/nope' is not a key of /sweep"},
      {R"({"base": {"geometry": {"builtin": {"shape": "cube"}}}, )" + degrees + "}",
       "/base: the case has no exact solution"},
      {R"({"base": {"geometry": {"builtin": {"shape": "cube"}}, "physics": {"kapa": 1}}, )" +
           degrees + "}",
       "/base/physics/kapa: unknown key"},
      {R"({"base": "missing.json", )" + degrees + "}", "/base: cannot open case file"},
      {R"({"base": )" + k_cube_base + R"(, "sweep": {"/geometry/builtin/size": [0.5]}})",
       "/sweep/~1geometry~1builtin~1size/0: the run with /geometry/builtin/size = 0.5 is not a "
       "valid case: /geometry/builtin/size: only for the ball"},
      {R"({"base": )" + k_cube_base + ", " + degrees, "invalid JSON"},
  };
  for (const auto& c : cases) {
    const auto file = dir / "bad_study.json";
    std::ofstream(file) << c.body;
    std::string log;
    EXPECT_EQ(run_study(file, dir / "out", &log), 2) << c.body << "\n" << log;
    EXPECT_NE(log.find(c.expected), std::string::npos) << log;
    EXPECT_NE(log.find("bad_study.json"), std::string::npos) << log;
    EXPECT_FALSE(std::filesystem::exists(dir / "out")) << c.body;
  }
}

TEST(Study, AFailedRunIsRecordedTheOthersAreWrittenAndTheStudyExitsThree) {
  const auto dir = test::scratch_dir("study_failed_run");
  // Dirichlet data on a small box in the middle of the face z = 0: with one division the face has
  // no node inside it (exit 2 from that run), with two it has one.
  auto study = [](const std::string& divisions) {
    return R"({"base": {
      "geometry": {"builtin": {"shape": "cube", "divisions": 1}},
      "boundary_conditions": [{"type": "dirichlet",
        "select": {"box": [[0.4, 0.4, -0.1], [0.6, 0.6, 0.1]]}, "value": 1}],
      "exact": "1"},
      "sweep": {"/geometry/builtin/divisions": )" +
           divisions + "}}";
  };
  const auto file = dir / "study.json";
  std::ofstream(file) << study("[1, 2]");
  const auto out = dir / "out";
  std::string log;
  ASSERT_EQ(run_study(file, out, &log), 3) << log;
  EXPECT_NE(log.find("1 of 2 runs failed"), std::string::npos) << log;
  const auto csv = read_csv(out / "study.csv");
  ASSERT_EQ(csv.size(), 3u);
  const auto& header = csv[0];
  EXPECT_EQ(csv[1][column(header, "status")], "failed");
  EXPECT_EQ(csv[1][column(header, "exit_code")], "2");
  EXPECT_NE(csv[1][column(header, "message")].find("selects no boundary face"), std::string::npos);
  EXPECT_EQ(csv[1][column(header, "dofs")], "");
  EXPECT_EQ(csv[2][column(header, "status")], "ok");
  EXPECT_FALSE(std::filesystem::exists(out / "runs" / "divisions=1"));
  EXPECT_TRUE(std::filesystem::exists(out / "runs" / "divisions=2" / "report.json"));
  const auto j = read_json(out / "study.json");
  EXPECT_EQ(j["failed_runs"], 1);
  EXPECT_EQ(j["runs"][0]["status"], "failed");
  EXPECT_TRUE(j["series"][0]["rates"]["l2_error"]["rate_h"].is_null());  // one ok point

  // Studying again into the same folder replaces runs/ as a whole.
  std::ofstream(file) << study("[2, 4]");
  ASSERT_EQ(run_study(file, out, &log), 0) << log;
  EXPECT_FALSE(std::filesystem::exists(out / "runs" / "divisions=1"));
  EXPECT_TRUE(std::filesystem::exists(out / "runs" / "divisions=4" / "report.json"));
  EXPECT_EQ(read_csv(out / "study.csv").size(), 3u);
}

// An ε × degree sweep on a curved case meshes once (issue 22): the runs share the ε levels of
// one coarsening (study.json shared_meshing), and each run solves on its own level.
TEST(Study, AnEpsSweepMeshesTheLevelsOnceAndEveryRunUsesItsOwn) {
  const auto dir = test::scratch_dir("study_eps_levels");
  const auto file = dir / "study.json";
  std::ofstream(file) << R"JSON({"base": {
      "geometry": {"builtin_surface": {"shape": "sphere", "level": 3}, "features": "none"},
      "meshing": {"method": "curved", "order": 2},
      "physics": {"type": "poisson"},
      "rhs": "5*sin(2*x)*cos(y)",
      "boundary_conditions": [{"type": "dirichlet", "select": {"all": true},
                               "value": "sin(2*x)*cos(y)"}],
      "exact": "sin(2*x)*cos(y)"},
    "sweep": {"/discretization/degree": [1, 2], "/meshing/eps": [0.04, 0.01]}})JSON";
  const auto out = dir / "out";
  std::string log;
  ASSERT_EQ(run_study(file, out, &log), 0) << log;
  const auto j = read_json(out / "study.json");
  ASSERT_EQ(j["shared_meshing"].size(), 1u) << j["shared_meshing"].dump();
  const auto& shared = j["shared_meshing"][0];
  EXPECT_EQ(shared["runs"].size(), 4u);
  EXPECT_EQ(shared["eps"].size(), 2u);
  EXPECT_GT(shared["seconds"].get<double>(), 0);
  // Each run on its own level: the mesh's bound, validity and faces; both degrees of a level on
  // the same mesh; the finer level has more faces.
  std::map<double, int> faces;
  for (const char* run :
       {"degree=1_eps=0.04", "degree=2_eps=0.04", "degree=1_eps=0.01", "degree=2_eps=0.01"}) {
    const auto r = read_json(out / "runs" / run / "report.json");
    const double eps = r["meshing"]["eps_rel"].get<double>();
    EXPECT_TRUE(r["mesh_valid"].get<bool>()) << run;
    EXPECT_LE(r["meshing"]["validation"]["max_distance_rel"].get<double>(), eps) << run;
    const int f = r["meshing"]["coarse_faces"].get<int>();
    if (faces.count(eps)) EXPECT_EQ(faces[eps], f) << run;
    faces[eps] = f;
  }
  ASSERT_EQ(faces.size(), 2u);
  EXPECT_GT(faces[0.01], faces[0.04]);
}
