// `curvefem run` on dense input surfaces (meshing.method curved | dense): boundary data painted on
// the input, the solution back on every input vertex, and broken cases that must leave nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "meshing/core/primitives.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/io/vtu_io.hpp"
#include "tests/support/test_support.hpp"

using namespace curvefem;

namespace {
std::string cli() { return test::curvefem_executable().string(); }

int run_case(const std::filesystem::path& file, const std::filesystem::path& out,
             std::string* log) {
  return test::run_command(cli() + " run -q " + file.string() + " -o " + out.string(), log);
}

nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

std::filesystem::path write_case(const std::filesystem::path& dir, const std::string& name,
                                 const std::string& text) {
  const auto file = dir / name;
  std::ofstream(file) << text;
  return file;
}

struct SphereRun {
  std::filesystem::path dir;
  int vertices = 0;       // of the input
  nlohmann::json report;  // null when the run did not exit 0 (the failure is recorded)
};
// Writes the level-L icosphere as sphere.obj and `text` as case.json in a scratch folder named
// `name`, and runs the case into dir/out.
SphereRun run_on_sphere(const std::string& name, int level, const std::string& text) {
  SphereRun run;
  run.dir = test::scratch_dir(name);
  const SurfaceMesh sphere = make_icosphere(level);
  run.vertices = sphere.num_vertices();
  io::write_surface(run.dir / "sphere.obj", sphere, io::SurfaceFormat::obj);
  std::string log;
  const int code = run_case(write_case(run.dir, "case.json", text), run.dir / "out", &log);
  EXPECT_EQ(code, 0) << log;
  if (code == 0) run.report = read_json(run.dir / "out" / "report.json");
  return run;
}

// A case on sphere.obj: the meshing object, the degree, and the remaining keys (physics, rhs,
// boundary conditions, exact; boundary_conditions after physics and rhs).
std::string sphere_case(const std::string& meshing, int degree, const std::string& rest) {
  return R"({"geometry": {"surface": "sphere.obj"}, "meshing": )" + meshing +
         R"(, "discretization": {"degree": )" + std::to_string(degree) + "},\n" + rest + "}";
}

// `text` with `entry` (e.g. "\"partial_dirichlet\": \"nodal\"") added to its discretization.
std::string with_discretization(std::string text, const std::string& entry) {
  const std::string key = R"("discretization": {)";
  text.insert(text.find(key) + key.size(), entry + ", ");
  return text;
}

// Poisson with u = x² + y² + z² (−Δu = −6) on a sphere of radius 1, Dirichlet data painted on
// the whole input, a Neumann flux on the top cap (∂u/∂n = 2r = 2 there).
std::string poisson_case(const std::string& meshing) {
  return sphere_case(meshing, 2, R"JSON(
  "physics": {"type": "poisson"},
  "rhs": "-6",
  "boundary_conditions": [
    {"type": "dirichlet", "select": {"not": {"plane": {"point": [0, 0, 0.7], "normal": [0, 0, 1]}}},
     "value": "x*x+y*y+z*z"},
    {"type": "neumann", "select": {"plane": {"point": [0, 0, 0.7], "normal": [0, 0, 1]}},
     "value": "2*sqrt(x*x+y*y+z*z)"}
  ],
  "exact": "x*x+y*y+z*z")JSON");
}

void expect_surface_output(const std::filesystem::path& out, int input_vertices,
                           const std::string& bc_field = "bc1_neumann") {
  ASSERT_TRUE(std::filesystem::exists(out / "surface.vtu"));
  ASSERT_TRUE(std::filesystem::exists(out / "volume.vtu"));
  ASSERT_TRUE(std::filesystem::exists(out / "result.pvd"));
  ASSERT_TRUE(std::filesystem::exists(out / "resolved_case.json"));
  const io::VtuContent surface = io::read_vtu(out / "surface.vtu");
  EXPECT_EQ(surface.mesh.num_nodes(), input_vertices);
  bool has_u = false, has_error = false, has_bc = false;
  for (const auto& f : surface.fields.point_data) {
    if (f.name == "u") {
      has_u = true;
      ASSERT_EQ(f.values.size(), std::size_t(input_vertices));
      for (double v : f.values) EXPECT_TRUE(std::isfinite(v));
    }
    has_error |= f.name == "error";
  }
  for (const auto& f : surface.fields.cell_data) has_bc |= f.name == bc_field;
  EXPECT_TRUE(has_u);
  EXPECT_TRUE(has_error);
  EXPECT_TRUE(has_bc);
}
}  // namespace

TEST(RunSurface, CurvedPoissonOnSphereMatchesExactSolutionOnTheInput) {
  // Measured with the linear coarsening bound (the curved-aware one gives fewer, larger faces and
  // a larger discretization error: l2 3.2e-2, surface max 0.18).
  const SphereRun run = run_on_sphere(
      "run_surface_curved", 3,
      poisson_case(R"({"method": "curved", "order": 2, "eps": 0.01, "curved_coarsening": false})"));
  ASSERT_FALSE(run.report.is_null());
  const auto& r = run.report;
  EXPECT_EQ(r["method"], "curved");
  EXPECT_EQ(r["order"], 2);
  EXPECT_GT(r["dofs"].get<int>(), 0);
  EXPECT_LT(r["tets"].get<int>(), 2000);
  EXPECT_EQ(r["meshing"]["input_vertices"], run.vertices);
  // u is quadratic and p = k = 2, so what remains is (a) the geometric error — the curved boundary
  // is within ε of the faceted input and Dirichlet data are read on the input — and (b) the
  // point-wise Dirichlet/Neumann interface at z = 0.7 cutting through coarse faces, imposed there
  // by Nitsche's method (34 faces). Measured: l2 1.0e-3, surface l2 1.7e-2, surface max 1.1e-2.
  // The all-Dirichlet case below isolates (a). A wrong φ⁻¹ or transfer gives O(1) errors.
  EXPECT_LT(r["l2_error"].get<double>(), 3e-3);
  EXPECT_LT(r["surface_l2_error"].get<double>(), 3e-2);
  EXPECT_LT(r["surface_max_error"].get<double>(), 3e-2);
  EXPECT_GT(r["physics_details"]["nitsche_faces"].get<int>(), 0);
  EXPECT_EQ(r["surface_unmapped_vertices"], 0);
  expect_surface_output(run.dir / "out", run.vertices);
  // Fixing only the DOFs the selection covers on the cut faces leaves the flux missing on their
  // Dirichlet part: the largest errors then sit at z ≈ 0.7. Measured: l2 1.7e-2, surface max
  // 0.11.
  const SphereRun nodal = run_on_sphere(
      "run_surface_curved_nodal", 3,
      with_discretization(poisson_case(R"({"method": "curved", "order": 2, "eps": 0.01,
                                           "curved_coarsening": false})"),
                          R"("partial_dirichlet": "nodal")"));
  ASSERT_FALSE(nodal.report.is_null());
  EXPECT_EQ(nodal.report["physics_details"]["nitsche_faces"], 0);
  EXPECT_GT(nodal.report["l2_error"].get<double>(), 5 * r["l2_error"].get<double>());
}

