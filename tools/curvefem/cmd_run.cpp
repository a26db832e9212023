// `curvefem run CASE.json [-o DIR]`: p-FEM on a given curved tetrahedral mesh (meshing.method
// "given"; the dense-surface pipelines arrive with the curved mesher). Writes volume.vtu (Lagrange
// cells of order max(p, k) with the solution), resolved_case.json and report.json (last).
#include <cstring>
#include <nlohmann/json.hpp>
#include <unordered_map>

#include "fem/problems/constraints.hpp"
#include "fem/problems/elasticity.hpp"
#include "fem/problems/error_norms.hpp"
#include "fem/problems/interpolation.hpp"
#include "fem/problems/poisson.hpp"
#include "fem/space/function_space.hpp"
#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/io/cad_part.hpp"
#include "meshing/io/msh_io.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/io/vtu_io.hpp"
#include "tools/curvefem/case_file.hpp"
#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"
#include "tools/curvefem/report_json.hpp"

namespace curvefem::cli {
namespace {

using json = nlohmann::json;

struct RunOptions {
  GlobalOptions global;
  std::string case_file;
  std::string output;
};

LagrangeMesh load_mesh(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) throw IoError("mesh file not found", {.file = path.string()});
  const std::string ext = path.extension().string();
  LagrangeMesh mesh;
  if (ext == ".vtu")
    mesh = io::read_vtu(path).mesh;
  else if (ext == ".msh")
    mesh = io::read_msh(path);
  else
    throw InputError("mesh must be .msh or .vtu", {.file = path.string()});
  if (mesh.kind != CellKind::tetrahedron)
    throw InputError("mesh holds no tetrahedra", {.file = path.string()});
  return mesh;
}

struct PositionKey {
  std::array<std::uint64_t, 3> bits;
  bool operator==(const PositionKey&) const = default;
};
struct PositionHash {
  std::size_t operator()(const PositionKey& k) const {
    return k.bits[0] * 0x9E3779B97F4A7C15ull ^ (k.bits[1] + 0x7F4A7C15ull) * 31 ^ k.bits[2];
  }
};
PositionKey key_of(const Eigen::Vector3d& p) {
  PositionKey k;
  for (int i = 0; i < 3; ++i) std::memcpy(&k.bits[i], &p[i], sizeof(double));
  return k;
}

/// Physical tag of every boundary face, from the triangles stored in the mesh file (-1 if none).
std::vector<int> boundary_face_tags(const std::filesystem::path& path, const LagrangeMesh& mesh,
                                    const fem::FunctionSpace& space) {
  std::vector<int> tags(space.boundary_faces.size(), -1);
  if (path.extension() != ".msh") return tags;
  SurfaceMesh triangles;
  try {
    triangles = io::read_msh_boundary_triangles(path);  // any order; corners + physical tags
  } catch (const InputError&) {
    return tags;  // no triangles in the file
  }
  if (!triangles.has_tags()) return tags;
  std::unordered_map<PositionKey, int, PositionHash> node_of;
  for (int n = 0; n < mesh.num_nodes(); ++n)
    node_of.emplace(key_of(mesh.nodes.row(n).transpose()), n);
  std::map<std::array<int, 3>, int> tag_of;
  for (int f = 0; f < triangles.num_faces(); ++f) {
    std::array<int, 3> ids;
    bool found = true;
    for (int c = 0; c < 3; ++c) {
      auto it = node_of.find(key_of(triangles.V.row(triangles.F(f, c)).transpose()));
      if (it == node_of.end())
        found = false;
      else
        ids[c] = it->second;
    }
    if (!found) continue;
    std::sort(ids.begin(), ids.end());
    tag_of[ids] = triangles.tags[f];
  }
  for (std::size_t f = 0; f < space.boundary_faces.size(); ++f) {
    const auto [cell, j] = space.boundary_faces[f];
    std::array<int, 3> ids;
    int k = 0;
    for (int i = 0; i < 4; ++i)
      if (i != j) ids[k++] = mesh.cells(cell, i);
    std::sort(ids.begin(), ids.end());
    auto it = tag_of.find(ids);
    if (it != tag_of.end()) tags[f] = it->second;
  }
  return tags;
}

/// Sides of the built-in unit cube: 1..6 = x=0, x=1, y=0, y=1, z=0, z=1 (as make_box).
std::vector<int> cube_face_tags(const LagrangeMesh& mesh, const fem::FunctionSpace& space) {
  std::vector<int> tags(space.boundary_faces.size(), -1);
  for (std::size_t f = 0; f < tags.size(); ++f) {
    const auto [cell, j] = space.boundary_faces[f];
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(2), hi = Eigen::Vector3d::Constant(-1);
    for (int i = 0; i < 4; ++i)
      if (i != j) {
        lo = lo.cwiseMin(mesh.nodes.row(mesh.cells(cell, i)).transpose());
        hi = hi.cwiseMax(mesh.nodes.row(mesh.cells(cell, i)).transpose());
      }
    for (int axis = 0; axis < 3; ++axis) {
      if (hi[axis] < 1e-12) tags[f] = 1 + 2 * axis;
      if (lo[axis] > 1 - 1e-12) tags[f] = 2 + 2 * axis;
    }
  }
  return tags;
}

struct Selected {
  std::vector<char> faces;
  fem::PointFilter where;
};

Selected select_faces(const Selection& s, const std::vector<int>& face_tags,
                      const fem::FunctionSpace& space, const std::string& file) {
  Selected out;
  out.faces.assign(face_tags.size(), 0);
  long long count = 0;
  for (std::size_t f = 0; f < face_tags.size(); ++f) {
    const bool take = s.kind != Selection::Kind::tag || face_tags[f] == s.tag;
    out.faces[f] = take;
    count += take;
  }
  if (s.kind == Selection::Kind::box) {
    const Eigen::Vector3d lo = s.lo, hi = s.hi;
    out.where = [lo, hi](const Eigen::Vector3d& x) {
      return (x.array() >= lo.array()).all() && (x.array() <= hi.array()).all();
    };
    // A box acts point-wise: it selects something only if a boundary DOF lies inside it.
    count = 0;
    fem::for_each_boundary_dof(space, out.faces, out.where, [&](int) { ++count; });
  }
  if (count == 0)
    throw InputError(
        s.where + ": selects no boundary face" +
            (s.kind == Selection::Kind::box ? std::string(" (no boundary node inside the box)")
                                            : std::string()) +
            (s.kind == Selection::Kind::tag
                 ? " (no boundary triangle has tag " + std::to_string(s.tag) + ")"
                 : ""),
        {.file = file});
  return out;
}

int run_case(const RunOptions& o) {
  auto progress = apply_global_options(o.global);
  Timings timings;
  Stopwatch total;
  const CaseSpec spec = read_case(o.case_file, o.output);
  const std::string case_name = spec.case_file.string();
  StagedOutputDir out(spec.output_dir);

  LagrangeMesh mesh;
  fem::FunctionSpace space;
  std::vector<int> face_tags;
  {
    ScopedTimer t(timings, "load_mesh");
    progress->update("load mesh", 0.0);
    if (spec.builtin == "ball")
      mesh = io::make_ball_mesh(1.0, spec.builtin_size, spec.builtin_order);
    else if (spec.builtin == "cube")
      mesh = elevate_order(make_cube_tets(spec.builtin_divisions), spec.builtin_order,
                           [](const Eigen::Vector3d& x) { return x; });
    else
      mesh = load_mesh(spec.mesh);
    progress->update("build space", 0.5);
    space = fem::build_function_space(mesh, spec.degree);
    face_tags = spec.builtin == "cube" ? cube_face_tags(mesh, space)
                                       : boundary_face_tags(spec.mesh, mesh, space);
  }
  progress->end_stage();
  log::info("mesh: ", mesh.num_cells(), " tetrahedra of order ", mesh.order, "; degree ",
            spec.degree, ": ", space.num_dofs, " nodes, ", space.boundary_faces.size(),
            " boundary faces");

  fem::LinearSolverOptions solver;
  solver.type = spec.solver;
  solver.rtol = spec.solver_rtol;
  solver.max_iterations = spec.solver_max_iterations;
  const int c = spec.components();
  Eigen::VectorXd u;
  json physics_report;
  fem::LinearSolveInfo solve_info;
  progress->update("solve " + spec.physics, 0.0);
  if (spec.physics == "poisson") {
    fem::PoissonProblem problem;
    const Expression kappa = spec.kappa;
    problem.kappa = [kappa](const Eigen::Vector3d& x) { return kappa(x); };
    if (!spec.rhs.empty()) {
      const Expression f = spec.rhs[0];
      problem.rhs = [f](const Eigen::Vector3d& x) { return f(x); };
    }
    problem.quadrature_degree = spec.quadrature;
    for (const auto& bc : spec.boundary_conditions) {
      Selected sel = select_faces(bc.select, face_tags, space, case_name);
      const Expression v = bc.value[0];
      auto value = [v](const Eigen::Vector3d& x) { return v(x); };
      if (bc.type == "dirichlet")
        problem.dirichlet.push_back({sel.faces, value, sel.where});
      else
        problem.neumann.push_back({sel.faces, value, sel.where});
    }
    const fem::PoissonSolution sol = fem::solve_poisson(mesh, space, problem, solver);
    u = sol.u;
    solve_info = sol.solve;
    for (const auto& [stage, s] : sol.timings.stages()) timings.add(stage, s);
    physics_report["free_dofs"] = sol.free_dofs;
  } else {
    fem::ElasticityProblem problem;
    problem.material = {spec.E, spec.nu};
    problem.quadrature_degree = spec.quadrature;
    auto vector_field = [](const std::vector<Expression>& e) {
      return [e](const Eigen::Vector3d& x) { return Eigen::Vector3d(e[0](x), e[1](x), e[2](x)); };
    };
    if (!spec.rhs.empty()) problem.body_force = vector_field(spec.rhs);
    for (const auto& bc : spec.boundary_conditions) {
      Selected sel = select_faces(bc.select, face_tags, space, case_name);
      if (bc.type == "dirichlet")
        problem.dirichlet.push_back({sel.faces, bc.components, vector_field(bc.value), sel.where});
      else
        problem.traction.push_back({sel.faces, vector_field(bc.value), sel.where});
    }
    fem::ElasticitySolution sol;
    if (spec.physics == "linear_elasticity") {
      sol = fem::solve_linear_elasticity(mesh, space, problem, solver);
    } else {
      fem::NewtonOptions newton;
      newton.load_steps = spec.load_steps;
      sol = fem::solve_neo_hookean(mesh, space, problem, solver, newton);
      json steps = json::array();
      for (const auto& s : sol.newton)
        steps.push_back({{"load_step", s.load_step},
                         {"iteration", s.iteration},
                         {"residual", s.residual},
                         {"step_length", s.step_length},
                         {"energy", s.energy}});
      physics_report["newton"] = steps;
    }
    u = sol.u;
    solve_info = sol.solve;
    for (const auto& [stage, s] : sol.timings.stages()) timings.add(stage, s);
    physics_report["free_unknowns"] = sol.free_unknowns;
    physics_report["E"] = spec.E;
    physics_report["nu"] = spec.nu;
  }
  progress->end_stage();

  json report;
  if (!spec.exact.empty()) {
    ScopedTimer t(timings, "errors");
    const auto exact = spec.exact;
    const fem::ErrorNorms e = fem::compute_errors(
        mesh, space, u, c,
        [exact](const Eigen::Vector3d& x, double* v) {
          for (std::size_t i = 0; i < exact.size(); ++i) v[i] = exact[i](x);
        },
        [exact](const Eigen::Vector3d& x, double* g) {
          for (std::size_t i = 0; i < exact.size(); ++i) {
            const Eigen::Vector3d gi = exact[i].gradient(x);
            for (int d = 0; d < 3; ++d) g[3 * i + d] = gi[d];
          }
        });
    report["l2_error"] = e.l2;
    report["h1_semi_error"] = e.h1_semi;
    report["h1_error"] = std::sqrt(e.l2 * e.l2 + e.h1_semi * e.h1_semi);
    report["l2_norm_exact"] = e.l2_exact;
    report["h1_semi_norm_exact"] = e.h1_semi_exact;
    report["exact_gradient"] = "4th-order central differences of the exact expression, h = 1e-3";
  }

  {
    ScopedTimer t(timings, "output");
    progress->update("write output", 0.0);
    const int m = std::max(spec.degree, mesh.order);
    const fem::FunctionSpace out_space =
        m == spec.degree ? space : fem::build_function_space(mesh, m);
    const Eigen::MatrixXd values = fem::interpolate_field(space, u, c, out_space);
    MeshFields fields;
    Field uf{c == 1 ? "u" : "displacement", c, {}};
    uf.values.resize(values.size());
    for (int r = 0; r < values.rows(); ++r)
      for (int i = 0; i < c; ++i) uf.values[static_cast<std::size_t>(r) * c + i] = values(r, i);
    fields.point_data.push_back(uf);
    if (!spec.exact.empty()) {
      Field ef{"exact", c, {}}, err{"error", c, {}};
      for (int r = 0; r < out_space.num_dofs; ++r)
        for (int i = 0; i < c; ++i) {
          const double ex = spec.exact[i](out_space.dof_points.row(r).transpose());
          ef.values.push_back(ex);
          err.values.push_back(values(r, i) - ex);
        }
      fields.point_data.push_back(ef);
      fields.point_data.push_back(err);
    }
    if (spec.physics == "linear_elasticity") {
      const Eigen::VectorXd vm =
          fem::von_mises_at_dofs(mesh, out_space, {spec.E, spec.nu}, values.transpose().reshaped());
      fields.point_data.push_back(
          {"von_mises", 1, std::vector<double>(vm.data(), vm.data() + vm.size())});
    }
    io::write_vtu(out.path("volume.vtu"), fem::lagrange_mesh_of_space(mesh, out_space), fields);
    write_text_file_atomic(out.path("resolved_case.json"), spec.resolved.dump(2) + "\n");
  }
  progress->end_stage();

  report["command"] = "run";
  report["case"] = spec.case_file.string();
  report["mesh"] = spec.builtin.empty() ? spec.mesh.string() : "builtin " + spec.builtin;
  report["tets"] = mesh.num_cells();
  report["order"] = mesh.order;
  report["degree"] = spec.degree;
  report["physics"] = spec.physics;
  report["dofs"] = static_cast<long long>(space.num_dofs) * c;
  report["nodes"] = space.num_dofs;
  report["physics_details"] = physics_report;
  report["solver"] = {{"method", solve_info.method},
                      {"iterations", solve_info.iterations},
                      {"relative_residual", solve_info.relative_residual},
                      {"setup_s", solve_info.setup_s},
                      {"solve_s", solve_info.solve_s}};
  timings.add("total", total.seconds());
  report["time_s"] = timings_json(timings);
  report["peak_rss_mb"] = peak_rss_mb();
  report["threads"] = o.global.threads;
  write_text_file_atomic(out.path("report.json"), report.dump(2) + "\n");
  out.commit();
  if (!o.global.quiet) {
    std::printf("curvefem run: %s, degree %d on %d tets of order %d: %lld unknowns\n",
                spec.physics.c_str(), spec.degree, mesh.num_cells(), mesh.order,
                static_cast<long long>(space.num_dofs) * c);
    if (report.contains("l2_error"))
      std::printf("  L2 error %.3e   H1-semi error %.3e\n", report["l2_error"].get<double>(),
                  report["h1_semi_error"].get<double>());
    for (const auto& [stage, s] : timings.stages())
      std::printf("  %-12s %8.3f s\n", stage.c_str(), s);
    std::printf("  results in %s\n", out.dir().c_str());
  }
  return 0;
}

}  // namespace

void register_run(CLI::App& app) {
  auto options = std::make_shared<RunOptions>();
  CLI::App* sub = app.add_subcommand("run", "solve the case described by a JSON case file");
  sub->add_option("case", options->case_file, "case file (schema: cases/README.md)")->required();
  sub->add_option("-o,--output", options->output, "output directory (overrides output.dir)");
  add_global_options(*sub, options->global);
  add_command(sub, [options] { return run_case(*options); });
}

}  // namespace curvefem::cli
