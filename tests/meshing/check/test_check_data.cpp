// check_surface on the real meshes of ../shared/data (label `data`):
//   - every dev mesh is acceptable, with the manifest's vertex/face counts, genus and components;
//   - every bad mesh is rejected with the manifest's defect class, and every count of the
//     manifest's measured_defects column is reproduced exactly;
//   - `curvefem check` exits 0 / 2 on a few of them (2 also for a read error).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "meshing/check/check_surface.hpp"
#include "meshing/core/error.hpp"
#include "meshing/io/surface_io.hpp"
#include "tests/support/test_support.hpp"

namespace curvefem::check {
namespace {

namespace fs = std::filesystem;

// Rows of a tab-separated manifest with a header line, as column name → value.
std::vector<std::map<std::string, std::string>> read_manifest(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::map<std::string, std::string>> rows;
  std::string line;
  std::vector<std::string> header;
  auto split = [](const std::string& s) {
    std::vector<std::string> cells;
    std::stringstream ss(s);
    std::string cell;
    while (std::getline(ss, cell, '\t')) cells.push_back(cell);
    return cells;
  };
  if (!std::getline(in, line)) return rows;
  header = split(line);
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    const std::vector<std::string> cells = split(line);
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < header.size() && i < cells.size(); ++i) row[header[i]] = cells[i];
    rows.push_back(row);
  }
  return rows;
}

std::set<std::string> kinds(const CheckReport& r) {
  std::set<std::string> k;
  for (const Defect& d : r.defects) k.insert(d.kind);
  return k;
}

TEST(CheckData, DevMeshesAreAcceptable) {
  const auto data = test::shared_data_dir();
  if (!data) GTEST_SKIP() << test::k_no_data_message;
  const auto rows = read_manifest(*data / "dev" / "MANIFEST.tsv");
  ASSERT_EQ(rows.size(), 19u);
  for (const auto& row : rows) {
    SCOPED_TRACE(row.at("file"));
    const SurfaceMesh mesh = io::read_surface(*data / "dev" / row.at("file"));
    const CheckReport r = check_surface(mesh);
    EXPECT_TRUE(r.acceptable) << (r.defects.empty() ? "" : r.defects[0].message);
    EXPECT_EQ(r.referenced_vertices, std::stoll(row.at("V")));
    EXPECT_EQ(r.faces, std::stoll(row.at("F")));
    EXPECT_EQ(r.genus, std::stoll(row.at("genus")));
    EXPECT_EQ(r.components, std::stoll(row.at("components")));
    EXPECT_EQ(r.orientation_sign, 1);
    EXPECT_TRUE(r.volume_bounded);
    EXPECT_TRUE(r.self_intersections_mesh_api);
    EXPECT_NEAR(r.signed_volume, std::stod(row.at("signed_volume")),
                1e-5 * std::abs(std::stod(row.at("signed_volume"))));
    EXPECT_NEAR(r.min_angle_deg, std::stod(row.at("min_angle_deg")),
                0.006 * std::stod(row.at("min_angle_deg")));
  }
}

// The manifest's measured_defects phrases and the report field each one counts. The manifest
// counts coincident vertices by value (-0.0 == 0.0), as check_surface does.
long long measured_field(const CheckReport& r, const std::string& phrase) {
  if (phrase == "boundary edges") return r.boundary_edges;
  if (phrase == "non-manifold edges") return r.non_manifold_edges;
  if (phrase == "non-manifold vertices") return r.non_manifold_vertices;
  if (phrase == "inconsistently oriented edges") return r.inconsistent_edges;
  if (phrase == "self-intersecting face pairs") return r.self_intersecting_pairs;
  if (phrase == "exactly degenerate faces") return r.degenerate_faces;
  if (phrase == "coincident (unwelded) vertices") return r.duplicate_vertices;
  if (phrase == "unreferenced vertices") return r.unreferenced_vertices;
  ADD_FAILURE() << "unknown manifest phrase: " << phrase;
  return -1;
}