TEST(RunSurface, OrderAboveTheDegreeIsSolvedOnTheDegreePInterpolant) {
  // Issue 20: k = 3, p = 2 on the curved sphere, u linear. `curvefem run` solves on the certified
  // degree-2 interpolant of the order-3 maps (discretization.geometry "iso"), where P2 holds u;
  // on the order-3 maps ("mesh") it does not. The top cap's flux is read through φ⁻¹ at the
  // solver's points on the lowered boundary, the rest is Dirichlet data painted on the input.
  // Measured: H1 error 2.6e-2 (iso, the geometric error of reading data through φ) against
  // 1.4e-1 (mesh).
  const std::string text =
      sphere_case(R"({"method": "curved", "order": 3, "eps": 0.01})", 2, R"JSON(
  "physics": {"type": "poisson"},
  "boundary_conditions": [
    {"type": "dirichlet", "select": {"not": {"plane": {"point": [0, 0, 0.7], "normal": [0, 0, 1]}}},
     "value": "x + 2*y - z"},
    {"type": "neumann", "select": {"plane": {"point": [0, 0, 0.7], "normal": [0, 0, 1]}},
     "value": "nx + 2*ny - nz"}
  ],
  "exact": "x + 2*y - z")JSON");
  const SphereRun iso = run_on_sphere("run_surface_iso", 3, text);
  const SphereRun mesh =
      run_on_sphere("run_surface_iso_mesh", 3, with_discretization(text, R"("geometry": "mesh")"));
  ASSERT_FALSE(iso.report.is_null());
  ASSERT_FALSE(mesh.report.is_null());
  const auto& g = iso.report["solve_geometry"];
  EXPECT_EQ(g["mode"], "iso");
  EXPECT_EQ(g["mesh_order"], 3);
  EXPECT_EQ(g["degree"], 2);
  EXPECT_LT(g["tets_kept_at_mesh_order"].get<int>(), iso.report["tets"].get<int>() / 20);
  EXPECT_EQ(mesh.report["solve_geometry"]["degree"], 3);
  const double e_iso = iso.report["h1_semi_error"].get<double>();
  const double e_mesh = mesh.report["h1_semi_error"].get<double>();
  std::printf("linear u, k = 3, p = 2: H1 error iso %.3e, mesh %.3e\n", e_iso, e_mesh);
  EXPECT_LT(e_iso, 0.5 * e_mesh);
  EXPECT_EQ(iso.report["surface_unmapped_vertices"], 0);
}

TEST(RunSurface, CurvedDirichletPoissonIsoparametricIsWithinTheGeometricError) {
  // The linear coarsening bound (with the curved-aware one, fewer and larger faces: l2 2.9e-3).
  std::string text =
      poisson_case(R"({"method": "curved", "order": 2, "eps": 0.01, "curved_coarsening": false})");
  text = text.substr(0, text.find("\"boundary_conditions\"")) +
         R"("boundary_conditions": [{"type": "dirichlet", "select": {"all": true},
                               "value": "x*x+y*y+z*z"}],
  "exact": "x*x+y*y+z*z",
  "output": {"surface_values": "image"}
})";
  // "image": u_h(φ(v)) on the input, what this test measures ("extended" gives every vertex its
  // Dirichlet data here).
  const SphereRun run = run_on_sphere("run_surface_curved_dirichlet", 3, text);
  ASSERT_FALSE(run.report.is_null());
  const auto& r = run.report;
  // p = k = 2: every boundary DOF is a fiber hit on the input, so the Dirichlet data are exact at
  // the DOFs and u = r² is in the space up to the geometric error. Measured: l2 4.8e-4, h1 1.5e-2,
  // surface max 9.1e-3 (≈ the 1.8e-3 boundary distance times |∇u| = 2, plus interpolation).
  EXPECT_LT(r["l2_error"].get<double>(), 2e-3);
  EXPECT_LT(r["h1_error"].get<double>(), 5e-2);
  EXPECT_LT(r["surface_max_error"].get<double>(), 3e-2);
}

TEST(RunSurface, ExtendedSurfaceValuesRemoveTheOffsetErrorAndKeepTheDirichletData) {
  // The mixed case above at k = p = 2: on the Neumann cap u_h is read at φ(v), up to ε away
  // from v, an error ∇u·(φ(v) − v) that "extended" removes to first order; below z = 0.7 the
  // Dirichlet data hold, and the value at v is g(v) itself. Measured: surface l2 1.69e-2 ->
  // 2.03e-3, max 1.09e-2 -> 4.89e-3.
  const std::string text =
      poisson_case(R"({"method": "curved", "order": 2, "eps": 0.01, "curved_coarsening": false})");
  const SphereRun ext = run_on_sphere("run_surface_extended", 3, text);
  std::string image_text = text;
  image_text.insert(image_text.rfind('}'), R"(, "output": {"surface_values": "image"})");
  const SphereRun img = run_on_sphere("run_surface_image", 3, image_text);
  ASSERT_FALSE(ext.report.is_null());
  ASSERT_FALSE(img.report.is_null());
  const auto& e = ext.report;
  const auto& i = img.report;
  std::printf("surface l2 / max: image %.3e / %.3e, extended %.3e / %.3e\n",
              i["surface_l2_error"].get<double>(), i["surface_max_error"].get<double>(),
              e["surface_l2_error"].get<double>(), e["surface_max_error"].get<double>());
  EXPECT_EQ(e["l2_error"], i["l2_error"]);  // the same solve
  EXPECT_LT(e["surface_l2_error"].get<double>(), 0.5 * i["surface_l2_error"].get<double>());
  EXPECT_LT(e["surface_max_error"].get<double>(), i["surface_max_error"].get<double>());
  const int held = e["surface_values"]["dirichlet_data_vertices"].get<int>();
  const int moved = e["surface_values"]["extended_vertices"].get<int>();
  EXPECT_GT(held, 0);
  EXPECT_GT(moved, 0);
  EXPECT_EQ(held + moved, ext.vertices);
  EXPECT_EQ(i["surface_values"]["extended_vertices"], 0);
  // Below the plane the value is the data (the exact solution, up to rounding in the two
  // evaluators); above it, an error of the solve.
  const io::VtuContent surface = io::read_vtu(ext.dir / "out" / "surface.vtu");
  const Field* error = nullptr;
  for (const auto& f : surface.fields.point_data)
    if (f.name == "error") error = &f;
  ASSERT_NE(error, nullptr);
  int below = 0;
  double above_max = 0;
  for (int v = 0; v < surface.mesh.num_nodes(); ++v) {
    if (surface.mesh.nodes(v, 2) < 0.7 - 1e-9) {
      ++below;
      EXPECT_LT(std::abs(error->values[std::size_t(v)]), 1e-14) << v;  // data = exact here
    } else if (surface.mesh.nodes(v, 2) > 0.7 + 1e-9) {
      above_max = std::max(above_max, std::abs(error->values[std::size_t(v)]));
    }
  }
  EXPECT_GT(below, 0);
  EXPECT_GT(above_max, 0.0);
}

