// The curvefem CLI on tiny inputs: exit codes (DESIGN.md §3), error lines, atomic output, and the
// demo's report.json.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>

#include "meshing/core/primitives.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/io/vtu_io.hpp"
#include "meshing/shell/displacement_map.hpp"
#include "tests/support/test_support.hpp"

using namespace curvefem;

namespace {
std::string cli() { return test::curvefem_executable().string(); }

nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

// `curvefem generate NAME -q -o PATH` (a corpus surface); fails with the command's output.
::testing::AssertionResult generate(const std::string& name, const std::filesystem::path& path) {
  std::string out;
  if (test::run_command(cli() + " generate " + name + " -q -o " + path.string(), &out) == 0)
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "generate " << name << ": " << out;
}
}  // namespace

TEST(Cli, HelpAndUsageErrors) {
  std::string out;
  EXPECT_EQ(test::run_command(cli() + " --help", &out), 0);
  EXPECT_NE(out.find("check"), std::string::npos);
  EXPECT_EQ(test::run_command(cli() + " check --help", &out), 0);
  EXPECT_NE(out.find("--json"), std::string::npos);
  EXPECT_EQ(test::run_command(cli() + " no-such-command", &out), 1);
  EXPECT_EQ(test::run_command(cli(), &out), 1);
}

