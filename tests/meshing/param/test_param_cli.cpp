// `curvefem param` on generated inputs: exit codes, the OBJ with vt (re-read here and re-checked
// with the exact verifier, independently of the CLI's own report), report.json fields.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "meshing/check/self_intersections.hpp"
#include "meshing/core/adversarial.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/param/uv_check.hpp"
#include "tests/meshing/param/param_inputs.hpp"
#include "tests/support/test_support.hpp"

using namespace curvefem;

namespace {

std::string cli() { return test::curvefem_executable().string(); }

nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

// vt rows and the vt ids of the faces of an OBJ written by `curvefem param`.
void read_uv_obj(const std::filesystem::path& p, Eigen::MatrixXd& uv, Eigen::MatrixXi& F,
                 Eigen::MatrixXi& Fv) {
  std::ifstream in(p);
  std::string line;
  std::vector<Eigen::Vector2d> vt;
  std::vector<Eigen::Vector3i> f, fv;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string kind;
    s >> kind;
    if (kind == "vt") {
      Eigen::Vector2d x;
      s >> x.x() >> x.y();
      vt.push_back(x);
    } else if (kind == "f") {
      Eigen::Vector3i a, b;
      for (int k = 0; k < 3; ++k) {
        char slash;
        s >> a[k] >> slash >> b[k];
      }
      fv.push_back(a.array() - 1);
      f.push_back(b.array() - 1);
    }
  }
  uv.resize(Eigen::Index(vt.size()), 2);
  for (std::size_t i = 0; i < vt.size(); ++i) uv.row(Eigen::Index(i)) = vt[i].transpose();
  F.resize(Eigen::Index(f.size()), 3);
  Fv.resize(Eigen::Index(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i) {
    F.row(Eigen::Index(i)) = f[i].transpose();
    Fv.row(Eigen::Index(i)) = fv[i].transpose();
  }
}

}  // namespace

TEST(ParamCli, GroupsBecomeChartsAndTheOutputIsBijective) {
  const auto dir = test::scratch_dir("param_cli_groups");
  SurfaceMesh disk = test::bump_disk(10, 40, 1.2, 0.3);
  disk.tags.resize(disk.num_faces());
  for (int f = 0; f < disk.num_faces(); ++f)
    disk.tags[f] =
        disk.V(disk.F(f, 0), 0) + disk.V(disk.F(f, 1), 0) + disk.V(disk.F(f, 2), 0) > 0 ? 1 : 2;
  disk.tag_names = {{1, "east"}, {2, "west"}};
  io::write_surface(dir / "disk.obj", disk, io::SurfaceFormat::obj);
  std::string out;
  ASSERT_EQ(test::run_command(cli() + " param -q " + (dir / "disk.obj").string() + " -o " +
                                  (dir / "uv.obj").string() + " --iterations 20 --report " +
                                  (dir / "report.json").string(),
                              &out),
            0)
      << out;
  const auto r = read_json(dir / "report.json");
  EXPECT_EQ(r["charts"], 2);
  EXPECT_EQ(r["faces"], disk.num_faces());
  EXPECT_EQ(r["flips"], 0);
  EXPECT_EQ(r["overlaps"], 0);
  EXPECT_EQ(r["bijective"], true);
  EXPECT_EQ(r["max_flips_over_iterations"], 0);
  EXPECT_EQ(r["max_overlaps_over_iterations"], 0);
  const auto& h = r["history"];
  ASSERT_EQ(h.size(), std::size_t(r["iterations"].get<int>() + 1));
  for (std::size_t i = 1; i < h.size(); ++i) {
    EXPECT_LE(h[i]["energy"].get<double>(), h[i - 1]["energy"].get<double>());
    EXPECT_EQ(h[i]["flips"], 0);
    EXPECT_EQ(h[i]["overlaps"], 0);
    EXPECT_GT(h[i]["min_singular_value"].get<double>(), 0);
    EXPECT_GT(h[i]["time_s"]["iteration"].get<double>(), 0);
  }
  EXPECT_GE(r["energy"].get<double>(), 4.0);
  EXPECT_LT(r["energy"].get<double>(), r["initial_energy"].get<double>());
  // The OBJ: same v and faces, a vt per UV vertex; checked again here from the file.
  Eigen::MatrixXd uv;
  Eigen::MatrixXi F, Fv;
  read_uv_obj(dir / "uv.obj", uv, F, Fv);
  EXPECT_EQ(uv.rows(), r["uv_vertices"].get<int>());
  EXPECT_GT(uv.rows(), disk.num_vertices());  // the group border is cut
  EXPECT_EQ(Fv, disk.F);
  const auto check = meshing::param::check_uv_map(uv, F);
  EXPECT_TRUE(check.bijective());
  EXPECT_EQ(check.components, 2);
  const SurfaceMesh back = io::read_surface(dir / "uv.obj");
  EXPECT_EQ(back.F, disk.F);
  EXPECT_EQ(back.tag_names.size(), 2u);
}