TEST(RunSurface, DensePoissonOnSphereMatchesExactSolutionOnTheInput) {
  const SphereRun run =
      run_on_sphere("run_surface_dense", 2, poisson_case(R"({"method": "dense"})"));
  ASSERT_FALSE(run.report.is_null());
  const auto& r = run.report;
  EXPECT_EQ(r["method"], "dense");
  EXPECT_EQ(r["order"], 1);
  // P1 on the input polyhedron; the plane z = 0.7 cuts input faces (Nitsche there). Measured: l2
  // 1.7e-3, surface l2 4.7e-3, surface max 5.1e-3 (fixing the covered DOFs only: 5.3e-3, 1.2e-2,
  // 1.6e-2).
  EXPECT_LT(r["l2_error"].get<double>(), 4e-3);
  // φ = identity: Dirichlet vertices carry the exact value; the Neumann cap is approximate.
  EXPECT_LT(r["surface_l2_error"].get<double>(), 1e-2);
  EXPECT_LT(r["surface_max_error"].get<double>(), 1e-2);
  EXPECT_EQ(r["tets"].get<int>() > 0, true);
  expect_surface_output(run.dir / "out", run.vertices);
  // The resolved case is a valid case file that reproduces the run.
  std::string log;
  ASSERT_EQ(run_case(run.dir / "out" / "resolved_case.json", run.dir / "again", &log), 0) << log;
  const auto again = read_json(run.dir / "again" / "report.json");
  EXPECT_EQ(again["dofs"], r["dofs"]);
  EXPECT_EQ(again["surface_l2_error"], r["surface_l2_error"]);
}

TEST(RunSurface, BrokenCasesExitTwoNameTheJsonPathAndLeaveNothing) {
  const auto dir = test::scratch_dir("run_surface_bad");
  io::write_surface(dir / "sphere.obj", make_icosphere(1), io::SurfaceFormat::obj);
  SurfaceMesh open = make_icosphere(1);
  open.F.conservativeResize(open.F.rows() - 1, 3);
  io::write_surface(dir / "open.obj", open, io::SurfaceFormat::obj);
  const std::string dirichlet =
      R"("boundary_conditions": [{"type": "dirichlet", "select": {"all": true}, "value": 0}])";
  struct Bad {
    std::string body, expected;
  } cases[] = {
      {R"("geometry": {"surface": "sphere.obj"}, "meshing": {"method": "dense", "ordr": 2}, )" +
           dirichlet,
       "/meshing/ordr: unknown key"},
      {R"("geometry": {"surface": "sphere.obj"}, "meshing": {"curved_coarsening": "yes"}, )" +
           dirichlet,
       "/meshing/curved_coarsening: expected true/false"},
      {R"("geometry": {"surface": "sphere.obj"}, "meshing": {"method": "dense", "curved_coarsening": false}, )" +
           dirichlet,
       "/meshing/curved_coarsening: only for method \"curved\""},
      {R"("geometry": {"surface": "missing.obj"}, )" + dirichlet,
       "/geometry/surface: file not found"},
      {R"("geometry": {"surface": "open.obj"}, "meshing": {"method": "dense"}, )" + dirichlet,
       "/geometry/surface: not a valid meshing input"},
      {R"("geometry": {"surface": "sphere.obj"}, "meshing": {"method": "dense"},
         "boundary_conditions": [{"type": "dirichlet", "select": {"and": [{"box": [[5,5,5],[6,6,6]]}]}, "value": 0}])",
       "/boundary_conditions/0/select: selects nothing on the input surface"},
      {R"("geometry": {"surface": "sphere.obj"}, "meshing": {"method": "dense"},
         "boundary_conditions": [{"type": "dirichlet", "select": {"or": [{"all": true}, {"normal": {"direction": [0,0,0]}}]}, "value": 0}])",
       "/boundary_conditions/0/select/or/1/normal/direction: must be a non-zero vector"},
      {R"("geometry": {"builtin_surface": {"shape": "sphere", "level": 1, "R": 2}}, )" + dirichlet,
       "/geometry/builtin_surface/R: only for the torus"},
      {R"("geometry": {"surface": "sphere.obj"}, "boundary_conditions": [{"type": "dirichlet", "select": {"all": true}, "value": "x+"}])",
       "/boundary_conditions/0/value: bad expression"},
      {R"("geometry": {"surface": "sphere.obj"}, "meshing": {"method": "dense"},
         "boundary_conditions": [{"type": "dirichlet", "select": {"not": {"outer_box": "all"}}, "value": 0}])",
       "/boundary_conditions/0/select: outer_box needs meshing.exterior: true"},
      {R"("geometry": {"surface": "sphere.obj"}, "meshing": {"method": "dense", "exterior": true},
         "boundary_conditions": [{"type": "dirichlet", "select": {"outer_box": "top"}, "value": 0}])",
       "/boundary_conditions/0/select/outer_box: 'top': expected all, xmin"},
      {R"("geometry": {"surface": "sphere.obj"}, "meshing": {"method": "dense", "padding": 0.5}, )" +
           dirichlet,
       "/meshing/padding: only with \"exterior\": true"},
      {R"("geometry": {"surface": "sphere.obj"}, "meshing": {"method": "dense", "exterior": true, "solve_on": "both"},
         "boundary_conditions": [{"type": "dirichlet", "select": {"all": true}, "value": 0}])",
       "/boundary_conditions/0/select: with meshing.solve_on \"both\" the input surface is inside"},
      {R"("geometry": {"surface": "sphere.obj"}, "meshing": {"method": "dense", "exterior": true},
         "physics": {"kappa_inside": 2}, )" +
           dirichlet,
       "/physics/kappa_inside: only with meshing.solve_on \"both\""},
      {R"("geometry": {"surface": "sphere.obj"}, "meshing": {"method": "dense"},
         "physics": {"type": "linear_elasticity", "E_inside": 2},
         "boundary_conditions": [{"type": "dirichlet", "select": {"all": true}, "value": [0, 0, 0]}])",
       "/physics/E_inside: only with meshing.solve_on \"both\""},
      {R"("geometry": {"surface": "sphere.obj"}, "meshing": {"method": "dense"},
         "physics": {"type": "neo_hookean"}, "discretization": {"boundary_values_at": "shifted"},
         "boundary_conditions": [{"type": "dirichlet", "select": {"all": true}, "value": [0, 0, 0]}])",
       "/discretization/boundary_values_at: \"shifted\" is for the linear problems"},
      {R"("geometry": {"surface": "sphere.obj"}, "discretization": {"boundary_values_at": "moved"}, )" +
           dirichlet,
       "/discretization/boundary_values_at: 'moved': expected input, mesh or shifted"},
  };
  for (const auto& c : cases) {
    const auto file = write_case(dir, "case.json", "{" + c.body + "}");
    std::string log;
    const auto out = dir / "out";
    EXPECT_EQ(run_case(file, out, &log), 2) << c.body << "\n" << log;
    EXPECT_NE(log.find(c.expected), std::string::npos) << c.expected << "\n" << log;
    // One message line on stderr.
    EXPECT_LE(std::count(log.begin(), log.end(), '\n'), 1) << log;
    EXPECT_FALSE(std::filesystem::exists(out)) << c.body;
  }
}