// Under an MPI launcher with more than one process only `run` is distributed (its linear solves;
// tests/integration/test_mpi_run.cpp): every other command is refused on every rank (exit 2)
// before writing, since N copies of it would write the same files.
TEST(Cli, SeveralMpiProcessesAreRefusedBeforeAnyOutput) {
  const auto dir = test::scratch_dir("cli_mpi");
  io::write_surface(dir / "sphere.obj", make_icosphere(2), io::SurfaceFormat::obj);
  const std::string mesh =
      " mesh " + (dir / "sphere.obj").string() + " -o " + (dir / "out").string() + " -q";
  std::string out;
  EXPECT_EQ(test::run_command("OMPI_COMM_WORLD_SIZE=2 " + cli() + mesh, &out), 2) << out;
  EXPECT_NE(out.find("2 MPI processes"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
  EXPECT_EQ(test::run_command("PMI_SIZE=3 " + cli() + mesh, &out), 2) << out;
  EXPECT_NE(out.find("3 MPI processes"), std::string::npos) << out;
  // One process (what mpirun -n 1 sets) runs as usual.
  EXPECT_EQ(
      test::run_command(
          "OMPI_COMM_WORLD_SIZE=1 " + cli() + " check -q " + (dir / "sphere.obj").string(), &out),
      0)
      << out;
  // The real launcher, where there is one (CI runs as root: --allow-run-as-root).
  if (test::run_command("command -v mpirun", &out) == 0) {
    EXPECT_NE(
        test::run_command("mpirun --allow-run-as-root --oversubscribe -n 2 " + cli() + mesh, &out),
        0)
        << out;
    EXPECT_NE(out.find("2 MPI processes"), std::string::npos) << out;
    EXPECT_FALSE(std::filesystem::exists(dir / "out"));
  }
}

TEST(Cli, CheckAcceptsClosedSphereAndRejectsOpenBox) {
  const auto dir = test::scratch_dir("cli_check");
  io::write_surface(dir / "sphere.obj", make_icosphere(2), io::SurfaceFormat::obj);
  std::string out;
  ASSERT_EQ(test::run_command(cli() + " check -q --json " + (dir / "sphere.obj").string(), &out), 0)
      << out;
  const auto j = nlohmann::json::parse(out);
  EXPECT_EQ(j["faces"], 320);
  EXPECT_EQ(j["genus"], 0);
  EXPECT_EQ(j["acceptable"], true);

  SurfaceMesh box = make_box({0, 0, 0}, {1, 1, 1}, 2);
  box.F.conservativeResize(box.F.rows() - 1, 3);  // remove one face: 3 boundary edges
  box.tags.conservativeResize(box.F.rows());
  io::write_surface(dir / "open.off", box, io::SurfaceFormat::off);
  EXPECT_EQ(test::run_command(cli() + " check " + (dir / "open.off").string(), &out), 2) << out;
  EXPECT_NE(out.find("3 boundary edges"), std::string::npos) << out;
}

TEST(Cli, MalformedInputNamesFileAndLine) {
  const auto dir = test::scratch_dir("cli_bad");
  std::ofstream(dir / "bad.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n";
  std::string out;
  EXPECT_EQ(test::run_command(cli() + " check " + (dir / "bad.obj").string(), &out), 2);
  EXPECT_NE(out.find("bad.obj:4"), std::string::npos) << out;
  // A file that cannot be opened is an I/O failure (4), named on the error line.
  EXPECT_EQ(test::run_command(cli() + " check " + (dir / "missing.obj").string(), &out), 4) << out;
  EXPECT_NE(out.find("missing.obj"), std::string::npos) << out;
}

TEST(Cli, ConvertRoundTripAndAtomicFailure) {
  const auto dir = test::scratch_dir("cli_convert");
  const SurfaceMesh box = make_box({0, 0, 0}, {1, 2, 3}, 2);
  io::write_surface(dir / "box.obj", box, io::SurfaceFormat::obj);
  std::string out;
  ASSERT_EQ(test::run_command(cli() + " convert -q " + (dir / "box.obj").string() + " " +
                                  (dir / "box.ply").string(),
                              &out),
            0)
      << out;
  const SurfaceMesh back = io::read_surface(dir / "box.ply");
  EXPECT_EQ(back.V, box.V);
  EXPECT_EQ(back.F, box.F);
  EXPECT_EQ(back.tags, box.tags);
  // Writing into a missing directory is an I/O failure (4) and leaves nothing behind.
  EXPECT_EQ(test::run_command(cli() + " convert -q " + (dir / "box.obj").string() + " " +
                                  (dir / "nope" / "box.stl").string(),
                              &out),
            4)
      << out;
  EXPECT_FALSE(std::filesystem::exists(dir / "nope"));
}

TEST(Cli, DemoWritesCompleteVerifiedReport) {
  const auto dir = test::scratch_dir("cli_demo");
  std::string out;
  ASSERT_EQ(test::run_command(
                cli() + " demo -q --order 2 --dense-size 0.08 --coarse-size 0.4 -o " + dir.string(),
                &out),
            0)
      << out;
  for (const char* f :
       {"surface.obj", "surface.vtu", "mesh.vtu", "mesh.msh", "volume.vtu", "demo.pvd"})
    EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
  const auto r = read_json(dir / "report.json");
  EXPECT_EQ(r["order"], 2);
  EXPECT_GT(r["output_tets"].get<int>(), 20);
  EXPECT_EQ(r["input"]["acceptable"], true);
  EXPECT_EQ(r["input"]["genus"], 1);  // the plate's through hole
  EXPECT_EQ(r["jacobian_sampled"]["tets_with_non_positive_sample"], 0);
  // Isoparametric P2 on the curved order-2 mesh, smooth solution: measured 2.0e-4 relative.
  EXPECT_LT(r["fem"]["l2_error_rel"].get<double>(), 1e-3);
  EXPECT_LT(r["fem"]["relative_residual"].get<double>(), 1e-10);
  EXPECT_LT(r["roundtrip_vtu_max_error_rel"].get<double>(), 1e-12);
  EXPECT_LT(r["roundtrip_msh_max_error_rel"].get<double>(), 1e-12);
  // No staging folder left behind.
  for (const auto& e : std::filesystem::directory_iterator(dir))
    EXPECT_NE(e.path().filename().string().rfind(".staging", 0), 0u) << e.path();
}

TEST(Cli, RemeshWritesSurfaceAndReport) {
  const auto dir = test::scratch_dir("cli_remesh");
  io::write_surface(dir / "sphere.obj", make_icosphere(3), io::SurfaceFormat::obj);  // 1280 faces
  std::string out;
  const std::string in = (dir / "sphere.obj").string();
  ASSERT_EQ(test::run_command(cli() + " remesh -q " + in + " -o " + (dir / "q.obj").string() +
                                  " --algorithm qslim --target-faces 300 --threads 2",
                              &out),
            0)
      << out;
  EXPECT_NE(out.find("1280 -> 300 faces"), std::string::npos) << out;
  const auto j = read_json(dir / "q.json");
  EXPECT_EQ(j["input_faces"], 1280);
  EXPECT_EQ(j["quality"]["faces"], 300);
  EXPECT_EQ(j["threads"], 2);
  EXPECT_LT(j["quality"]["max_deviation_rel"].get<double>(), 0.05);
  EXPECT_GT(j["passes"][0]["succeeded"].get<int>(), 400);
  EXPECT_EQ(io::read_surface(dir / "q.obj").num_faces(), 300);
  // Isotropic with an envelope.
  ASSERT_EQ(test::run_command(cli() + " remesh -q " + in + " -o " + (dir / "i.obj").string() +
                                  " --algorithm isotropic --target-edge 0.2 --envelope 0.02",
                              &out),
            0)
      << out;
  const auto k = read_json(dir / "i.json");
  EXPECT_LE(k["quality"]["max_deviation"].get<double>(), 0.02);
  EXPECT_EQ(k["passes"].size(), 20u);  // 5 rounds of split, collapse, swap, smooth
  // Usage errors: missing target, wrong algorithm, non-manifold input; nothing written.
  EXPECT_EQ(test::run_command(cli() + " remesh -q " + in + " -o " + (dir / "x.obj").string() +
                                  " --algorithm qslim",
                              &out),
            2);
  EXPECT_NE(out.find("--target-faces"), std::string::npos) << out;
  EXPECT_NE(test::run_command(cli() + " remesh -q " + in + " -o " + (dir / "x.obj").string() +
                                  " --algorithm magic --target-faces 10",
                              &out),
            0);
  SurfaceMesh bad = make_icosphere(1);
  std::swap(bad.F(3, 1), bad.F(3, 2));
  io::write_surface(dir / "bad.obj", bad, io::SurfaceFormat::obj);
  EXPECT_EQ(test::run_command(cli() + " remesh -q " + (dir / "bad.obj").string() + " -o " +
                                  (dir / "x.obj").string() + " --algorithm qslim --target-faces 10",
                              &out),
            2);
  EXPECT_NE(out.find("inconsistently oriented"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.obj"));
  EXPECT_FALSE(std::filesystem::exists(dir / "x.json"));
}

TEST(Cli, MeshThenValidateAndDetectTampering) {
  const auto dir = test::scratch_dir("cli_mesh");
  io::write_surface(dir / "sphere.obj", make_icosphere(3), io::SurfaceFormat::obj);  // 1280 faces
  const std::string in = (dir / "sphere.obj").string(), out_dir = (dir / "m").string();
  std::string out;
  ASSERT_EQ(test::run_command(cli() + " mesh -q " + in + " -o " + out_dir +
                                  " --order 3 --eps 0.01 --no-features --threads 2"
                                  " --optimize-edit-energy 1.5",
                              &out),
            0)
      << out;
  const auto j = read_json(dir / "m" / "report.json");
  EXPECT_EQ(j["input_faces"], 1280);
  // The curved edits (no target at the default energy 4 on this sphere: its worst cell is 2.5)
  // report what they did, and the validated mesh is theirs.
  const auto& edits = j["optimize"]["curved_edits"];
  EXPECT_GT(edits["collapses"].get<long>() + edits["flips"].get<long>(), 0) << edits.dump();
  EXPECT_LT(edits["targets"]["after"].get<int>(), edits["targets"]["before"].get<int>());
  EXPECT_EQ(edits["tets"]["after"], j["validation"]["tets"]);
  EXPECT_EQ(j["order"], 3);
  EXPECT_TRUE(j["min_jacobian_certified"].get<bool>());
  EXPECT_EQ(j["boundary_self_intersections"], 0);
  EXPECT_LE(j["max_distance_rel"].get<double>(), 0.01);
  EXPECT_LT(j["output_boundary_faces"].get<int>(), 640);
  EXPECT_LE(j["map_roundtrip_max_error_rel"].get<double>(), 1e-9);
  EXPECT_EQ(j["map_roundtrip_failures"], 0);
  EXPECT_TRUE(j["valid"].get<bool>());
  for (const char* f : {"mesh.vtu", "mesh.msh", "boundary_map.json"})
    EXPECT_TRUE(std::filesystem::exists(dir / "m" / f)) << f;
  // The validator re-reads everything and agrees.
  ASSERT_EQ(test::run_command(cli() + " validate " + out_dir, &out), 0) << out;
  EXPECT_NE(out.find("valid"), std::string::npos) << out;
  // A tighter bound than the mesh was built for must fail (exit 3) and say so.
  EXPECT_EQ(test::run_command(cli() + " validate " + out_dir + " --eps 1e-6", &out), 3) << out;
  EXPECT_NE(out.find("EXCEEDS"), std::string::npos) << out;
  // Tampered map: one input vertex sent to another corner of its face.
  auto map = read_json(dir / "m" / "boundary_map.json");
  map["vertex_uv"][0] = {0.0, 0.0};
  map["vertex_uv"][1] = {0.0, 0.0};
  { std::ofstream(dir / "m" / "boundary_map.json") << map.dump(); }
  EXPECT_EQ(test::run_command(cli() + " validate " + out_dir, &out), 3) << out;
  // ... and names what failed and where.
  EXPECT_NE(out.find("defect"), std::string::npos) << out;
  EXPECT_NE(out.find("input vertex"), std::string::npos) << out;
  // Invalid inputs: open surface → exit 2, nothing written.
  SurfaceMesh open = make_icosphere(1);
  open.F.conservativeResize(open.F.rows() - 1, 3);
  io::write_surface(dir / "open.obj", open, io::SurfaceFormat::obj);
  EXPECT_EQ(
      test::run_command(
          cli() + " mesh -q " + (dir / "open.obj").string() + " -o " + (dir / "x").string(), &out),
      2)
      << out;
  EXPECT_FALSE(std::filesystem::exists(dir / "x"));
}

TEST(Cli, ShellKeepsItsDistortionBoundAndRefusesATangentPillar) {
  // A thin torus coarsened with a thick zoom (0.224 absolute, the bbox edge is 1.84). Under the
  // bare section condition (--pillar-cos 0) a pillar on the tube's outer equator ends tangent to
  // faces on top of the tube up to rounding: every exact check passes, but P maps input vertices
  // back 0.0093 away, so the verifier fails the shell (exit 3). The default bound keeps every
  // covered face at cosine >= 0.01 with its pillars, and verify_shell measures it.
  const auto dir = test::scratch_dir("cli_shell_pillar_cos");
  io::write_surface(dir / "torus.obj", make_torus(0.8, 0.12, 96, 10), io::SurfaceFormat::obj);
  const std::string base = cli() + " shell -q " + (dir / "torus.obj").string() +
                           " --threads 1 --zoom " + std::to_string(0.224 / 1.84) + " -o ";
  std::string out;
  EXPECT_EQ(test::run_command(base + (dir / "bare").string() + " --pillar-cos 0", &out), 3) << out;
  const auto bare = read_json(dir / "bare" / "report.json");
  EXPECT_EQ(bare["pillar_cos_bound"].get<double>(), 0.0);
  EXPECT_LT(bare["min_pillar_cos"].get<double>(), 1e-12);
  EXPECT_GT(bare["roundtrip_failures"].get<int>(), 0);
  EXPECT_EQ(bare["is_section_verified"], true);  // exact: the fibers still cross once

  ASSERT_EQ(test::run_command(base + (dir / "bounded").string(), &out), 0) << out;
  const auto bounded = read_json(dir / "bounded" / "report.json");
  EXPECT_EQ(bounded["pillar_cos_bound"].get<double>(), 0.01);
  EXPECT_GE(bounded["min_pillar_cos"].get<double>(), 0.01);
  EXPECT_EQ(bounded["roundtrip_failures"], 0);
  EXPECT_LT(bounded["roundtrip_max_error_rel"].get<double>(), 1e-12);
  EXPECT_LT(bounded["prisms"].get<int>(), 300);  // 1920 before coarsening
}

// `check --merge-short-edges L -o OUT`: the sliver sphere's 40 slivers are edges of a level-3
// icosphere split at 1e-4 of their length; merged, the icosphere comes back (1,280 faces, no
// needle), with the vertex map beside it. Without --merge-short-edges, -o is refused; a result
// that is not acceptable (here an open input) is not written. `mesh` meshes the repaired surface.
TEST(Cli, MergingShortEdgesWritesTheRepairedSurfaceWithItsVertexMapAndMeshesIt) {
  const auto dir = test::scratch_dir("cli_check_merge");
  std::string out;
  ASSERT_TRUE(generate("sliver_sphere_001", dir / "slivers.obj"));
  const SurfaceMesh input = io::read_surface(dir / "slivers.obj");
  ASSERT_EQ(input.num_faces(), 1280 + 80);
  const auto merged = dir / "merged.obj";
  ASSERT_EQ(test::run_command(cli() + " check -q --json " + (dir / "slivers.obj").string() +
                                  " --merge-short-edges 1e-4 -o " + merged.string(),
                              &out),
            0)
      << out;
  const auto j = nlohmann::json::parse(out.substr(out.find('{')));
  EXPECT_EQ(j["acceptable"], true);
  EXPECT_TRUE(j["warnings"].empty());
  EXPECT_EQ(j["faces"], 1280);
  const auto& m = j["merge_short_edges"];
  EXPECT_EQ(m["candidates"], 40);
  EXPECT_EQ(m["merged"], 40);
  EXPECT_EQ(m["left"], 0);
  EXPECT_EQ(m["written"], true);
  EXPECT_LT(m["max_moved"].get<double>(), 1e-4 * 2.0);
  const SurfaceMesh repaired = io::read_surface(merged);
  EXPECT_EQ(repaired.num_faces(), 1280);
  EXPECT_EQ(repaired.num_vertices(), input.num_vertices() - 40);
  const auto map = read_json(dir / "merged_vertex_map.json");
  ASSERT_EQ(map["vertex_map"].size(), std::size_t(input.num_vertices()));
  ASSERT_EQ(map["face_origin"].size(), 1280u);
  ASSERT_EQ(map["pairs"].size(), 40u);
  for (const auto& p : map["pairs"]) {  // each merged vertex sits where its kept end is mapped
    const int removed = p["removed"], kept = p["kept"];
    EXPECT_EQ(map["vertex_map"][removed], map["vertex_map"][kept]);
    EXPECT_EQ(repaired.V.row(map["vertex_map"][kept].get<int>()), input.V.row(kept));
    EXPECT_NEAR((input.V.row(removed) - input.V.row(kept)).norm(), p["length"].get<double>(),
                1e-15);
  }

  EXPECT_EQ(test::run_command(cli() + " check -q " + (dir / "slivers.obj").string() + " -o " +
                                  (dir / "alone.obj").string(),
                              &out),
            2)
      << out;
  EXPECT_FALSE(std::filesystem::exists(dir / "alone.obj"));

  SurfaceMesh open = input;
  open.F = input.F.bottomRows(input.num_faces() - 1);
  io::write_surface(dir / "open.obj", open, io::SurfaceFormat::obj);
  EXPECT_EQ(test::run_command(cli() + " check -q " + (dir / "open.obj").string() +
                                  " --merge-short-edges 1e-4 -o " + (dir / "bad.obj").string(),
                              &out),
            2)
      << out;
  EXPECT_NE(out.find("is not acceptable and is not written"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.obj"));
  EXPECT_FALSE(std::filesystem::exists(dir / "bad_vertex_map.json"));

  // `mesh --merge-short-edges`: the same repair, the repaired surface saved in the mesh folder as
  // the input the map refers to (so `validate` and geometry.mesh_dir read it).
  const auto mdir = dir / "meshed";
  ASSERT_EQ(
      test::run_command(cli() + " mesh -q " + (dir / "slivers.obj").string() +
                            " --order 3 --threads 1 --merge-short-edges 1e-4 -o " + mdir.string(),
                        &out),
      0)
      << out;
  const auto r = read_json(mdir / "report.json");
  EXPECT_EQ(r["valid"], true);
  EXPECT_EQ(r["input_repair"]["merged"], 40);
  EXPECT_EQ(r["input_repair"]["original_distance"]["within_eps"], true);
  EXPECT_GE(r["input_repair"]["original_distance"]["max_distance_rel"].get<double>(),
            r["max_distance_rel"].get<double>());
  EXPECT_EQ(r["input_repair"]["original"], std::filesystem::absolute(dir / "slivers.obj").string());
  EXPECT_EQ(r["input"], std::filesystem::absolute(mdir / "input_merged.obj").string());
  EXPECT_TRUE(r["input_warnings"].empty());
  EXPECT_EQ(r["input_faces"], 1280);
  EXPECT_EQ(io::read_surface(mdir / "input_merged.obj").F, repaired.F);
  EXPECT_EQ(read_json(mdir / "input_merged_vertex_map.json")["vertex_map"], map["vertex_map"]);
  EXPECT_EQ(read_json(mdir / "boundary_map.json")["input"], r["input"]);
  EXPECT_EQ(test::run_command(cli() + " validate -q " + mdir.string(), &out), 0) << out;
}

TEST(Cli, AKnifeEdgeMeshesWithItsPillarsHeldToHalfTheirOwnCosine) {
  // knife_disc's rim is a 0.5° wedge: no pillar makes 0.01 with both sides (its pinch pillars
  // start at 0.0074). Under the absolute bound the coarsening kept 1,030 coarse faces (478
  // under the bare condition) and the min scaled Jacobian fell from 7.9e-4 to 1e-4; the rim's
  // 64 pillars now keep half their own starting cosine, every other pillar 0.01.
  const auto dir = test::scratch_dir("cli_mesh_knife_pillar_cos");
  std::string out;
  ASSERT_TRUE(generate("knife_disc", dir / "knife.obj"));
  ASSERT_EQ(test::run_command(cli() + " mesh -q " + (dir / "knife.obj").string() +
                                  " --order 3 --threads 1 -o " + (dir / "m").string(),
                              &out),
            0)
      << out;
  const auto r = read_json(dir / "m" / "report.json");
  const auto& c = r["coarsening"];
  EXPECT_EQ(c["pillar_cos_bound"].get<double>(), 0.01);
  EXPECT_EQ(c["pillar_cos_relative"].get<double>(), 0.5);
  EXPECT_EQ(c["pillar_cos_relaxed_pillars"].get<int>(), 64);
  const double floor = c["min_pillar_cos_bound"].get<double>();
  EXPECT_GT(floor, 0.003);
  EXPECT_LT(floor, 0.004);
  // verify_shell's own measure of the coarse shell, over every covered pair.
  EXPECT_GE(r["shell_min_pillar_cos"].get<double>(), floor);
  EXPECT_LT(r["coarse_faces"].get<int>(), 600);
  EXPECT_EQ(r["valid"], true);
  EXPECT_GT(r["min_scaled_jacobian"].get<double>(), 5e-4);
  // The rim's 64 edges are near folds (face normals turning by 179.2°): `check` warns of them and
  // so does the report; the coarse rim joins rim vertices further apart, so none is kept as it is
  // (input_floors; the coarse rim's own wedge is in validation.boundary_limits).
  ASSERT_EQ(r["input_warnings"].size(), 1u);
  EXPECT_EQ(r["input_warnings"][0]["kind"], "near_fold");
  EXPECT_EQ(r["input_warnings"][0]["count"], 64);
  EXPECT_EQ(r["input_floors"]["near_fold_edges"], 64);
  EXPECT_EQ(r["input_floors"]["near_fold_edges_kept"], 0);
  EXPECT_EQ(r["input_floors"]["tets_at_kept"], 0);
  EXPECT_LT(r["validation"]["boundary_limits"]["min_dihedral_deg"].get<double>(), 10.0);
  ASSERT_EQ(test::run_command(cli() + " check -q --json " + (dir / "knife.obj").string(), &out), 0)
      << out;
  const auto checked = nlohmann::json::parse(out);
  EXPECT_EQ(checked["acceptable"], true);
  EXPECT_EQ(checked["warnings"], r["input_warnings"]);
}

TEST(Cli, ShellRemeshSectionWritesSurfaceAndReport) {
  const auto dir = test::scratch_dir("cli_shell_remesh_section");
  io::write_surface(dir / "sphere.obj", make_icosphere(3), io::SurfaceFormat::obj);  // 1280 faces
  std::string out;
  ASSERT_EQ(test::run_command(cli() + " shell -q " + (dir / "sphere.obj").string() + " -o " +
                                  (dir / "out").string() +
                                  " --no-simplify --remesh-section 0.1 --threads 1",
                              &out),
            0)
      << out;
  const auto r = read_json(dir / "out" / "report.json");
  const auto& s = r["section_remesh"];
  EXPECT_DOUBLE_EQ(s["target_edge_rel"].get<double>(), 0.1);
  EXPECT_DOUBLE_EQ(s["target_edge"].get<double>(), 0.2);  // the bbox edge is 2
  EXPECT_EQ(s["is_section_verified"], true);
  EXPECT_EQ(s["field_roundtrip_failures"], 0);
  // Measured 0.07 (max) and 0.012 (mean) on this sphere.
  EXPECT_LT(s["field_roundtrip_max_error"].get<double>(), 0.15);
  EXPECT_LT(s["field_roundtrip_mean_error"].get<double>(), 0.03);
  const SurfaceMesh remeshed = io::read_surface(dir / "out" / "remeshed.obj");
  EXPECT_EQ(remeshed.num_faces(), s["faces"].get<int>());
  EXPECT_EQ(remeshed.num_vertices(), s["vertices"].get<int>());
}

TEST(Cli, ShellDisplacementMapRebuildsTheInputFromTheCageAndTheMap) {
  // noise_sphere_5 (adversarial corpus) and the beveled crater of the next test: the map is
  // baked on the refined surface there.
  const auto dir = test::scratch_dir("cli_shell_displacement");
  std::string out;
  ASSERT_TRUE(generate("noise_sphere_5", dir / "noisy.obj"));
  ASSERT_EQ(test::run_command(cli() + " shell -q " + (dir / "noisy.obj").string() + " -o " +
                                  (dir / "out").string() + " --displacement-map 3 --threads 1",
                              &out),
            0)
      << out;
  const auto r = read_json(dir / "out" / "report.json");
  const auto& d = r["displacement_map"];
  const int prisms = r["prisms"].get<int>();
  EXPECT_EQ(d["level"], 3);
  EXPECT_EQ(d["coarse_faces"], prisms);
  EXPECT_EQ(d["samples"], prisms * 10);
  EXPECT_EQ(d["failures"], 0);
  EXPECT_EQ(d["rebuilt_faces"], prisms * 9);
  EXPECT_EQ(d["rebuilt"]["vertices_not_located"], 0);
  EXPECT_LT(d["rebuilt"]["fiber_offset_max_rel"].get<double>(), 1e-12);
  EXPECT_LT(d["rebuilt"]["max_vertex_distance_rel"].get<double>(), 1e-13);
  EXPECT_EQ(d["rebuilt"]["self_intersecting_pairs"], 0);
  EXPECT_GT(d["along_normals"]["self_intersecting_pairs"].get<int>(), 0);
  // Measured 0.031 (through P) and 0.044 (along the normals, 280 pairs) of the bbox.
  EXPECT_LT(d["rebuilt"]["hausdorff_rel"].get<double>(),
            d["along_normals"]["hausdorff_rel"].get<double>());
  // The cage and the map are all the rebuilt surface needs: OBJ numbers are written with 17
  // digits, so displaced.obj's vertices are the ones rebuilt from the files.
  const SurfaceMesh cage = io::read_surface(dir / "out" / "cage.obj");
  const SurfaceMesh displaced = io::read_surface(dir / "out" / "displaced.obj");
  ASSERT_EQ(cage.num_vertices() % 3, 0);
  const int n = cage.num_vertices() / 3;
  meshing::shell::Shell shell;
  shell.base = cage.V.topRows(n);
  shell.mid = cage.V.middleRows(n, n);
  shell.top = cage.V.bottomRows(n);
  shell.F = cage.F.array() - n;
  const auto map =
      meshing::shell::read_displacement_map((dir / "out" / "displacement_map.txt").string());
  const auto rebuilt = meshing::shell::reconstruct(shell, map);
  EXPECT_EQ(rebuilt.mesh.F, displaced.F);
  EXPECT_LT((rebuilt.mesh.V - displaced.V).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(Cli, ShellNestedCagesAreWrittenCheckedAndReported) {
  const auto dir = test::scratch_dir("cli_shell_cages");
  std::string out;
  ASSERT_TRUE(generate("split_ring_01", dir / "ring.obj"));
  ASSERT_EQ(test::run_command(cli() + " shell -q " + (dir / "ring.obj").string() + " -o " +
                                  (dir / "out").string() + " --cages 2 --threads 1",
                              &out),
            0)
      << out;
  const auto r = read_json(dir / "out" / "report.json");
  const auto& c = r["nested_cages"];
  EXPECT_EQ(c["layers"], 2);
  EXPECT_EQ(c["intersecting_pairs_between_layers"], 0);
  EXPECT_EQ(c["between_layers"].size(), 3u);  // (input, 1), (input, 2), (1, 2)
  ASSERT_EQ(c["per_layer"].size(), 2u);
  for (const auto& l : c["per_layer"]) {
    EXPECT_EQ(l["shell_verified"], true);
    EXPECT_EQ(l["self_intersecting_pairs"], 0);
    EXPECT_NEAR(l["winding_number_of_layer_inside"].get<double>(), 1.0, 1e-9);
    EXPECT_GT(l["min_gap_to_layer_inside_rel"].get<double>(), 0.0);
    EXPECT_EQ(l["map_failures"], 0);
    EXPECT_LT(l["map_roundtrip_max_rel"].get<double>(), 1e-12);
    EXPECT_EQ(l["filled_points"], 0);  // no shell of zero thickness anywhere
    EXPECT_EQ(l["map_samples_on_fills"], 0);
    const SurfaceMesh cage = io::read_surface(dir / "out" / l["file"].get<std::string>());
    EXPECT_EQ(cage.num_faces(), l["faces"].get<int>());
  }
  EXPECT_GT(c["per_layer"][0]["self_intersecting_pairs_before_shrinking"].get<int>(), 0);
}

TEST(Cli, MeshMeanPolishLowersTheMeanCurvedMipsAndNoWorstCell) {
  // --optimize-mean-sweeps: stars holding a cell above curved MIPS 50 get their summed MIPS
  // lowered, their worst scaled Jacobian and MIPS no worse (torus_coarse, K = 3; without the flips
  // for the mean, which run after the polish).
  const auto dir = test::scratch_dir("cli_mesh_mean_polish");
  std::string out;
  ASSERT_TRUE(generate("torus_coarse", dir / "t.obj"));
  nlohmann::json r[2];
  for (int ms = 0; ms < 2; ++ms) {
    const auto o = dir / ("m" + std::to_string(ms));
    ASSERT_EQ(
        test::run_command(cli() + " mesh -q " + (dir / "t.obj").string() + " -o " + o.string() +
                              " --order 3 --threads 1 --optimize-no-mean-flips "
                              "--optimize-mean-sweeps " +
                              std::to_string(2 * ms),
                          &out),
        0)
        << out;
    r[ms] = read_json(o / "report.json");
    ASSERT_EQ(r[ms]["valid"], true);
  }
  const auto& v0 = r[0]["validation"];
  const auto& v1 = r[1]["validation"];
  const auto& w = r[1]["optimize"]["worst"];
  EXPECT_EQ(r[0]["optimize"]["worst"]["mean_mips_moves"], 0);
  EXPECT_GT(w["mean_mips_moves"].get<int>(), 0);
  EXPECT_EQ(r[0]["output_tets"], r[1]["output_tets"]);  // the polish only moves nodes
  EXPECT_LT(v1["mean_mips"].get<double>(), 0.99 * v0["mean_mips"].get<double>());
  EXPECT_LE(v1["max_mips"].get<double>(), v0["max_mips"].get<double>());
  EXPECT_GE(v1["min_scaled_jacobian"].get<double>(), v0["min_scaled_jacobian"].get<double>());
  EXPECT_NEAR(w["mean_mips_after"].get<double>(), v1["mean_mips"].get<double>(),
              1e-9 * v1["mean_mips"].get<double>());
  // It does not hang on the worst-cell sweeps: without them it still runs.
  ASSERT_EQ(test::run_command(cli() + " mesh -q " + (dir / "t.obj").string() + " -o " +
                                  (dir / "m2").string() +
                                  " --order 3 --threads 1 --optimize-worst-sweeps 0 "
                                  "--optimize-mean-sweeps 2",
                              &out),
            0)
      << out;
  EXPECT_GT(
      read_json(dir / "m2" / "report.json")["optimize"]["worst"]["mean_mips_moves"].get<int>(), 0);
  // The maps' guards are on unless --optimize-mean-free-nodes, which the report says.
  EXPECT_EQ(w["mean_mips_variation_guard"], true);
  ASSERT_EQ(test::run_command(cli() + " mesh -q " + (dir / "t.obj").string() + " -o " +
                                  (dir / "m3").string() +
                                  " --order 3 --threads 1 --optimize-mean-sweeps 2 "
                                  "--optimize-mean-free-nodes",
                              &out),
            0)
      << out;
  const auto r3 = read_json(dir / "m3" / "report.json");
  EXPECT_EQ(r3["optimize"]["worst"]["mean_mips_variation_guard"], false);
  EXPECT_EQ(r3["valid"], true);
}

TEST(Cli, MeshFlipsForTheMeanAreOnByDefaultAndKeepTheWorstCells) {
  // The flips for the mean run last (CurvedEditOptions::mean_flips): the mesh without them is the
  // mesh they start from, so its mean is the report's mean before; after them the mean is lower,
  // the worst MIPS no higher than max(before, 30), the min scaled Jacobian no lower than
  // min(before, 0.1). --optimize-no-mean-flips turns them off (torus_coarse, K = 3 and 4).
  const auto dir = test::scratch_dir("cli_mesh_mean_flips");
  std::string out;
  ASSERT_TRUE(generate("torus_coarse", dir / "t.obj"));
  for (int k : {3, 4}) {
    SCOPED_TRACE("order " + std::to_string(k));
    nlohmann::json r[2];
    for (int off = 0; off < 2; ++off) {
      const auto o = dir / ("m" + std::to_string(k) + std::to_string(off));
      ASSERT_EQ(test::run_command(cli() + " mesh -q " + (dir / "t.obj").string() + " -o " +
                                      o.string() + " --threads 1 --order " + std::to_string(k) +
                                      (off ? " --optimize-no-mean-flips" : ""),
                                  &out),
                0)
          << out;
      r[off] = read_json(o / "report.json");
      ASSERT_EQ(r[off]["valid"], true);
    }
    const auto& on = r[0]["validation"];
    const auto& off = r[1]["validation"];
    const auto& f = r[0]["optimize"]["curved_edits"]["mean_flips"];
    EXPECT_EQ(r[1]["optimize"]["curved_edits"]["mean_flips"]["flips"], 0);
    EXPECT_GT(f["flips"].get<int>(), 0);
    EXPECT_NEAR(f["mean_mips_before"].get<double>(), off["mean_mips"].get<double>(),
                1e-9 * off["mean_mips"].get<double>());
    EXPECT_NEAR(f["mean_mips_after"].get<double>(), on["mean_mips"].get<double>(),
                1e-9 * on["mean_mips"].get<double>());
    EXPECT_LT(on["mean_mips"].get<double>(), off["mean_mips"].get<double>());
    EXPECT_LE(on["max_mips"].get<double>(), std::max(off["max_mips"].get<double>(), 30.0));
    EXPECT_GE(on["min_scaled_jacobian"].get<double>(),
              std::min(off["min_scaled_jacobian"].get<double>(), 0.1) * (1 - 1e-9));
  }
}

TEST(Cli, ShellNestedCageIsFilledAtTheInputsSingularVertices) {
  // needle_sphere_8: 8 needle tips no direction sees, where the shell has zero thickness.
  const auto dir = test::scratch_dir("cli_shell_cages_fill");
  std::string out;
  ASSERT_TRUE(generate("needle_sphere_8", dir / "n.obj"));
  ASSERT_EQ(test::run_command(cli() + " shell -q " + (dir / "n.obj").string() + " -o " +
                                  (dir / "out").string() + " --cages 1 --threads 1",
                              &out),
            0)
      << out;
  const auto r = read_json(dir / "out" / "report.json");
  const auto& c = r["nested_cages"];
  EXPECT_EQ(c["intersecting_pairs_between_layers"], 0);
  const auto& l = c["per_layer"][0];
  EXPECT_EQ(l["singular_vertices"], 8);
  EXPECT_EQ(l["filled_points"], 8);
  EXPECT_EQ(l["unfilled_points"], 0);
  EXPECT_GT(l["fill_faces"].get<int>(), 0);
  EXPECT_GT(l["min_gap_to_layer_inside_rel"].get<double>(), 0.0);
  EXPECT_EQ(l["map_failures"], 0);
  EXPECT_LT(l["map_to_input_max_distance_rel"].get<double>(), 1e-12);
  EXPECT_LT(l["map_roundtrip_max_rel"].get<double>(), 1e-12);
  // Samples on the tetrahedra are not one to one; they cover a tiny share of the cage (2.5e-6
  // measured).
  EXPECT_GT(l["map_samples_on_fills"].get<int>(), 0);
  EXPECT_LT(l["map_area_share_on_fills"].get<double>(), 1e-4);
}

TEST(Cli, ShellGeometricTextureFromABuiltInTileAndAnObjTile) {
  const auto dir = test::scratch_dir("cli_shell_texture");
  io::write_surface(dir / "sphere.obj", make_icosphere(2), io::SurfaceFormat::obj);  // 320 faces
  std::string out;
  // Not simplified: the middle surface is the input, so the upper half (t > 1/2) is above it.
  ASSERT_EQ(test::run_command(cli() + " shell -q " + (dir / "sphere.obj").string() + " -o " +
                                  (dir / "knob").string() + " --no-simplify --texture knob",
                              &out),
            0)
      << out;
  const auto r = read_json(dir / "knob" / "report.json");
  const auto& t = r["geometric_texture"];
  EXPECT_EQ(t["copies"], 320);
  EXPECT_EQ(t["prisms_pinched_skipped"], 0);
  EXPECT_EQ(t["self_intersecting_pairs"], 0);
  EXPECT_EQ(t["pairs_with_input"], 0);
  EXPECT_EQ(t["degenerate_faces"], 0);
  EXPECT_GT(t["min_distance_to_input_rel"].get<double>(), 0.0);
  // The knob lies in the upper half only: the top surface was checked for self-intersections
  // (a sphere's has none), the base was not.
  EXPECT_EQ(t["shell_separation"]["top"]["self_intersecting_pairs_before"], 0);
  EXPECT_EQ(t["shell_separation"]["top"]["failure"], "");
  EXPECT_FALSE(t["shell_separation"].contains("base"));
  EXPECT_EQ(io::read_surface(dir / "knob" / "textured.obj").num_faces(), t["faces"].get<int>());
  // A tile of one's own: a tetrahedron in the upper half of the prism.
  std::ofstream(dir / "tet.obj") << "v 0.2 0.2 0.6\nv 0.6 0.2 0.6\nv 0.2 0.6 0.6\nv 0.3 0.3 0.9\n"
                                    "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";
  ASSERT_EQ(
      test::run_command(cli() + " shell -q " + (dir / "sphere.obj").string() + " -o " +
                            (dir / "tet").string() + " --texture " + (dir / "tet.obj").string(),
                        &out),
      0)
      << out;
  EXPECT_EQ(read_json(dir / "tet" / "report.json")["geometric_texture"]["self_intersecting_pairs"],
            0);
  // A tile reaching out of the prism is refused (exit 2), naming the vertex; no output folder.
  std::ofstream(dir / "bad.obj") << "v 0.2 0.2 0.6\nv 0.9 0.2 0.6\nv 0.2 0.6 0.6\nv 0.3 0.3 0.9\n"
                                    "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";
  EXPECT_EQ(
      test::run_command(cli() + " shell -q " + (dir / "sphere.obj").string() + " -o " +
                            (dir / "bad").string() + " --texture " + (dir / "bad.obj").string(),
                        &out),
      2)
      << out;
  EXPECT_NE(out.find("tile vertex 1"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad"));
}

TEST(Cli, ShellBooleanCarriesBothOperandsOntoTheCoarseResult) {
  const auto dir = test::scratch_dir("cli_shell_boolean");
  io::write_surface(dir / "a.obj", make_icosphere(3), io::SurfaceFormat::obj);
  io::write_surface(dir / "b.obj", make_icosphere(3, 0.7, Eigen::Vector3d(0.9, 0.3, 0.2)),
                    io::SurfaceFormat::obj);
  std::string out;
  ASSERT_EQ(test::run_command(cli() + " shell -q " + (dir / "a.obj").string() + " -o " +
                                  (dir / "u").string() + " --boolean union --with " +
                                  (dir / "b.obj").string() + " --threads 1",
                              &out),
            0)
      << out;
  const auto r = read_json(dir / "u" / "report.json");
  const auto& b = r["boolean"];
  EXPECT_EQ(b["operation"], "union");
  EXPECT_EQ(r["input_faces"], b["result_faces"]);  // the shell is built on the result
  EXPECT_GT(b["result_faces_from_a"].get<int>(), 0);
  EXPECT_GT(b["result_faces_from_b"].get<int>(), 0);
  EXPECT_EQ(b["result_self_intersecting_pairs"], 0);
  EXPECT_EQ(b["map_failures"], 0);
  EXPECT_LT(b["map_to_operand_max_distance_rel"].get<double>(), 1e-13);
  EXPECT_EQ(r["is_section_verified"], true);
  // Both fields reach the coarse result: each operand owns some of its vertices.
  const auto remeshed = io::read_vtu(dir / "u" / "remeshed.vtu");
  EXPECT_EQ(remeshed.mesh.num_cells(), b["remeshed_faces"].get<int>());
  const auto& fields = remeshed.fields.point_data;
  auto operand =
      std::find_if(fields.begin(), fields.end(), [](const auto& f) { return f.name == "operand"; });
  ASSERT_NE(operand, fields.end());
  EXPECT_GT(std::count(operand->values.begin(), operand->values.end(), 0.0), 0);
  EXPECT_GT(std::count(operand->values.begin(), operand->values.end(), 1.0), 0);
  // An open operand is refused before any corefinement, naming it; no output folder.
  SurfaceMesh open = make_icosphere(2);
  open.F.conservativeResize(open.F.rows() - 1, 3);
  io::write_surface(dir / "open.obj", open, io::SurfaceFormat::obj);
  EXPECT_EQ(test::run_command(cli() + " shell -q " + (dir / "a.obj").string() + " -o " +
                                  (dir / "x").string() + " --boolean union --with " +
                                  (dir / "open.obj").string(),
                              &out),
            2)
      << out;
  EXPECT_NE(out.find("open.obj is not a closed, embedded surface"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir / "x"));
}

TEST(Cli, ShellReportsBeveling) {
  const auto dir = test::scratch_dir("cli_shell_bevel");
  // The crater of tests/meshing/shell/test_shell_bevel.cpp: its own shell is no section.
  SurfaceMesh crater;
  crater.V.resize(9, 3);
  crater.V << 0.44, 0, 1.40, -0.04, -0.11, 0.95, -0.55, -0.22, 0.97, -0.60, 0.70, 0.78, 0.98, 0.57,
      0.90, 1.24, 0.30, 1.07, -0.08, 0.09, -1.45, 0.92, 0.81, 0.48, -0.35, -0.48, 1.14;
  crater.F.resize(14, 3);
  crater.F << 0, 5, 1, 5, 4, 1, 4, 7, 1, 7, 3, 1, 3, 2, 1, 2, 8, 1, 8, 0, 1, 5, 0, 6, 4, 5, 6, 7, 4,
      6, 3, 7, 6, 2, 3, 6, 8, 2, 6, 0, 8, 6;
  io::write_surface(dir / "crater.obj", crater, io::SurfaceFormat::obj);
  io::write_surface(dir / "sphere.obj", make_icosphere(2), io::SurfaceFormat::obj);
  std::string out;
  for (const char* name : {"crater", "sphere"}) {
    ASSERT_EQ(
        test::run_command(cli() + " shell -q " + (dir / (std::string(name) + ".obj")).string() +
                              " -o " + (dir / name).string() + " --threads 1 --displacement-map 2",
                          &out),
        0)
        << out;
  }
  const auto c = read_json(dir / "crater" / "report.json");
  EXPECT_EQ(c["beveling"], "applied");
  EXPECT_EQ(c["beveled_faces"], 10);
  EXPECT_EQ(c["non_section_prisms_before_beveling"], 2);
  EXPECT_EQ(c["input_faces"], 14);
  EXPECT_EQ(c["input_vertices"], 9);
  EXPECT_EQ(c["is_section_verified"], true);
  EXPECT_EQ(c["positive_verified"], true);
  EXPECT_EQ(c["intersection_free_verified"], true);
  EXPECT_EQ(c["roundtrip_failures"], 0);
  // The map is baked on the beveled surface, whose geometry is the crater's.
  EXPECT_EQ(c["displacement_map"]["failures"], 0);
  EXPECT_EQ(c["displacement_map"]["rebuilt"]["vertices_not_located"], 0);
  EXPECT_LT(c["displacement_map"]["rebuilt"]["max_vertex_distance_rel"].get<double>(), 1e-13);
  const auto s = read_json(dir / "sphere" / "report.json");
  EXPECT_EQ(s["beveling"], "not needed");
  EXPECT_EQ(s["beveled_faces"], 0);
}

// A self-intersecting input (thesis §4.5): refused by default with the reason and the way out
// (exit 2, nothing written); with --allow-self-intersections a locally injective shell, verified
// and reported as such; the applications that need an embedded shell are refused with it.
TEST(Cli, ShellOfASelfIntersectingInputIsLocallyInjectiveOnRequest) {
  const auto dir = test::scratch_dir("cli_shell_local_sheets");
  io::write_surface(dir / "eight.obj", make_figure_eight_tube(96, 10, 0.12),
                    io::SurfaceFormat::obj);  // 1920 faces
  const std::string in = (dir / "eight.obj").string();
  std::string out;
  // `check` refuses it and says what still works.
  EXPECT_EQ(test::run_command(cli() + " check " + in, &out), 2) << out;
  EXPECT_NE(out.find("--allow-self-intersections"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(cli() + " shell -q " + in + " -o " + (dir / "plain").string(), &out),
            2)
      << out;
  EXPECT_NE(out.find("self-intersecting face pairs"), std::string::npos) << out;
  EXPECT_NE(out.find("--allow-self-intersections"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir / "plain"));
  ASSERT_EQ(test::run_command(cli() + " shell -q " + in + " -o " + (dir / "local").string() +
                                  " --allow-self-intersections --threads 2",
                              &out),
            0)
      << out;
  const auto r = read_json(dir / "local" / "report.json");
  EXPECT_EQ(r["local_sheets"]["locally_injective_only"], true);
  EXPECT_GT(r["local_sheets"]["input_self_intersecting_pairs"].get<int>(), 0);
  EXPECT_GT(r["local_sheets"]["middle_self_intersecting_pairs"].get<int>(), 0);
  EXPECT_LT(r["prisms"].get<int>(), 1920 / 4);
  EXPECT_EQ(r["positive_verified"], true);
  EXPECT_EQ(r["intersection_free_verified"], true);
  EXPECT_EQ(r["is_section_verified"], true);
  EXPECT_EQ(r["roundtrip_failures"], 0);
  EXPECT_LT(r["roundtrip_max_error_rel"].get<double>(), 1e-12);
  EXPECT_EQ(io::read_surface(dir / "local" / "middle.obj").num_faces(), r["prisms"].get<int>());
  EXPECT_EQ(test::run_command(cli() + " shell -q " + in + " -o " + (dir / "remesh").string() +
                                  " --allow-self-intersections --remesh-section 0.05",
                              &out),
            2)
      << out;
  EXPECT_NE(out.find("need an embedded one"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir / "remesh"));
}

// Feature chains (the default): the box's edge vertices go inside coarse feature edges;
// boundary_map.json carries the feature edges and the reference copy's snapped vertices (with the
// shell's fibers), and `validate` re-checks both (the map roundtrip through the snapped copy, and
// every feature edge along a boundary edge).
TEST(Cli, MeshAlongFeatureChainsWritesAndValidatesThem) {
  const auto dir = test::scratch_dir("cli_mesh_chains");
  const SurfaceMesh box = make_box({0, 0, 0}, {1, 2, 1}, 4);  // 192 faces
  io::write_surface(dir / "box.obj", box, io::SurfaceFormat::obj);
  const std::string in = (dir / "box.obj").string(), out_dir = (dir / "m").string();
  std::string out;
  ASSERT_EQ(test::run_command(
                cli() + " mesh -q " + in + " -o " + out_dir + " --order 2 --threads 2", &out),
            0)
      << out;
  const auto j = read_json(dir / "m" / "report.json");
  EXPECT_TRUE(j["valid"].get<bool>());
  EXPECT_EQ(j["output_boundary_faces"], 12);
  EXPECT_EQ(j["coarsening"]["snapped_vertices"], 12 * 3);  // 12 edges of 4 steps
  EXPECT_EQ(j["validation"]["feature_edges"], 12 * 4);
  EXPECT_EQ(j["validation"]["features_off_boundary_edges"], 0);
  EXPECT_LT(j["map_roundtrip_max_error_rel"].get<double>(), 1e-12);
  ASSERT_EQ(test::run_command(cli() + " validate " + out_dir, &out), 0) << out;
  EXPECT_NE(out.find("feature edges        48, 0 not along a boundary edge"), std::string::npos)
      << out;
  // An edge vertex moved into its boundary triangle fails the check.
  auto map = read_json(dir / "m" / "boundary_map.json");
  ASSERT_EQ(map["fibers"]["reference"].size(), 36u);
  const int x = map["fibers"]["reference"][0][0].get<int>();
  map["vertex_uv"][x] = {0.2, 0.3};
  { std::ofstream(dir / "m" / "boundary_map.json") << map.dump(); }
  EXPECT_EQ(test::run_command(cli() + " validate " + out_dir, &out), 3) << out;
  EXPECT_NE(out.find("2 not along a boundary edge"), std::string::npos) << out;
}

TEST(Cli, MeshWithDistancePointsWritesAndValidatesThem) {
  const auto dir = test::scratch_dir("cli_mesh_points");
  const SurfaceMesh sphere = make_icosphere(2);  // 320 faces, 480 edges
  io::write_surface(dir / "sphere.obj", sphere, io::SurfaceFormat::obj);
  {
    std::ofstream(dir / "points.json") << "[[0, 0, 1], [" << sphere.V(7, 0) << ", "
                                       << sphere.V(7, 1) << ", " << sphere.V(7, 2) << "]]";
  }
  const std::string in = (dir / "sphere.obj").string(), out_dir = (dir / "m").string();
  std::string out;
  // (0, 0, 1) is a vertex of the icosphere; both points are on it.
  ASSERT_EQ(test::run_command(cli() + " mesh -q " + in + " -o " + out_dir +
                                  " --order 2 --eps 0.01 --threads 2 --eps-samples 2 "
                                  "--constraints " +
                                  (dir / "points.json").string(),
                              &out),
            0)
      << out;
  const auto j = read_json(dir / "m" / "report.json");
  EXPECT_EQ(j["distance_points"], 480 + 2);  // edge midpoints + the two constraint points
  EXPECT_EQ(j["validation"]["distance_points"], 482);
  EXPECT_LE(j["distance_points_max_distance_rel"].get<double>(), 0.01);
  EXPECT_TRUE(j["valid"].get<bool>());
  ASSERT_EQ(test::run_command(cli() + " validate " + out_dir, &out), 0) << out;
  EXPECT_NE(out.find("distance points      482"), std::string::npos) << out;
  // The validator reads the points back from boundary_map.json: one moved to another input face
  // fails it.
  auto map = read_json(dir / "m" / "boundary_map.json");
  const int t = map["distance_points"]["input_face"][0].get<int>();
  map["distance_points"]["input_face"][0] = (t + 160) % 320;
  { std::ofstream(dir / "m" / "boundary_map.json") << map.dump(); }
  EXPECT_EQ(test::run_command(cli() + " validate " + out_dir, &out), 3) << out;
  EXPECT_NE(out.find("EXCEEDS"), std::string::npos) << out;
  // A constraint point off the surface: exit 2, the point named, nothing written.
  { std::ofstream(dir / "off.json") << "[[0, 0, 0]]"; }
  EXPECT_EQ(test::run_command(cli() + " mesh -q " + in + " -o " + (dir / "x").string() +
                                  " --constraints " + (dir / "off.json").string(),
                              &out),
            2)
      << out;
  EXPECT_NE(out.find("constraint point 0"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir / "x"));
}

TEST(Cli, MeshWithAnEpsFieldSavesItAndTheValidatorChecksIt) {
  const auto dir = test::scratch_dir("cli_mesh_eps_field");
  const SurfaceMesh sphere = make_icosphere(3);  // 1280 faces
  io::write_surface(dir / "sphere.obj", sphere, io::SurfaceFormat::obj);
  const std::string in = (dir / "sphere.obj").string(), out_dir = (dir / "m").string();
  std::string out;
  ASSERT_EQ(test::run_command(cli() + " mesh -q " + in + " -o " + out_dir +
                                  " --order 2 --eps 0.01 --threads 2 --eps-field \"z > 0 ? 0.003 "
                                  ": 1\"",
                              &out),
            0)
      << out;
  const auto j = read_json(dir / "m" / "report.json");
  EXPECT_EQ(j["eps_field"], "z > 0 ? 0.003 : 1");
  EXPECT_TRUE(j["validation"]["eps_field"].get<bool>());
  EXPECT_LE(j["validation"]["max_distance_over_local_eps"].get<double>(), 1.0);
  EXPECT_TRUE(j["valid"].get<bool>());
  // min(eps, 1) = eps where z <= 0: factor 1; 0.3 where z > 0.
  auto map = read_json(dir / "m" / "boundary_map.json");
  ASSERT_EQ(map["eps_scale"].size(), std::size_t(sphere.num_vertices()));
  for (int v = 0; v < sphere.num_vertices(); ++v)
    EXPECT_DOUBLE_EQ(map["eps_scale"][std::size_t(v)].get<double>(), sphere.V(v, 2) > 0 ? 0.3 : 1)
        << v;
  ASSERT_EQ(test::run_command(cli() + " validate " + out_dir, &out), 0) << out;
  EXPECT_NE(out.find("eps field up to 0.01"), std::string::npos) << out;
  // The validator reads the field back: a tenth of ε everywhere fails it.
  for (auto& s : map["eps_scale"]) s = 0.1;
  { std::ofstream(dir / "m" / "boundary_map.json") << map.dump(); }
  EXPECT_EQ(test::run_command(cli() + " validate " + out_dir, &out), 3) << out;
  EXPECT_NE(out.find("EXCEEDS the local eps"), std::string::npos) << out;
  // A field that is not positive somewhere: exit 2 naming the vertex, nothing written.
  EXPECT_EQ(
      test::run_command(
          cli() + " mesh -q " + in + " -o " + (dir / "x").string() + " --eps-field \"x\"", &out),
      2)
      << out;
  EXPECT_NE(out.find("at input vertex"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir / "x"));
}

// --eps-levels (issue 22): one shell and one coarsening, a validated mesh folder per level.
TEST(Cli, MeshWithEpsLevelsWritesAValidFolderPerLevel) {
  const auto dir = test::scratch_dir("cli_mesh_eps_levels");
  const SurfaceMesh sphere = make_icosphere(3);  // 1280 faces
  io::write_surface(dir / "sphere.obj", sphere, io::SurfaceFormat::obj);
  const std::string in = (dir / "sphere.obj").string(), out_dir = (dir / "m").string();
  std::string out;
  ASSERT_EQ(test::run_command(cli() + " mesh -q " + in + " -o " + out_dir +
                                  " --order 2 --threads 2 --eps-levels 0.02,0.005",
                              &out),
            0)
      << out;
  const auto levels = read_json(dir / "m" / "levels.json");
  ASSERT_EQ(levels["levels"].size(), 2u);
  EXPECT_TRUE(levels["valid"].get<bool>());
  const auto& coarse = levels["levels"][0];
  const auto& fine = levels["levels"][1];
  EXPECT_EQ(coarse["dir"], "eps_0.02");
  EXPECT_EQ(fine["dir"], "eps_0.005");
  EXPECT_EQ(fine["coarsen_start_faces"].get<int>(), 0);
  EXPECT_EQ(coarse["coarsen_start_faces"].get<int>(), fine["coarse_faces"].get<int>());
  EXPECT_LT(coarse["coarse_faces"].get<int>(), fine["coarse_faces"].get<int>());
  EXPECT_GT(fine["shell_seconds"].get<double>(), 0);
  EXPECT_EQ(coarse["shell_seconds"].get<double>(), 0);
  for (const char* level : {"eps_0.02", "eps_0.005"}) {
    const auto j = read_json(dir / "m" / level / "report.json");
    EXPECT_TRUE(j["valid"].get<bool>()) << level;
    EXPECT_EQ(j["eps_levels"].size(), 2u);
    EXPECT_LE(j["max_distance_rel"].get<double>(), j["eps_rel"].get<double>()) << level;
    EXPECT_TRUE(std::filesystem::exists(dir / "m" / level / "boundary_map.json"));
    EXPECT_EQ(test::run_command(cli() + " validate " + (dir / "m" / level).string(), &out), 0)
        << out;
  }
  EXPECT_DOUBLE_EQ(read_json(dir / "m" / "eps_0.02" / "report.json")["eps_rel"].get<double>(),
                   0.02);
  // --eps and --eps-levels together, or a repeated level: refused, nothing written.
  EXPECT_NE(test::run_command(cli() + " mesh -q " + in + " -o " + (dir / "x").string() +
                                  " --eps 0.01 --eps-levels 0.02,0.01",
                              &out),
            0);
  EXPECT_EQ(test::run_command(cli() + " mesh -q " + in + " -o " + (dir / "x").string() +
                                  " --eps-levels 0.02,0.02",
                              &out),
            2)
      << out;
  EXPECT_NE(out.find("repeats level 1"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir / "x"));
}

TEST(Cli, GenerateWritesTheAdversarialSurfacesAndRefusesUnknownNames) {
  const auto dir = test::scratch_dir("cli_generate");
  std::string out;
  ASSERT_EQ(test::run_command(cli() + " generate --list", &out), 0) << out;
  EXPECT_NE(out.find("knife_disc_slivers"), std::string::npos) << out;
  EXPECT_NE(out.find("noise_sphere_20"), std::string::npos) << out;
  const std::string file = (dir / "kd.obj").string();
  ASSERT_EQ(test::run_command(cli() + " generate knife_disc_slivers -o " + file, &out), 0) << out;
  const SurfaceMesh m = io::read_surface(file);
  EXPECT_EQ(m.num_faces(), 1920);
  EXPECT_EQ(test::run_command(cli() + " check -q " + file, &out), 0) << out;
  // An unknown name: exit 2, naming the known ones, no file written.
  const std::string none = (dir / "none.obj").string();
  EXPECT_EQ(test::run_command(cli() + " generate no_such -o " + none, &out), 2);
  EXPECT_NE(out.find("known: knife_disc"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(none));
}

// `curvefem mesh -q IN -o OUT --order 3 --threads 1 [EXTRA]`: its report.json (a failure is
// recorded and an empty report returned when the run does not exit 0).
nlohmann::json mesh_k3_one_thread(const std::filesystem::path& in, const std::filesystem::path& out,
                                  const std::string& extra = "") {
  std::string log;
  const int rc = test::run_command(
      cli() + " mesh -q " + in.string() + " -o " + out.string() + " --order 3 --threads 1 " + extra,
      &log);
  if (rc != 0) {
    ADD_FAILURE() << "exit " << rc << ": " << log;
    return nlohmann::json{{"valid", false}, {"roundtrip_fallback", "?"}, {"validation", {}}};
  }
  return read_json(out / "report.json");
}

TEST(Cli, AChainSnapThatFlattensARefinedFaceIsRefusedAndTheRefinedMapRoundTrips) {
  // CGAL's part.off (libcgal-dev's data): a feature chain 16-18-20 over a cap 3.1e-3 high whose
  // base, the input edge 16-20, the shape refinement bisects. Snapping vertex 18 onto the coarse
  // edge 16-20 left the bisection point (rounded) and the snapped vertex collinear up to
  // rounding: the reference copy's faces there had 1e-14 of their input area, not exactly
  // degenerate, so the chain collapse accepted it, and P sent vertex 18 back 3.1e-3 away (the
  // mesher fell back to the unrefined input). The chain collapse now refuses a face flattened
  // below k_min_reference_area_ratio, and verify_shell counts such faces.
  const auto dir = test::scratch_dir("cli_part");
  const auto path = test::cgal_data_mesh("part", dir);
  if (!path) GTEST_SKIP() << test::k_no_cgal_data_message;
  const auto j = mesh_k3_one_thread(*path, dir / "m");
  EXPECT_TRUE(j["valid"].get<bool>());
  EXPECT_EQ(j["roundtrip_fallback"].get<std::string>(), "");
  EXPECT_GT(j["shape_refinement"]["bisections"].get<int>(), 0);  // the refinement is kept
  EXPECT_LE(j["map_roundtrip_max_error_rel"].get<double>(), 1e-6);
  std::string out;
  ASSERT_EQ(test::run_command(cli() + " validate " + (dir / "m").string(), &out), 0) << out;
}

TEST(Cli, TheWorstMipsSearchMayLowerACurvedNeighboursScaledJacobianALittle) {
  // CGAL's dino.off (libcgal-dev's data), K = 3: one slab tet of curved MIPS 1.67e4, the only
  // cell above the quality goal's 1e4. Moving its free corner by about 0.011 would bring it to
  // about 4.9e3, but every such move costs a curved neighbour (the star's smallest scaled
  // Jacobian, 0.0065, at its own optimum) a little, and the search refused any fall of the star's
  // minimum. With --optimize-worst-mips-sj-slack 0 (the old rule) the mesh keeps max MIPS 1.67e4;
  // with the default slack (10% in stars above 1e4) it ends at max MIPS 7.2e3 and min SJ 0.0068.
  const auto dir = test::scratch_dir("cli_dino_worst_mips");
  const auto path = test::cgal_data_mesh("dino", dir);
  if (!path) GTEST_SKIP() << test::k_no_cgal_data_message;
  const auto j = mesh_k3_one_thread(*path, dir / "m");
  EXPECT_TRUE(j["valid"].get<bool>());
  const auto& v = j["validation"];
  EXPECT_LT(v["max_mips"].get<double>(), 1e4);
  EXPECT_GT(v["min_scaled_jacobian"].get<double>(), 0.005);
  EXPECT_LE(v["tets_scaled_jacobian_below_0.01"].get<int>(), 2);
  EXPECT_GT(j["optimize"]["worst"]["mips_moves"].get<int>(), 0);
  // Without the slack the cell stays above the goal. (Measured without the flips for the mean,
  // which run after the search: since f531ca6 they flip that cell away too, to max MIPS 4.8e3
  // without the slack.)
  const auto strict = mesh_k3_one_thread(
      *path, dir / "strict", "--optimize-worst-mips-sj-slack 0 --optimize-no-mean-flips");
  EXPECT_TRUE(strict["valid"].get<bool>());
  EXPECT_GT(strict["validation"]["max_mips"].get<double>(), 1e4);
}

TEST(Cli, TheHandsWorstTetSitsOnAnInputFoldTheBoundaryKept) {
  // CGAL's hand.off (libcgal-dev's data), K = 3: a sliver 0.003 wide folded back by 177.9° on the
  // palm (input edges 1143-1185 and 1151-1185). `check` accepts it with a near_fold warning; the
  // coarse boundary keeps both edges as they are (the shell there is 3e-4 thick), and the slab tet
  // on them is the mesh's worst (curved MIPS 4.4e6): the report's input_floors says so.
  const auto dir = test::scratch_dir("cli_hand_floors");
  const auto path = test::cgal_data_mesh("hand", dir);
  if (!path) GTEST_SKIP() << test::k_no_cgal_data_message;
  std::string out;
  ASSERT_EQ(test::run_command(cli() + " check --json -q " + path->string(), &out), 0) << out;
  const auto c = nlohmann::json::parse(out);
  ASSERT_EQ(c["warnings"].size(), 2u) << out;
  EXPECT_EQ(c["warnings"][1]["kind"], "near_fold");
  EXPECT_EQ(c["warnings"][1]["ids"], nlohmann::json::parse("[1151, 1185, 1143, 1185]"));
  const auto j = mesh_k3_one_thread(*path, dir / "m");
  EXPECT_TRUE(j["valid"].get<bool>());
  const auto& f = j["input_floors"];
  EXPECT_EQ(f["near_fold_edges"], 2);
  EXPECT_EQ(f["near_fold_edges_kept"], 2);
  EXPECT_TRUE(f["worst_mips_tet_at_kept"].get<bool>());
  EXPECT_TRUE(f["worst_scaled_jacobian_tet_at_kept"].get<bool>());
  EXPECT_EQ(f["max_mips_at_kept"].get<double>(), j["validation"]["max_mips"].get<double>());
  EXPECT_EQ(j["input_warnings"].size(), 2u);
  // `validate` finds the same from the saved files.
  ASSERT_EQ(test::run_command(cli() + " validate --json -q " + (dir / "m").string(), &out), 0)
      << out;
  EXPECT_EQ(nlohmann::json::parse(out)["input_floors"], f);
  // The fold's short side (edge 1143-1185) is 0.003 of the bbox, below ε: `mesh` names the merge
  // that removes it, and with it the worst tet is 1.15e3 (the quality goal's 1e4 is met).
  EXPECT_NEAR(f["shortest_edge_at_kept_rel"].get<double>(), 0.00302, 1e-5);
  ASSERT_EQ(test::run_command(cli() + " mesh -q " + path->string() + " --order 3 --threads 1 -o " +
                                  (dir / "m2").string(),
                              &out),
            0)
      << out;
  EXPECT_NE(out.find("`--merge-short-edges 0.0032`"), std::string::npos) << out;
  ASSERT_EQ(test::run_command(cli() + " mesh -q " + path->string() +
                                  " --order 3 --threads 1 --merge-short-edges 0.0032 -o " +
                                  (dir / "merged").string(),
                              &out),
            0)
      << out;
  const auto merged = read_json(dir / "merged" / "report.json");
  EXPECT_EQ(merged["input_repair"]["merged"], 1);
  EXPECT_EQ(merged["input_floors"]["near_fold_edges"], 0);
  EXPECT_LT(merged["validation"]["max_mips"].get<double>(), 1e4);
  EXPECT_GT(merged["validation"]["min_scaled_jacobian"].get<double>(), 1e-3);
}

TEST(Cli, AnUnseenCadPartsShapeRefinedMapRoundTripsAtEitherPillarBound) {
  // CGAL's spool.off (libcgal-dev's data, a CAD part nobody here tuned for): with the default
  // shape refinement, φ of input vertex 31 (on a feature chain, on a coarse feature edge) pulled
  // back from just inside the triangle across that edge came back 7.4e-3 of the bounding box
  // away; the mesher then meshed the input again without the refinement (`roundtrip_fallback`).
  // Like CGAL's part.off (RefinedRoundTrip.*), a chain vertex snapped onto a coarse feature edge
  // of a shape-refined input: the chain collapse now refuses to flatten the reference copy's
  // faces, and the refined input round-trips under the bare section condition
  // (--shell-pillar-cos 0, where the miss was seen) and the default bound alike.
  const auto dir = test::scratch_dir("cli_spool");
  const auto path = test::cgal_data_mesh("spool", dir);
  if (!path) GTEST_SKIP() << test::k_no_cgal_data_message;
  const std::string in = path->string();
  std::string out;
  for (const char* bound : {"0", "0.01"}) {
    SCOPED_TRACE(bound);
    const std::string run = (dir / (std::string("m") + bound)).string();
    ASSERT_EQ(test::run_command(cli() + " mesh -q " + in + " -o " + run +
                                    " --order 3 --threads 2 --shell-pillar-cos " + bound,
                                &out),
              0)
        << out;
    const auto j = read_json(std::filesystem::path(run) / "report.json");
    EXPECT_TRUE(j["valid"].get<bool>());
    EXPECT_LE(j["map_roundtrip_max_error_rel"].get<double>(), 1e-6);
    EXPECT_EQ(j["roundtrip_fallback"].get<std::string>(), "");
    EXPECT_GT(j["shape_refinement"]["bisections"].get<int>(), 0);   // the refinement is kept
    EXPECT_GT(j["time_s"]["refined round trip"].get<double>(), 0);  // and checked
    EXPECT_EQ(j["coarsening"]["pillar_cos_bound"].get<double>(), std::stod(bound));
    EXPECT_EQ(j["shell_reference_collapsed_faces"].get<int>(), 0);
    if (std::string(bound) != "0") EXPECT_GE(j["shell_min_pillar_cos"].get<double>(), 0.01);
    ASSERT_EQ(test::run_command(cli() + " validate " + run, &out), 0) << out;
  }
}