TEST(ParamCli, TorusNeedsSeams) {
  const auto dir = test::scratch_dir("param_cli_torus");
  auto [torus, seams] = test::cut_torus(2, 0.8, 30, 12);
  io::write_surface(dir / "torus.obj", torus, io::SurfaceFormat::obj);
  {
    std::ofstream s(dir / "seams.txt");
    s << "# meridian and longitude\n";
    for (const auto& e : seams) s << e[0] << ' ' << e[1] << '\n';
  }
  std::string out;
  // without seams: not a disk, exit 2, no output
  EXPECT_EQ(test::run_command(cli() + " param " + (dir / "torus.obj").string() + " -o " +
                                  (dir / "uv.obj").string(),
                              &out),
            2)
      << out;
  EXPECT_NE(out.find("chart 0"), std::string::npos) << out;
  EXPECT_NE(out.find("Euler characteristic 0"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir / "uv.obj"));
  // a malformed seam file: exit 2 naming file and line
  std::ofstream(dir / "bad.txt") << "0 1\n3 x\n";
  EXPECT_EQ(
      test::run_command(cli() + " param " + (dir / "torus.obj").string() + " -o " +
                            (dir / "uv.obj").string() + " --seams " + (dir / "bad.txt").string(),
                        &out),
      2)
      << out;
  EXPECT_NE(out.find("bad.txt:2"), std::string::npos) << out;
  ASSERT_EQ(test::run_command(
                cli() + " param -q " + (dir / "torus.obj").string() + " -o " +
                    (dir / "uv.obj").string() + " --seams " + (dir / "seams.txt").string() +
                    " --iterations 15 --newton 0 --report " + (dir / "report.json").string(),
                &out),
            0)
      << out;
  const auto r = read_json(dir / "report.json");
  EXPECT_EQ(r["charts"], 1);
  EXPECT_EQ(r["uv_vertices"], 30 * 12 + 30 + 12 + 1);
  EXPECT_EQ(r["flips"], 0);
  EXPECT_EQ(r["overlaps"], 0);
  EXPECT_LT(r["energy"].get<double>(), 4.3);
  EXPECT_EQ(r["newton_iterations"], 0);
  EXPECT_TRUE(r["newton_stop_reason"].is_null());
  // --newton: the SLIM iterations, then Newton ones, each named in the history and checked.
  ASSERT_EQ(test::run_command(cli() + " param -q " + (dir / "torus.obj").string() + " -o " +
                                  (dir / "uv_newton.obj").string() + " --seams " +
                                  (dir / "seams.txt").string() + " --iterations 15 --newton 10 " +
                                  "--report " + (dir / "newton.json").string(),
                              &out),
            0)
      << out;
  const auto n = read_json(dir / "newton.json");
  const int newton = n["newton_iterations"].get<int>();
  EXPECT_GT(newton, 0);
  EXPECT_LE(newton, 10);
  EXPECT_EQ(n["iterations"].get<int>(), r["iterations"].get<int>() + newton);
  EXPECT_EQ(n["history"].back()["method"], "newton");
  EXPECT_TRUE(n["history"].back().contains("gradient_norm"));
  EXPECT_EQ(n["max_flips_over_iterations"], 0);
  EXPECT_EQ(n["max_overlaps_over_iterations"], 0);
  EXPECT_LT(n["energy"].get<double>(), r["energy"].get<double>());
}