TEST(RunSurface, ShippedCurvedCaseRuns) {
  const auto dir = test::scratch_dir("run_surface_shipped");
  std::string log;
  ASSERT_EQ(run_case(test::source_dir() / "cases/poisson_curved_sphere.json", dir / "out", &log), 0)
      << log;
  const auto r = read_json(dir / "out" / "report.json");
  EXPECT_EQ(r["method"], "curved");
  // Measured: l2 7.0e-4, surface l2 8.4e-3 (before the cut faces were imposed by Nitsche: l2
  // 7.6e-3, surface l2 3.0e-2).
  EXPECT_LT(r["l2_error"].get<double>(), 2e-3);
  EXPECT_LT(r["surface_l2_error"].get<double>(), 2e-2);
}

namespace {
// Exterior Poisson around the unit sphere, out to the box padded by 0.25 × 2: u = 1/r is harmonic
// there. Dirichlet on the outer box (outer_box) and on the sphere below z = 0.2; on the cap above
// it a Neumann flux with the *exterior* domain's outward normal, −r̂: ∂u/∂n = −∂u/∂r = 1/r².
std::string exterior_case(const std::string& meshing, int degree) {
  return sphere_case(meshing, degree, R"JSON(
  "physics": {"type": "poisson"},
  "boundary_conditions": [
    {"type": "dirichlet", "select": {"outer_box": "all"}, "value": "1/sqrt(x*x+y*y+z*z)"},
    {"type": "dirichlet", "select": {"not": {"plane": {"point": [0, 0, 0.2], "normal": [0, 0, 1]}}},
     "value": "1/sqrt(x*x+y*y+z*z)"},
    {"type": "neumann", "select": {"plane": {"point": [0, 0, 0.2], "normal": [0, 0, 1]}},
     "value": "1/(x*x+y*y+z*z)"}
  ],
  "exact": "1/sqrt(x*x+y*y+z*z)")JSON");
}
}  // namespace

TEST(RunSurface, CurvedExteriorPoissonAroundSphereMatchesOneOverR) {
  const SphereRun run = run_on_sphere(
      "run_surface_exterior", 3,
      exterior_case(R"({"method": "curved", "order": 2, "eps": 0.01, "exterior": true})", 2));
  ASSERT_FALSE(run.report.is_null());
  const auto& r = run.report;
  ASSERT_TRUE(r["meshing"].contains("exterior")) << r.dump(1);
  // The domain is the outer slab layer and the exterior only (tags 3, 4).
  EXPECT_EQ(r["tets"],
            r["meshing"]["outer_slab_tets"].get<int>() + r["meshing"]["exterior_tets"].get<int>());
  EXPECT_TRUE(r["mesh_valid"].get<bool>());
  // The box is the sphere's bounding box padded by 0.25 × its longest edge (2): the outer slab
  // surface stays more than 0.125 inside it.
  const auto box = r["meshing"]["exterior"]["box"];
  for (int a = 0; a < 3; ++a) {
    EXPECT_DOUBLE_EQ(box[0][a].get<double>(), -1.5);
    EXPECT_DOUBLE_EQ(box[1][a].get<double>(), 1.5);
  }
  // Measured (140 coarse faces, 908 tets, 1,556 DOFs): l2 6.5e-3, surface l2 9.6e-3, surface
  // max 4.8e-3 (u = 1 on the sphere; ε = 0.02 with |∇u| = 1 there; the Dirichlet/Neumann
  // interface at z = 0.2 by Nitsche, 26 faces; fixing the covered DOFs only: l2 2.0e-2, surface
  // max 6.7e-2). The same run with the flux's sign flipped (the interior's normal) gives l2 0.67,
  // surface max 0.78.
  EXPECT_LT(r["l2_error"].get<double>(), 1.5e-2);
  EXPECT_LT(r["surface_l2_error"].get<double>(), 2e-2);
  EXPECT_LT(r["surface_max_error"].get<double>(), 1.5e-2);
  EXPECT_EQ(r["surface_unmapped_vertices"], 0);
  expect_surface_output(run.dir / "out", run.vertices, "bc2_neumann");
}