TEST(CheckData, BadMeshesAreRejectedWithTheirDefect) {
  const auto data = test::shared_data_dir();
  if (!data) GTEST_SKIP() << test::k_no_data_message;
  // The defect class each file is in the folder for (from intended_defect).
  const std::map<std::string, std::string> primary = {
      {"open_blob_1hole.off", "open"},
      {"open_stanford_bunny_scan.obj", "open"},
      {"nonmanifold_edge_4tris.off", "non_manifold_edge"},
      {"nonmanifold_vertex_hourglass.off", "non_manifold_vertex"},
      {"nonmanifold_thingi37989_visor.obj", "non_manifold_edge"},
      {"nonmanifold_openscad_example017.obj", "non_manifold_edge"},
      {"selfintersect_camel.off", "self_intersection"},
      {"selfintersect_abc_00000050.obj", "self_intersection"},
      {"inconsistent_orientation_blobby.off", "orientation"},
      {"inverted_ellipsoid.off", "inward"},
      {"degenerate_faces_tiny.off", "degenerate"},
      {"degenerate_propeller_stl.obj", "degenerate"},
      {"famous_cow_nonmanifold_vertex.obj", "non_manifold_vertex"},
      {"famous_teapot_soup.obj", "open"},
  };
  const auto rows = read_manifest(*data / "bad" / "MANIFEST.tsv");
  ASSERT_EQ(rows.size(), 15u);
  const std::regex item(R"(^\s*(\d+) (.+?)\s*$)");
  for (const auto& row : rows) {
    const std::string file = row.at("file");
    SCOPED_TRACE(file);
    const fs::path path = *data / "bad" / file;
    if (file == "quads_torus.off") {
      EXPECT_THROW(io::read_surface(path), InputError);
      continue;
    }
    ASSERT_TRUE(primary.count(file)) << "no expected defect for a new bad file";
    const CheckReport r = check_surface(io::read_surface(path));
    EXPECT_FALSE(r.acceptable);
    EXPECT_TRUE(kinds(r).count(primary.at(file))) << "defects: " << r.defects.size();
    EXPECT_EQ(r.components, std::stoll(row.at("components")));
    EXPECT_EQ(r.referenced_vertices, std::stoll(row.at("V")));
    // The manifest's "closed" means every edge has exactly two faces (no boundary edge and no
    // non-manifold edge); CheckReport::closed only means no boundary edge.
    EXPECT_EQ(r.closed && r.edge_manifold, row.at("closed") == "yes");

    // Every count of measured_defects ("4 boundary edges; 1113 unreferenced vertices").
    std::stringstream items(row.at("measured_defects"));
    std::string text;
    while (std::getline(items, text, ';')) {
      std::smatch m;
      if (text.find("inward orientation") != std::string::npos) {
        EXPECT_EQ(r.orientation_sign, -1);
        EXPECT_TRUE(kinds(r).count("inward"));
      } else if (std::regex_match(text, m, item)) {
        EXPECT_EQ(measured_field(r, m[2]), std::stoll(m[1])) << m[2];
      } else {
        ADD_FAILURE() << "cannot parse measured_defects item: " << text;
      }
    }
    // The self-intersection column ("yes (20 pairs)" / "no (0 pairs)").
    const std::string si = row.at("self_intersecting");
    const auto open = si.find('('), space = si.find(' ', open);
    EXPECT_EQ(r.self_intersecting_pairs, std::stoll(si.substr(open + 1, space - open - 1)));
  }
}

TEST(CheckData, CommandLineExitCodes) {
  const auto data = test::shared_data_dir();
  if (!data) GTEST_SKIP() << test::k_no_data_message;
  const fs::path exe = test::curvefem_executable();
  ASSERT_TRUE(fs::exists(exe)) << exe;
  const auto run = [&](const std::string& args, std::string* out) {
    return test::run_command(exe.string() + " check --quiet " + args, out);
  };
  std::string out;
  EXPECT_EQ(run((*data / "dev" / "knight_decimated.obj").string(), &out), 0) << out;
  EXPECT_NE(out.find("acceptable for meshing: yes"), std::string::npos) << out;
  EXPECT_NE(out.find("genus                    0"), std::string::npos) << out;

  EXPECT_EQ(run((*data / "bad" / "open_blob_1hole.off").string(), &out), 2) << out;
  EXPECT_NE(out.find("open: 4 boundary edges (surface is open): "), std::string::npos) << out;
  EXPECT_NE(out.find("acceptable for meshing: no"), std::string::npos) << out;

  EXPECT_EQ(run("--json " + (*data / "bad" / "inverted_ellipsoid.off").string(), &out), 2) << out;
  EXPECT_NE(out.find("\"kind\": \"inward\""), std::string::npos) << out;
  EXPECT_NE(out.find("\"acceptable\": false"), std::string::npos) << out;

  // A read error: one line on stderr naming the file, exit 2.
  EXPECT_EQ(run((*data / "bad" / "quads_torus.off").string(), &out), 2) << out;
  EXPECT_NE(out.find("quads_torus.off"), std::string::npos) << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
}

}  // namespace
}  // namespace curvefem::check