// --init-uv: the output of one run restarts the next from its own vt (same energy: the vt are
// written in round-trip precision); vt that are not a bijective map are refused (exit 2).
TEST(ParamCli, InitialMapFromTheInputTextureCoordinates) {
  const auto dir = test::scratch_dir("param_cli_init_uv");
  io::write_surface(dir / "disk.obj", test::bump_disk(8, 32, 1.0, 0.3), io::SurfaceFormat::obj);
  std::string out;
  ASSERT_EQ(test::run_command(cli() + " param -q " + (dir / "disk.obj").string() + " -o " +
                                  (dir / "uv.obj").string() + " --iterations 5 --report " +
                                  (dir / "r1.json").string(),
                              &out),
            0)
      << out;
  ASSERT_EQ(test::run_command(cli() + " param -q --init-uv " + (dir / "uv.obj").string() + " -o " +
                                  (dir / "uv2.obj").string() + " --iterations 5 --report " +
                                  (dir / "r2.json").string(),
                              &out),
            0)
      << out;
  const auto r1 = read_json(dir / "r1.json"), r2 = read_json(dir / "r2.json");
  EXPECT_EQ(r2["initial_map"], "input vt");
  // the same map (up to the summation order of the energy)
  EXPECT_NEAR(r2["initial_energy"].get<double>(), r1["energy"].get<double>(),
              1e-12 * r1["energy"].get<double>());
  EXPECT_LE(r2["energy"].get<double>(), r1["energy"].get<double>());
  // mirror the map: every face flips
  std::ifstream in(dir / "uv.obj");
  std::ofstream mirrored(dir / "mirrored.obj");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("vt ", 0) == 0) {
      std::istringstream s(line.substr(3));
      double u = 0, v = 0;
      s >> u >> v;
      std::ostringstream m;
      m.precision(17);
      m << "vt " << -u << ' ' << v;
      line = m.str();
    }
    mirrored << line << '\n';
  }
  mirrored.close();
  EXPECT_EQ(test::run_command(cli() + " param --init-uv " + (dir / "mirrored.obj").string() +
                                  " -o " + (dir / "uv3.obj").string(),
                              &out),
            2)
      << out;
  EXPECT_NE(out.find("not a bijective map"), std::string::npos) << out;
  const int faces = test::bump_disk(8, 32, 1.0, 0.3).num_faces();
  EXPECT_NE(out.find(std::to_string(faces) + " flipped"), std::string::npos) << out;
}