TEST(RunSurface, DenseExteriorPoissonAroundSphereMatchesOneOverR) {
  const SphereRun run = run_on_sphere("run_surface_exterior_dense", 2,
                                      exterior_case(R"({"method": "dense", "exterior": true})", 1));
  ASSERT_FALSE(run.report.is_null());
  const auto& r = run.report;
  const auto box = r["meshing"]["exterior"]["box"];
  for (int a = 0; a < 3; ++a) {
    EXPECT_DOUBLE_EQ(box[0][a].get<double>(), -1.5);
    EXPECT_DOUBLE_EQ(box[1][a].get<double>(), 1.5);
  }
  // P1 on 1,100 tets, 316 nodes. Measured: l2 6.4e-2, surface l2 5.9e-2, surface max 4.0e-2.
  EXPECT_LT(r["l2_error"].get<double>(), 0.12);
  EXPECT_LT(r["surface_max_error"].get<double>(), 0.1);
  EXPECT_EQ(r["surface_unmapped_vertices"], 0);
  expect_surface_output(run.dir / "out", run.vertices, "bc2_neumann");
}

// The shipped exterior case: potential flow past the unit sphere, u = x (1 + 1/(2r³)), Dirichlet
// on the box [-3, 3]³ and zero flux on the sphere (exact there). Measured: 126 coarse faces,
// 1,135 tets (outer slab + exterior), 5,847 DOFs at k = p = 3: l2 6.2e-3, surface max 8.7e-3.
TEST(RunSurface, ShippedPotentialFlowExteriorCaseRuns) {
  const auto dir = test::scratch_dir("run_surface_potential_flow");
  std::string log;
  ASSERT_EQ(
      run_case(test::source_dir() / "cases/potential_flow_sphere_exterior.json", dir / "out", &log),
      0)
      << log;
  const auto r = read_json(dir / "out" / "report.json");
  const auto box = r["meshing"]["exterior"]["box"];
  EXPECT_DOUBLE_EQ(box[0][0].get<double>(), -3.0);
  EXPECT_DOUBLE_EQ(box[1][2].get<double>(), 3.0);
  EXPECT_LT(r["l2_error"].get<double>(), 1.5e-2);
  EXPECT_LT(r["surface_max_error"].get<double>(), 2e-2);
}

namespace {
// Two materials in the box [-1.5, 1.5]³: κ = 10 inside the unit sphere, 1 outside, f = 6 on both
// sides (−∇·(κ∇u) = −6 as rhs). u = r²/10 + 0.9 inside and r² outside: continuous at r = 1
// with continuous flux κ ∂u/∂r = 2. Dirichlet data on the box only (the sphere is an interface).
std::string two_region_case(const std::string& method, int degree) {
  return sphere_case("{" + method + R"(, "exterior": true, "solve_on": "both"})", degree, R"JSON(
  "physics": {"type": "poisson", "kappa": 1, "kappa_inside": 10},
  "rhs": "-6",
  "boundary_conditions": [
    {"type": "dirichlet", "select": {"outer_box": "all"}, "value": "x*x+y*y+z*z"}
  ],
  "exact": "x*x+y*y+z*z < 1 ? (x*x+y*y+z*z)/10 + 0.9 : x*x+y*y+z*z")JSON");
}
}  // namespace

TEST(RunSurface, TwoRegionPoissonSolvesInsideAndOutsideWithTheirOwnKappa) {
  const SphereRun run =
      run_on_sphere("run_surface_two_region", 3,
                    two_region_case(R"("method": "curved", "order": 2, "eps": 0.01)", 2));
  ASSERT_FALSE(run.report.is_null());
  const auto& r = run.report;
  // Every tet of the mesh: slab + interior + outer slab + exterior.
  EXPECT_EQ(r["tets"], r["meshing"]["slab_tets"].get<int>() +
                           r["meshing"]["interior_tets"].get<int>() +
                           r["meshing"]["outer_slab_tets"].get<int>() +
                           r["meshing"]["exterior_tets"].get<int>());
  // Measured (1,468 tets, 2,193 DOFs): l2 1.1e-2 (norm 13.2), surface max 6.9e-3 (u = 1 on the
  // sphere). The same case with kappa_inside 1 (u = r² inside, 0.9 below the exact value at the
  // centre) gives l2 0.88.
  EXPECT_LT(r["l2_error"].get<double>(), 3e-2);
  EXPECT_LT(r["surface_max_error"].get<double>(), 2e-2);
  EXPECT_EQ(r["surface_unmapped_vertices"], 0);
}

TEST(RunSurface, DenseTwoRegionPoissonMergesTheInsideAndOutsideFills) {
  const SphereRun run =
      run_on_sphere("run_surface_two_region_dense", 2, two_region_case(R"("method": "dense")", 2));
  ASSERT_FALSE(run.report.is_null());
  const auto& r = run.report;
  // P2 (r² is in the space): what remains is the polyhedral interface against the exact solution's
  // kink at r = 1. Measured (1,767 tets: 667 inside, 1,100 outside): l2 3.8e-2, surface max
  // 1.7e-2.
  EXPECT_LT(r["l2_error"].get<double>(), 8e-2);
  EXPECT_LT(r["surface_max_error"].get<double>(), 4e-2);
  EXPECT_EQ(r["surface_unmapped_vertices"], 0);
}

// A stiff ball in a soft box (linear elasticity, E = 10 inside the unit sphere, 1 outside, ν = 0.3
// on both sides, no body force): u = A x inside and (B + C/r³) x outside, with u and the radial
// traction continuous at r = 1 (B = 0.01, C = 3B (K_out − K_in) / (3 K_in + 4 μ_out), A = B + C;
// K the bulk modulus). Dirichlet data on the box only.
TEST(RunSurface, TwoRegionElasticityTakesTheInsidesMaterial) {
  const std::string u =
      "(x*x+y*y+z*z < 1 ? 0.00152173913 : 0.01 - 0.00847826087/(x*x+y*y+z*z)^1.5)";
  const std::string exact = "[\"" + u + "*x\", \"" + u + "*y\", \"" + u + "*z\"]";
  // Neo-Hookean at this strain (1%) differs from the linear solution by O(|∇u|²).
  for (const std::string physics : {"linear_elasticity", "neo_hookean"}) {
    SCOPED_TRACE(physics);
    const SphereRun run = run_on_sphere(
        "run_surface_two_region_" + physics, 3,
        sphere_case(
            R"({"method": "curved", "order": 2, "eps": 0.01, "exterior": true, "solve_on": "both"})",
            2,
            R"("physics": {"type": ")" + physics + R"(", "E": 1, "nu": 0.3, "E_inside": 10},
  "boundary_conditions": [{"type": "dirichlet", "select": {"outer_box": "all"}, "value": )" +
                exact + R"(}],
  "exact": )" + exact));
    ASSERT_FALSE(run.report.is_null());
    const auto& r = run.report;
    // Measured (1,468 tets, 6,579 DOFs): l2 2.3e-4 (norm 6.1e-2), surface max 3.3e-5 (linear);
    // 2.2e-4 and 5.8e-5 (Neo-Hookean, 4 Newton steps). With E_inside 1 (one material
    // everywhere): l2 1.7e-2, surface max 7.3e-3 for both.
    EXPECT_LT(r["l2_error"].get<double>(), 1e-3);
    EXPECT_LT(r["surface_max_error"].get<double>(), 2e-4);
    EXPECT_EQ(r["surface_unmapped_vertices"], 0);
  }
}

// Neumann values may use nx, ny, nz: the mesh's outward unit normal at the quadrature point
// (x, y, z stay the input point φ⁻¹(x)). Dense P1 reproduces a linear u exactly, so a wrong or
// reversed normal shows as an O(1) error.
namespace {
nlohmann::json run_text(const std::string& name, const std::string& text) {
  const auto dir = test::scratch_dir(name);
  std::string log;
  const int code = run_case(write_case(dir, "case.json", text), dir / "out", &log);
  EXPECT_EQ(code, 0) << log;
  return code == 0 ? read_json(dir / "out" / "report.json") : nlohmann::json();
}

// u = 1 + 2x − y + z/2 (harmonic): Dirichlet off the upward normal cone of the input, and on
// the cone the flux ∇u·n written with the normal (`sign` −1 flips it, a fault to be seen).
std::string linear_flux_case(const std::string& geometry, const std::string& meshing, int degree,
                             const std::string& sign = "") {
  return "{" + geometry + R"(, "meshing": )" + meshing + R"(, "discretization": {"degree": )" +
         std::to_string(degree) + R"JSON(},
  "physics": {"type": "poisson"},
  "boundary_conditions": [
    {"type": "dirichlet", "select": {"not": {"normal": {"direction": [0, 0, 1], "angle": 60}}},
     "value": "1 + 2*x - y + 0.5*z"},
    {"type": "neumann", "select": {"normal": {"direction": [0, 0, 1], "angle": 60}},
     "value": ")JSON" +
         sign + R"JSON((2*nx - ny + 0.5*nz)"}
  ],
  "exact": "1 + 2*x - y + 0.5*z"})JSON";
}

const char* kTorus =
    R"("geometry": {"builtin_surface": {"shape": "torus", "R": 1, "r": 0.4, "nu": 48,
    "nv": 24}, "features": "none"})";
}  // namespace

TEST(RunSurface, NeumannFluxWithTheNormalIsExactForLinearUOnTheDenseTorus) {
  // Dense P1 on the input polyhedron reproduces a linear u exactly when the flux on each input
  // face is ∇u · (that face's outward normal); the selection by normal splits along input edges.
  // Measured: l2 1.1e-15.
  const auto r =
      run_text("run_normal_dense_torus", linear_flux_case(kTorus, R"({"method": "dense"})", 1));
  ASSERT_FALSE(r.is_null());
  EXPECT_LT(r["l2_error"].get<double>(), 1e-10);
  EXPECT_LT(r["surface_max_error"].get<double>(), 1e-10);
  // The flux with the normal reversed: measured l2 0.23, surface max 0.63.
  const auto flipped = run_text("run_normal_dense_torus_flipped",
                                linear_flux_case(kTorus, R"({"method": "dense"})", 1, "-"));
  ASSERT_FALSE(flipped.is_null());
  EXPECT_GT(flipped["l2_error"].get<double>(), 1e-2);
}

TEST(RunSurface, NeumannFluxWithTheNormalOnTheCurvedTorusIsWithinTheGeometricError) {
  // The same data on a curved order-2 mesh, P2: values at φ⁻¹(x) with the curved mesh's normal.
  // u is in the space; what remains is the geometric error (ε = 1% of 2.8 times |∇u| = 2.3 in
  // the Dirichlet data) and the point-wise Dirichlet/Neumann interface cutting coarse faces (41,
  // by Nitsche). Measured (715 tets, 1,137 DOFs): l2 4.4e-3, surface l2 4.7e-2, surface max
  // 5.5e-2 (all-Dirichlet: l2 1.3e-3, surface max 5.5e-2). Fixing the covered DOFs only: l2
  // 2.5e-2, surface max 0.145.
  const auto r =
      run_text("run_normal_curved_torus",
               linear_flux_case(kTorus, R"({"method": "curved", "order": 2, "eps": 0.01})", 2));
  ASSERT_FALSE(r.is_null());
  EXPECT_TRUE(r["mesh_valid"].get<bool>());
  EXPECT_LT(r["l2_error"].get<double>(), 1e-2);
  EXPECT_LT(r["surface_max_error"].get<double>(), 0.1);
  EXPECT_EQ(r["surface_unmapped_vertices"], 0);
}

TEST(RunSurface, NormalInAnExteriorDomainPointsIntoTheObject) {
  // Exterior of the unit sphere: n is the exterior domain's outward normal, so it points into
  // the sphere there, and it is the box side's normal on the outer box (Neumann on zmax).
  // Measured: l2 2.0e-15.
  const std::string text = sphere_case(R"({"method": "dense", "exterior": true})", 1, R"JSON(
  "physics": {"type": "poisson"},
  "boundary_conditions": [
    {"type": "dirichlet", "select": {"or": [{"outer_box": "xmin"}, {"outer_box": "xmax"},
       {"outer_box": "ymin"}, {"outer_box": "ymax"}, {"outer_box": "zmin"}]},
     "value": "1 + 2*x - y + 0.5*z"},
    {"type": "neumann", "select": {"outer_box": "zmax"}, "value": "2*nx - ny + 0.5*nz"},
    {"type": "dirichlet", "select": {"not": {"normal": {"direction": [0, 0, 1], "angle": 60}}},
     "value": "1 + 2*x - y + 0.5*z"},
    {"type": "neumann", "select": {"normal": {"direction": [0, 0, 1], "angle": 60}},
     "value": "2*nx - ny + 0.5*nz"}
  ],
  "exact": "1 + 2*x - y + 0.5*z")JSON");
  const SphereRun run = run_on_sphere("run_normal_exterior", 2, text);
  ASSERT_FALSE(run.report.is_null());
  EXPECT_LT(run.report["l2_error"].get<double>(), 1e-10);
  EXPECT_LT(run.report["surface_max_error"].get<double>(), 1e-10);
}