// `curvefem deform`: the split ring's end caps sent across each other. The naive targets make the
// surface cross itself; the deformed OBJ (re-read here) must not, exactly, and the report must
// carry the tiling's verification. Bad input: exit 2 and no output.
TEST(DeformCli, EndsOfASplitRingPulledAcrossStayApartAndBadInputIsRefused) {
  const auto dir = test::scratch_dir("deform_cli");
  const int n = 16;
  const SurfaceMesh ring = make_split_ring(1.0, 1.4, 0.4, 0.3, n);
  io::write_surface(dir / "ring.obj", ring, io::SurfaceFormat::obj);
  {
    std::ofstream t(dir / "targets.txt");
    t.precision(17);
    t << "# end caps swapped\n";
    for (int k = 0; k < 4; ++k) {
      const int a = k, b = 4 * n + k;
      t << a << ' ' << ring.V(b, 0) << ' ' << ring.V(b, 1) << ' ' << ring.V(b, 2) << '\n';
      t << b << ' ' << ring.V(a, 0) << ' ' << ring.V(a, 1) << ' ' << ring.V(a, 2) << '\n';
    }
  }
  const std::string in = (dir / "ring.obj").string(), out_obj = (dir / "closed.obj").string();
  std::string out;
  ASSERT_EQ(test::run_command(cli() + " deform -q " + in + " -o " + out_obj + " --targets " +
                                  (dir / "targets.txt").string() + " --iterations 20 --report " +
                                  (dir / "report.json").string(),
                              &out),
            0)
      << out;
  const auto r = read_json(dir / "report.json");
  EXPECT_GT(r["naive_self_intersecting_pairs"].get<int>(), 0);
  EXPECT_EQ(r["self_intersecting_pairs"], 0);
  EXPECT_EQ(r["max_self_intersecting_pairs_over_iterations"], 0);
  EXPECT_EQ(r["non_positive_tets"], 0);
  EXPECT_EQ(r["tiling_boundary_mismatches"], 0);
  EXPECT_EQ(r["valid"], true);
  // Each end can come at best halfway to its target (where the other end was): the two meet.
  EXPECT_LT(r["target_error_rel"].get<double>(),
            0.55 * r["initial_target_error_rel"].get<double>());
  const auto& h = r["history"];
  ASSERT_EQ(h.size(), std::size_t(r["iterations"].get<int>() + 1));
  for (std::size_t i = 1; i < h.size(); ++i) {
    EXPECT_LE(h[i]["objective"].get<double>(), h[i - 1]["objective"].get<double>());
    EXPECT_GT(h[i]["min_tet_volume_rel"].get<double>(), 0);
  }
  const SurfaceMesh closed = io::read_surface(dir / "closed.obj");
  EXPECT_EQ(closed.F, ring.F);
  EXPECT_EQ(check::count_self_intersecting_pairs(closed.V, closed.F), 0);
  EXPECT_EQ(r["sliver_rests"], false);
  // --sliver-rests: the flattened scaffold between the ends pushes back (Scaf3d test).
  ASSERT_EQ(test::run_command(cli() + " deform -q " + in + " -o " + (dir / "apart.obj").string() +
                                  " --targets " + (dir / "targets.txt").string() +
                                  " --iterations 20 --sliver-rests --report " +
                                  (dir / "apart.json").string(),
                              &out),
            0)
      << out;
  const auto a = read_json(dir / "apart.json");
  EXPECT_EQ(a["sliver_rests"], true);
  EXPECT_EQ(a["valid"], true);
  EXPECT_EQ(a["max_self_intersecting_pairs_over_iterations"], 0);
  int slivers = 0;
  for (const auto& it : a["history"]) slivers = std::max(slivers, it["slivers"].get<int>());
  EXPECT_GT(slivers, 0);
  // --untangle: the ring with its ends already swapped (self-intersecting) comes back embedded.
  SurfaceMesh tangled = ring;
  for (int k = 0; k < 4; ++k) tangled.V.row(k).swap(tangled.V.row(4 * n + k));
  io::write_surface(dir / "tangled.obj", tangled, io::SurfaceFormat::obj);
  ASSERT_EQ(test::run_command(cli() + " deform -q " + (dir / "tangled.obj").string() + " -o " +
                                  (dir / "untangled.obj").string() + " --untangle --report " +
                                  (dir / "untangle.json").string(),
                              &out),
            0)
      << out;
  const auto u = read_json(dir / "untangle.json");
  EXPECT_GT(u["untangle"]["input_self_intersecting_pairs"].get<int>(), 0);
  EXPECT_GE(u["untangle"]["flow_steps"].get<int>(), 1);
  EXPECT_EQ(u["untangle"]["pairs_after_each_flow_step"].back(), 0);
  EXPECT_LT(u["untangle"]["mean_distance_to_input_rel"].get<double>(), 0.01);
  EXPECT_EQ(u["self_intersecting_pairs"], 0);
  EXPECT_EQ(u["valid"], true);
  const SurfaceMesh untangled = io::read_surface(dir / "untangled.obj");
  EXPECT_EQ(check::count_self_intersecting_pairs(untangled.V, untangled.F), 0);
  // --untangle of an embedded surface: nothing to do (exit 2).
  EXPECT_EQ(test::run_command(
                cli() + " deform " + in + " -o " + (dir / "x.obj").string() + " --untangle", &out),
            2)
      << out;
  EXPECT_NE(out.find("no self-intersection"), std::string::npos) << out;
  // Bad input: a target vertex out of range (file:line), nothing to do, an open surface.
  std::ofstream(dir / "bad.txt") << "0 0 0 0\n999 1 1 1\n";
  EXPECT_EQ(test::run_command(cli() + " deform " + in + " -o " + (dir / "x.obj").string() +
                                  " --targets " + (dir / "bad.txt").string(),
                              &out),
            2)
      << out;
  EXPECT_NE(out.find("bad.txt:2"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(cli() + " deform " + in + " -o " + (dir / "x.obj").string(), &out), 2)
      << out;
  EXPECT_NE(out.find("nothing to do"), std::string::npos) << out;
  SurfaceMesh open = ring;
  open.F.conservativeResize(open.F.rows() - 1, 3);
  io::write_surface(dir / "open.obj", open, io::SurfaceFormat::obj);
  EXPECT_EQ(test::run_command(cli() + " deform " + (dir / "open.obj").string() + " -o " +
                                  (dir / "x.obj").string() + " --grow 1.5",
                              &out),
            2)
      << out;
  // The ARAP way back: without --arap nothing would pull the surface back; without --untangle
  // the flag means nothing. Both refused with exit 2 and no output.
  EXPECT_EQ(test::run_command(cli() + " deform " + (dir / "tangled.obj").string() + " -o " +
                                  (dir / "x.obj").string() + " --untangle --no-way-back-targets",
                              &out),
            2)
      << out;
  EXPECT_NE(out.find("ARAP"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(cli() + " deform " + in + " -o " + (dir / "x.obj").string() +
                                  " --grow 1.5 --no-way-back-targets",
                              &out),
            2)
      << out;
  EXPECT_NE(out.find("untangle option"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.obj"));
}