namespace {
// Linear elasticity, E = 1, ν = 0.3, pressure p = 0.1 on the upper cap (traction −p n) and the
// exact displacement u = −p / (3K) x, K = E / (3 (1 − 2ν)), elsewhere: σ = −p I everywhere.
std::string pressure_case(const std::string& meshing, int degree) {
  return sphere_case(meshing, degree, R"JSON(
  "physics": {"type": "linear_elasticity", "E": 1, "nu": 0.3},
  "boundary_conditions": [
    {"type": "dirichlet", "select": {"not": {"normal": {"direction": [0, 0, 1], "angle": 50}}},
     "value": ["-0.04*x", "-0.04*y", "-0.04*z"]},
    {"type": "neumann", "select": {"normal": {"direction": [0, 0, 1], "angle": 50}},
     "value": ["-0.1*nx", "-0.1*ny", "-0.1*nz"]}
  ],
  "exact": ["-0.04*x", "-0.04*y", "-0.04*z"])JSON");
}
}  // namespace

TEST(RunSurface, PressureLoadWithTheNormalCompressesABallUniformly) {
  // Dense P1 on the input polyhedron is exact. Measured: l2 1.8e-17.
  const SphereRun run =
      run_on_sphere("run_normal_pressure", 2, pressure_case(R"({"method": "dense"})", 1));
  ASSERT_FALSE(run.report.is_null());
  EXPECT_LT(run.report["l2_error"].get<double>(), 1e-10);
  EXPECT_LT(run.report["surface_max_error"].get<double>(), 1e-10);
}

TEST(RunSurface, PressureLoadOnTheCurvedBallUsesTheCurvedNormal) {
  // The same load on a curved order-2 mesh, P2 (535 tets, 2,604 DOFs). u is in the space and
  // all-Dirichlet gives l2 3.7e-17, surface max 5.4e-4 (|u| = 0.04 there). With the pressure
  // cap, the interface cut through 16 coarse faces by Nitsche: l2 6.0e-5, surface max 5.4e-4;
  // fixing the covered DOFs only: l2 2.8e-3, surface max 1.5e-2.
  // Nitsche is asked for: elasticity's default is nodal (cases/README.md).
  constexpr double kL2Bound = 2e-4, kSurfaceMaxBound = 1.5e-3;
  const SphereRun run = run_on_sphere(
      "run_normal_pressure_curved", 3,
      with_discretization(pressure_case(R"({"method": "curved", "order": 2, "eps": 0.01})", 2),
                          R"("partial_dirichlet": "nitsche")"));
  ASSERT_FALSE(run.report.is_null());
  EXPECT_EQ(run.report["physics_details"]["nitsche_faces"], 16);
  EXPECT_LT(run.report["l2_error"].get<double>(), kL2Bound);
  EXPECT_LT(run.report["surface_max_error"].get<double>(), kSurfaceMaxBound);
  // Without the key, elasticity fixes the covered DOFs (its default): no Nitsche face, and the
  // smooth data's error is the nodal one above.
  const SphereRun nodal =
      run_on_sphere("run_normal_pressure_curved_nodal", 3,
                    pressure_case(R"({"method": "curved", "order": 2, "eps": 0.01})", 2));
  ASSERT_FALSE(nodal.report.is_null());
  EXPECT_EQ(nodal.report["physics_details"]["nitsche_faces"], 0);
  EXPECT_GT(nodal.report["l2_error"].get<double>(), 10 * run.report["l2_error"].get<double>());
}

// A Dirichlet selection smaller than the mesh: a box inside one input face of the dense sphere
// (no input vertex in it, so no node) still constrains the solution through Nitsche's method on
// the face quadrature points it covers, and u (linear, the flux elsewhere with the normal) is
// reproduced exactly. Fixing nodes only, the same selection is refused: it covers none.
TEST(RunSurface, DirichletSelectionInsideOneFaceActsThroughNitsche) {
  const SurfaceMesh sphere = make_icosphere(2);
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) c += sphere.V.row(sphere.F(0, k)).transpose() / 3;
  const double h = 0.3 * (sphere.V.row(sphere.F(0, 0)) - sphere.V.row(sphere.F(0, 1))).norm();
  auto box = [&](double s) {
    return "[[" + std::to_string(c[0] - s) + ", " + std::to_string(c[1] - s) + ", " +
           std::to_string(c[2] - s) + "], [" + std::to_string(c[0] + s) + ", " +
           std::to_string(c[1] + s) + ", " + std::to_string(c[2] + s) + "]]";
  };
  const std::string text = sphere_case(R"({"method": "dense"})", 1, R"(
  "physics": {"type": "poisson"},
  "boundary_conditions": [
    {"type": "dirichlet", "select": {"box": )" + box(h) + R"(}, "value": "1 + 2*x - y + 0.5*z"},
    {"type": "neumann", "select": {"not": {"box": )" + box(h) + R"(}},
     "value": "2*nx - ny + 0.5*nz"}
  ],
  "exact": "1 + 2*x - y + 0.5*z")");
  const SphereRun run = run_on_sphere("run_dirichlet_inside_face", 2, text);
  ASSERT_FALSE(run.report.is_null());
  // The box reaches into a neighbour face too: measured 2 cut faces, l2 error 9.7e-15.
  EXPECT_GE(run.report["physics_details"]["nitsche_faces"].get<int>(), 1);
  EXPECT_EQ(run.report["dofs"], run.report["physics_details"]["free_dofs"]);  // no fixed node
  EXPECT_LT(run.report["l2_error"].get<double>(), 1e-10);
  // Nodal: refused, naming the selection.
  std::string log;
  const auto dir = test::scratch_dir("run_dirichlet_inside_face_nodal");
  io::write_surface(dir / "sphere.obj", sphere, io::SurfaceFormat::obj);
  const auto file =
      write_case(dir, "case.json", with_discretization(text, R"("partial_dirichlet": "nodal")"));
  EXPECT_EQ(run_case(file, dir / "out", &log), 2) << log;
  EXPECT_NE(log.find("/boundary_conditions/0/select: selects no boundary node"), std::string::npos)
      << log;
}

TEST(RunSurface, PaintedDataErrorIsWithinTheGeometricErrorAtEveryOrderAndDegree) {
  // Issue 20's matrix, part (b): Dirichlet data painted on the faceted input and read through
  // φ⁻¹, every geometry order k with every degree p (the default "iso" solve for k > p). The
  // curved boundary lies within ε of the input, so the data carry an error up to ε·|∇u| and, by
  // the maximum principle, so does the solution; what p adds on top is its discretization error.
  // u = sin x cos y e^z on the unit icosphere (level 3), ε = 1% of the bbox edge 2 = 0.02, and
  // max |∇u| = e on the ball: ε·|∇u| = 0.054. Asserted on the input vertices and in L2 over the
  // mesh, for p ≥ 2; p = 1 on these coarse meshes (135 DOFs at k ≥ 2) is discretization-limited
  // and asserted at 4 times the bound. Measured (2026-12-01): surface max 0.12–0.66 of the bound
  // for p ≥ 2, 1.1–3.4 at p = 1; relative L2 1.2e-4 (k = p = 4) to 1.0e-2 (k = 1). At p > k the
  // boundary DOFs are not fiber hits on the input, so their data carry the ε error the nodes of
  // k = p do not: k = 3, p = 4 gives 1.0e-3 against 4.3e-4 at p = 3 (k = 4, p = 4: 1.2e-4).
  const double bound = 0.02 * std::exp(1.0);
  for (int k = 1; k <= 4; ++k)
    for (int p = 1; p <= 4; ++p) {
      if (p == 4 && k < 3) continue;  // k = 3, 4 cover p = 4
      const std::string text = sphere_case(
          R"({"method": "curved", "order": )" + std::to_string(k) + R"(, "eps": 0.01})", p,
          R"JSON(
  "physics": {"type": "poisson"},
  "rhs": "sin(x)*cos(y)*exp(z)",
  "boundary_conditions": [{"type": "dirichlet", "select": {"all": true},
                           "value": "sin(x)*cos(y)*exp(z)"}],
  "exact": "sin(x)*cos(y)*exp(z)",
  "output": {"surface_values": "image"})JSON");
      const SphereRun run = run_on_sphere(
          "run_surface_painted_k" + std::to_string(k) + "_p" + std::to_string(p), 3, text);
      ASSERT_FALSE(run.report.is_null()) << "k = " << k << ", p = " << p;
      const auto& r = run.report;
      const double smax = r["surface_max_error"].get<double>();
      const double l2 = r["l2_error"].get<double>() / r["l2_norm_exact"].get<double>();
      std::printf(
          "painted k = %d p = %d: %d tets, %d dofs, surface max %.3e (%.2f of eps|grad u|),"
          " relative L2 %.3e\n",
          k, p, r["tets"].get<int>(), r["dofs"].get<int>(), smax, smax / bound, l2);
      const double c = p == 1 ? 4.0 : 1.0;
      EXPECT_LT(smax, c * bound) << "k = " << k << ", p = " << p;
      EXPECT_LT(l2, c * bound) << "k = " << k << ", p = " << p;
      EXPECT_EQ(r["solve_geometry"]["degree"].get<int>(), std::min(k, p));
    }
}

namespace {
// The relative L2 error of `text` (a sphere_case) run with each discretization.boundary_values_at,
// in scratch folders `name`_<mode>; the shift's report field is checked on the way. NaN for a run
// that failed (recorded by run_on_sphere).
std::map<std::string, double> relative_l2_by_values_at(const std::string& name, int level,
                                                       const std::string& text) {
  std::map<std::string, double> l2;
  for (const std::string at : {"input", "shifted", "mesh"}) {
    const SphereRun run =
        run_on_sphere(name + "_" + at, level,
                      with_discretization(text, R"("boundary_values_at": ")" + at + R"(")"));
    const auto& r = run.report;
    if (r.is_null()) {
      l2[at] = std::nan("");
      continue;
    }
    l2[at] = r["l2_error"].get<double>() / r["l2_norm_exact"].get<double>();
    EXPECT_EQ(r["physics_details"].contains("boundary_shift"), at == "shifted") << at;
    if (at == "shifted") EXPECT_EQ(r["physics_details"]["boundary_shift"]["passes"].size(), 1u);
  }
  std::printf("relative L2: input %.3e, shifted %.3e, mesh %.3e\n", l2["input"], l2["shifted"],
              l2["mesh"]);
  return l2;
}
}  // namespace

TEST(RunSurface, BoundaryValuesReadAtTheMeshOrShiftedRemoveTheTransportError) {
  // The painted-data case above at k = 2, p = 3 (Dirichlet everywhere, u = sin x cos y e^z; at
  // p > k the boundary DOFs are not fiber hits on the input, at p = k they are and the three
  // modes coincide): read on the input, the data carry up to ε·|∇u|
  // (discretization.boundary_values_at "input"); read at the mesh's own point they are
  // consistent with the domain solved on ("mesh"); "shifted" continues the input's values to the
  // mesh point with the recovered gradient (one re-solve). Measured, relative L2: input 2.49e-3,
  // shifted 2.20e-4, mesh 2.23e-4.
  auto l2 = relative_l2_by_values_at(
      "run_surface_values_at", 3,
      sphere_case(R"({"method": "curved", "order": 2, "eps": 0.01})", 3, R"JSON(
  "physics": {"type": "poisson"},
  "rhs": "sin(x)*cos(y)*exp(z)",
  "boundary_conditions": [{"type": "dirichlet", "select": {"all": true},
                           "value": "sin(x)*cos(y)*exp(z)"}],
  "exact": "sin(x)*cos(y)*exp(z)")JSON"));
  EXPECT_LT(l2["mesh"], 0.2 * l2["input"]);
  EXPECT_LT(l2["shifted"], 0.2 * l2["input"]);
}

TEST(RunSurface, ShiftedDirichletValuesOfLinearElasticityApproachTheAffineSolution) {
  // An affine displacement without body force is the exact solution and lies in the space (k = 2,
  // p = 3): with the values read at the mesh's points the solve reproduces it to rounding; read
  // on the input they are off by up to ε·|∇u| (the P3 boundary DOFs are not fiber hits), and the
  // shifted values recover most of that. Measured, relative L2: input 7.40e-3, shifted 3.21e-4,
  // mesh 1.2e-15.
  auto l2 = relative_l2_by_values_at(
      "run_surface_elastic_values_at", 2,
      sphere_case(R"({"method": "curved", "order": 2, "eps": 0.01})", 3, R"JSON(
  "physics": {"type": "linear_elasticity", "E": 1, "nu": 0.3},
  "boundary_conditions": [{"type": "dirichlet", "select": {"all": true},
                           "value": ["0.1*x - 0.05*z", "0.02*x + 0.1*y", "0.03*y - 0.08*z"]}],
  "exact": ["0.1*x - 0.05*z", "0.02*x + 0.1*y", "0.03*y - 0.08*z"])JSON"));
  EXPECT_LT(l2["mesh"], 1e-9);
  EXPECT_GT(l2["input"], 1e-4);  // the transport error is there to remove
  EXPECT_LT(l2["shifted"], 0.1 * l2["input"]);
}
