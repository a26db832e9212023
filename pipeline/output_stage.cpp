// Stages compute_errors, transfer_to_input and write_outputs (stages.hpp).
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>

#include "fem/problems/elasticity.hpp"
#include "fem/problems/interpolation.hpp"
#include "fem/problems/null_space.hpp"
#include "fem/solvers/distributed.hpp"
#include "mapping/selection.hpp"
#include "mapping/surface_transfer.hpp"
#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
#include "meshing/io/pvd.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/io/vtu_io.hpp"
#include "pipeline/mesh_dir.hpp"
#include "pipeline/paraview_script.hpp"
#include "pipeline/report_json.hpp"
#include "pipeline/stages.hpp"

namespace curvefem::pipeline {
namespace {
using json = nlohmann::json;

Field field_of(const std::string& name, const Eigen::MatrixXd& m) {
  Field f{name, int(m.cols()), {}};
  f.values.reserve(std::size_t(m.size()));
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index i = 0; i < m.cols(); ++i) f.values.push_back(m(r, i));
  return f;
}

}  // namespace

ErrorResult compute_errors(const LoadCase& spec, const Discretization& disc,
                           const Solution& solution, const StageContext& ctx) {
  ErrorResult out;
  out.report = json::object();
  ctx.update("errors", 0.0);
  const LagrangeMesh& mesh = disc.mesh;
  const fem::FunctionSpace& space = disc.space;
  const int c = solution.components;
  // The a-posteriori estimate needs no exact solution; it has its own stage in time_s, so that
  // "errors" is the cost of the error norms alone (what a peer's error computation is compared
  // with).
  std::optional<ScopedTimer> t;
  if (ctx.timings) t.emplace(*ctx.timings, "error_estimate");
  const fem::RecoveryEstimate estimate =
      fem::estimate_gradient_recovery(mesh, space, solution.u, c);
  t.reset();
  if (ctx.timings) t.emplace(*ctx.timings, "errors");
  out.cell_estimate = estimate.cell_eta;
  out.report["error_estimate"] = {
      {"method",
       "gradient recovery (Zienkiewicz-Zhu: grad u_h averaged at the DOF points, volume-weighted, "
       "interpolated in the same space); estimates the h1_semi_error of the discretization, not "
       "the geometric error of eps; fem/problems/error_estimate.hpp"},
      {"h1_semi", estimate.eta},
      {"relative", estimate.gradient_norm > 0 ? estimate.eta / estimate.gradient_norm : 0.0},
      {"gradient_norm", estimate.gradient_norm},
      {"max_cell", estimate.cell_eta.size() > 0 ? estimate.cell_eta.maxCoeff() : 0.0}};
  if (spec.exact.empty()) return out;
  const auto exact = spec.exact;
  const fem::ExactValue value = [exact](const Eigen::Vector3d& x, double* v) {
    for (std::size_t i = 0; i < exact.size(); ++i) v[i] = exact[i](x);
  };
  const fem::ExactGradient gradient = [exact, grad = spec.exact_gradient](const Eigen::Vector3d& x,
                                                                          double* g) {
    for (std::size_t i = 0; i < exact.size(); ++i) {
      if (!grad.empty()) {
        for (int d = 0; d < 3; ++d) g[3 * i + d] = grad[3 * i + std::size_t(d)](x);
        continue;
      }
      const Eigen::Vector3d gi = exact[i].gradient(x);
      for (int d = 0; d < 3; ++d) g[3 * i + d] = gi[d];
    }
  };
  // Without Dirichlet data u_h is determined up to the null space: the errors are those of
  // u_h − (u + r) with the mode r that takes out the null-space part of u_h − u (its mean for
  // Poisson); `exact` and `error` in the VTU files use u + r too.
  out.exact_value = value;
  fem::ErrorNorms e;
  if (solution.null_space_dim > 0) {
    auto modes = std::make_shared<const fem::NullSpaceModes>(fem::null_space_modes(mesh, space, c));
    Eigen::VectorXd theta;
    e = fem::compute_errors_modulo_null_space(mesh, space, *modes, solution.u, value, gradient,
                                              &theta);
    out.exact_value = [value, modes, theta](const Eigen::Vector3d& x, double* v) {
      double r[3];
      value(x, v);
      modes->evaluate(theta, x, r);
      for (int i = 0; i < modes->components; ++i) v[i] += r[i];
    };
    out.report["errors_modulo"] =
        c == 1 ? "constant: errors of u_h - (u + m), m = the mean of u_h - u (pure Neumann: u is "
                 "determined up to a constant)"
               : "rigid motion: errors of u_h - (u + r), r = the rigid motion with the mean "
                 "translation and rotation of u_h - u (tractions only: u is determined up to a "
                 "rigid motion)";
    out.report["error_offset"] = std::vector<double>(theta.data(), theta.data() + theta.size());
  } else {
    // All the points of a cell at once: one walk of each expression's tree per cell.
    const fem::ExactBatch batch = [exact, grad = spec.exact_gradient](const Eigen::MatrixXd& x,
                                                                      Eigen::MatrixXd& v,
                                                                      Eigen::MatrixXd& g) {
      const int n = static_cast<int>(x.rows());
      const double *px = x.col(0).data(), *py = x.col(1).data(), *pz = x.col(2).data();
      for (std::size_t i = 0; i < exact.size(); ++i) {
        const auto col = [&](std::size_t d) { return g.col(Eigen::Index(3 * i + d)).data(); };
        if (grad.empty()) {
          exact[i].values_and_gradients(n, px, py, pz, v.col(Eigen::Index(i)).data(), col(0),
                                        col(1), col(2));
          continue;
        }
        exact[i].values_and_gradients(n, px, py, pz, v.col(Eigen::Index(i)).data(), nullptr,
                                      nullptr, nullptr);
        for (std::size_t d = 0; d < 3; ++d)
          grad[3 * i + d].values_and_gradients(n, px, py, pz, col(d), nullptr, nullptr, nullptr);
      }
    };
    e = fem::compute_errors(mesh, space, solution.u, c, batch);
  }
  out.report["l2_error"] = e.l2;
  out.report["h1_semi_error"] = e.h1_semi;
  out.report["h1_error"] = std::sqrt(e.l2 * e.l2 + e.h1_semi * e.h1_semi);
  out.report["l2_norm_exact"] = e.l2_exact;
  out.report["error_estimate"]["effectivity"] = e.h1_semi > 0 ? estimate.eta / e.h1_semi : 0.0;
  out.report["h1_semi_norm_exact"] = e.h1_semi_exact;
  bool differentiated = true;
  for (const auto& x : exact) differentiated = differentiated && x.differentiated();
  out.report["exact_gradient"] =
      !spec.exact_gradient.empty()
          ? "exact_gradient of the case (checked against 4th-order central differences of the "
            "exact expression at 4 points)"
      : differentiated
          ? "forward-mode differentiation of the exact expression (pipeline/expression_ad.hpp; "
            "checked against muparser's values and 4th-order central differences at 6 points)"
          : "4th-order central differences of the exact expression, h = 1e-3";
  ctx.update("errors", 1.0);
  return out;
}

InputSolution transfer_to_input(const LoadCase& spec, const Domain& domain,
                                const Discretization& disc, const Solution& solution,
                                const ErrorResult& errors, const StageContext& ctx,
                                SurfaceValues values) {
  CF_VERIFY(domain.on_input(), "transfer_to_input: the domain has no dense input");
  std::optional<ScopedTimer> t;
  if (ctx.timings) t.emplace(*ctx.timings, "surface_transfer");
  ctx.update("transfer to input", 0.0);
  InputSolution out;
  const SurfaceMesh& input = domain.input;
  const int c = solution.components;
  const mapping::SurfaceSamples samples = mapping::locate_input_vertices(disc.mesh, domain.map());
  out.images = mapping::sample_positions(disc.mesh, samples);
  out.values = mapping::evaluate_on_surface(disc.space, solution.u, c, samples);
  long long extended = 0, from_data = 0;
  if (values == SurfaceValues::extended) {
    // Where a Dirichlet condition holds v (component by component), the value is its data g(v),
    // as on a node of a dense mesh (u_h(φ(v)) interpolates g∘φ⁻¹ between the mesh's boundary
    // nodes; continued to v it would add ∂u_h/∂n times the offset, which the data do not have).
    // Elsewhere: u_h continued from φ(v) to v. The first condition holding a component wins.
    const Eigen::MatrixXd ext = mapping::evaluate_on_surface_extended(
        disc.mesh, disc.space, solution.u, c, samples, input.V);
    std::vector<const BoundaryConditionSpec*> held(
        std::size_t(input.num_vertices()) * std::size_t(c), nullptr);
    for (const auto& bc : spec.boundary_conditions) {
      if (bc.type != BoundaryType::dirichlet) continue;
      for (int f = 0; f < input.num_faces(); ++f) {
        mapping::SelectionSite site;
        site.tag = input.has_tags() ? input.tags[f] : -1;
        site.normal = mapping::face_normal(input, f);
        for (int k = 0; k < 3; ++k) {
          const int v = input.F(f, k);
          site.x = input.V.row(v).transpose();
          if (!mapping::selects(bc.select, site)) continue;
          for (int i = 0; i < c; ++i)
            if ((c == 1 || bc.components[std::size_t(i)]) &&
                !held[std::size_t(v) * std::size_t(c) + std::size_t(i)])
              held[std::size_t(v) * std::size_t(c) + std::size_t(i)] = &bc;
        }
      }
    }
    for (int v = 0; v < input.num_vertices() && v < out.values.rows(); ++v) {
      if (samples.cell[v] < 0) continue;  // no image: stays NaN
      bool moved = false, data = false;
      for (int i = 0; i < c; ++i) {
        const BoundaryConditionSpec* bc = held[std::size_t(v) * std::size_t(c) + std::size_t(i)];
        if (bc) {
          out.values(v, i) = bc->value[std::size_t(i)](input.V.row(v).transpose());
          data = true;
        } else if (std::isfinite(ext(v, i))) {
          out.values(v, i) = ext(v, i);
          moved = true;
        }
      }
      extended += moved;
      from_data += data;
    }
  }
  out.fields.point_data.push_back(field_of(c == 1 ? "u" : "displacement", out.values));
  out.fields.point_data.push_back(field_of("phi_offset", out.images - input.V));
  out.report = json::object();
  {
    // The geometric error at every input vertex (issue 22): |φ(v) - v|, and the angle between
    // the curved boundary's normal at φ(v) and the nearest in direction of the normals of the
    // input faces around v (0 where φ(v) lies in one of them, as on a dense mesh).
    const BoundaryMap& map = domain.map();
    std::vector<std::vector<int>> faces_of(std::size_t(input.num_vertices()));
    for (int f = 0; f < input.num_faces(); ++f)
      for (int k = 0; k < 3; ++k) faces_of[std::size_t(input.F(f, k))].push_back(f);
    Eigen::MatrixXd deviation = Eigen::MatrixXd::Zero(input.num_vertices(), 1);
    double max_deviation = 0, sum_deviation = 0, max_offset = 0;
    long long counted = 0;
    for (int v = 0; v < input.num_vertices() && v < map.num_input_vertices(); ++v) {
      const int f = map.vertex_face[v];
      if (f < 0 || faces_of[std::size_t(v)].empty()) continue;
      const Eigen::MatrixXd J =
          map.boundary.jacobian(f, Eigen::Vector3d(map.vertex_uv(v, 0), map.vertex_uv(v, 1), 0));
      const Eigen::Vector3d du = J.col(0), dv = J.col(1);
      const Eigen::Vector3d n = du.cross(dv);
      if (!(n.norm() > 0)) continue;
      double best = 180;
      for (int t : faces_of[std::size_t(v)]) {
        const Eigen::Vector3d a = input.V.row(input.F(t, 0)), b = input.V.row(input.F(t, 1)),
                              c = input.V.row(input.F(t, 2));
        const Eigen::Vector3d m = (b - a).cross(c - a);
        if (!(m.norm() > 0)) continue;
        best = std::min(best, std::atan2(n.cross(m).norm(), n.dot(m)) * 180 / M_PI);
      }
      deviation(v, 0) = best;
      max_deviation = std::max(max_deviation, best);
      sum_deviation += best;
      ++counted;
      max_offset = std::max(max_offset, (out.images.row(v) - input.V.row(v)).norm());
    }
    out.fields.point_data.push_back(field_of("normal_deviation_deg", deviation));
    const double unit = bbox_longest_edge(input.V);
    out.report["surface_geometry"] = {
        {"max_phi_offset_rel", unit > 0 ? max_offset / unit : 0.0},
        {"max_normal_deviation_deg", max_deviation},
        {"mean_normal_deviation_deg", counted > 0 ? sum_deviation / double(counted) : 0.0},
        {"method",
         "per input vertex v: |phi(v) - v| / bbox edge, and the angle between the curved "
         "boundary's normal at phi(v) and the closest normal of the input faces around v; "
         "surface.vtu fields phi_offset, normal_deviation_deg"}};
  }
  if (errors.exact_value) {
    const mapping::SurfaceErrors e = mapping::surface_errors(input, out.values, errors.exact_value);
    out.fields.point_data.push_back(field_of("exact", e.exact));
    out.fields.point_data.push_back(field_of("error", e.error));
    out.report["surface_l2_error"] = e.l2;
    out.report["surface_l2_norm_exact"] = e.l2_exact;
    out.report["surface_max_error"] = e.max;
  }
  out.report["surface_vertices"] = input.num_vertices();
  out.report["surface_values"] = {
      {"method", values == SurfaceValues::extended
                     ? "u_h(phi(v)) + grad u_h(phi(v)) . (v - phi(v)) where no Dirichlet "
                       "condition holds v; the Dirichlet data g(v) where one does "
                       "(component-wise)"
                     : "u_h(phi(v))"},
      {"extended_vertices", extended},
      {"dirichlet_data_vertices", from_data}};
  long long unmapped = 0;
  for (Eigen::Index v = 0; v < samples.cell.size(); ++v) unmapped += samples.cell[v] < 0;
  out.report["surface_unmapped_vertices"] = unmapped;
  for (std::size_t i = 0; i < spec.boundary_conditions.size(); ++i) {
    const auto& bc = spec.boundary_conditions[i];
    Field f{"bc" + std::to_string(i) + "_" + to_string(bc.type), 1, {}};
    for (int k = 0; k < input.num_faces(); ++k)
      f.values.push_back(mapping::face_coverage(bc.select, input, k));
    out.fields.cell_data.push_back(f);
  }
  ctx.update("transfer to input", 1.0);
  return out;
}

namespace {

/// The report keys of one load case: errors, surface errors, physics details, solver.
json load_report(const LoadResult& l) {
  json report = l.errors.report.is_object() ? l.errors.report : json::object();
  if (l.on_input)
    for (const auto& [k, v] : l.on_input->report.items()) report[k] = v;
  report["physics_details"] = l.solution.physics;
  const fem::LinearSolveInfo& s = l.solution.solve;
  report["solver"] = {{"method", s.method},
                      {"iterations", s.iterations},
                      {"relative_residual", s.relative_residual},
                      {"setup_s", s.setup_s},
                      {"solve_s", s.solve_s},
                      {"near_nullspace", s.near_nullspace},
                      {"null_space_dim", s.null_space_dim},
                      {"reused_factorization", s.reused_factorization}};
  if (s.ranks > 1) {
    report["solver"]["ranks"] = s.ranks;
    report["solver"]["rows_per_rank"] = s.rows_per_rank;
    report["solver"]["partitioner"] = s.partitioner;
    report["solver"]["partition_s"] = s.partition_s;
    report["solver"]["distribute_s"] = s.distribute_s;
    report["solver"]["assembled_by_rows"] = s.assembled_by_rows;
    if (!s.parallel_ptap.empty()) report["solver"]["parallel_ptap"] = s.parallel_ptap;
    if (!s.rank_shares.empty()) {
      report["solver"]["rank_shares"] = s.rank_shares;
      report["solver"]["rank_heap_mb"] = s.rank_heap_mb;
    }
    if (s.assembled_by_rows) report["solver"]["rows_assembly_s"] = s.assembly_s;
  }
  return report;
}

bool named(const std::vector<LoadResult>& loads) {
  return !(loads.size() == 1 && loads[0].load.name.empty());
}

/// A field name with the load case's suffix ("u" → "u_lift"; unnamed: unchanged).
std::string suffixed(const std::string& field, const LoadCase& load) {
  return load.name.empty() ? field : field + "_" + load.name;
}

/// volume.vtu's point fields of one load case, on `out_space` (unsuffixed names).
std::vector<Field> volume_fields(const CaseSpec& spec, const Discretization& disc,
                                 const fem::FunctionSpace& out_space, const LoadResult& l) {
  const int c = l.solution.components;
  const Eigen::MatrixXd values = fem::interpolate_field(disc.space, l.solution.u, c, out_space);
  std::vector<Field> fields;
  Field uf{c == 1 ? "u" : "displacement", c, {}};
  uf.values.resize(std::size_t(values.size()));
  for (int r = 0; r < values.rows(); ++r)
    for (int i = 0; i < c; ++i) uf.values[static_cast<std::size_t>(r) * c + i] = values(r, i);
  fields.push_back(uf);
  if (l.errors.exact_value) {
    Field ef{"exact", c, {}}, err{"error", c, {}};
    for (int r = 0; r < out_space.num_dofs; ++r) {
      double ex[3];
      l.errors.exact_value(out_space.dof_points.row(r).transpose(), ex);
      for (int i = 0; i < c; ++i) {
        ef.values.push_back(ex[i]);
        err.values.push_back(values(r, i) - ex[i]);
      }
    }
    fields.push_back(ef);
    fields.push_back(err);
  }
  if (spec.physics == Physics::linear_elasticity) {
    const Eigen::VectorXd vm =
        fem::von_mises_at_dofs(disc.mesh, out_space, {spec.E, spec.nu},
                               values.transpose().reshaped(), l.solution.cell_material);
    fields.push_back({"von_mises", 1, std::vector<double>(vm.data(), vm.data() + vm.size())});
  }
  return fields;
}

}  // namespace

json run_report(const CaseSpec& spec, const Domain& domain, const Discretization& disc,
                const std::vector<LoadResult>& loads) {
  CF_VERIFY(!loads.empty(), "run_report: no load case");
  json report = json::object();
  if (!named(loads)) {
    report = load_report(loads[0]);
  } else {
    report["load_cases"] = json::array();
    for (const LoadResult& l : loads) {
      json r = load_report(l);
      r["name"] = l.load.name;
      report["load_cases"].push_back(r);
    }
  }
  report["command"] = "run";
  report["case"] = spec.case_file.string();
  report["method"] = spec.method;
  if (domain.on_input()) {
    report["surface"] =
        spec.surface.empty() ? "builtin " + to_string(spec.builtin_surface) : spec.surface.string();
    report["meshing"] = domain.report;
    report["mesh_valid"] = domain.valid;
  } else {
    report["mesh"] = (spec.builtin == BuiltinVolume::none) ? spec.mesh.string()
                                                           : "builtin " + to_string(spec.builtin);
    if (domain.report.contains("data_surface"))
      report["data_surface"] = domain.report["data_surface"];
  }
  report["tets"] = disc.mesh.num_cells();
  report["order"] = disc.mesh.order;
  report["degree"] = spec.degree;
  report["solve_geometry"] = disc.solve_geometry;
  report["physics"] = spec.physics;
  report["dofs"] = static_cast<long long>(disc.space.num_dofs) * spec.components();
  report["nodes"] = disc.space.num_dofs;
  return report;
}

void write_outputs(const CaseSpec& spec, const Domain& domain, const Discretization& disc,
                   const std::vector<LoadResult>& loads, const OutputOptions& options, json& report,
                   const StageContext& ctx) {
  const LagrangeMesh& mesh = disc.mesh;
  const int c = spec.components();
  const bool several = named(loads);
  // Nothing is written before this point; a failure while writing removes what was made.
  const bool existed = std::filesystem::exists(spec.output_dir);
  std::optional<StagedOutputDir> staged;
  try {
    staged.emplace(spec.output_dir);
    StagedOutputDir& out = *staged;
    std::vector<io::PvdEntry> parts{{"volume.vtu", 0, 0.0, "volume"}};
    {
      std::optional<ScopedTimer> t;
      if (ctx.timings) t.emplace(*ctx.timings, "output");
      ctx.update("write output", 0.0);
      const int m = std::max(spec.degree, mesh.order);
      const fem::FunctionSpace out_space =
          m == spec.degree ? disc.space : fem::build_function_space(mesh, m);
      const LagrangeMesh volume = fem::lagrange_mesh_of_space(mesh, out_space);
      LagrangeMesh surface;
      if (domain.on_input()) {
        surface.kind = CellKind::triangle;
        surface.order = 1;
        surface.nodes = domain.input.V;
        surface.cells = domain.input.F;
        if (domain.input.has_tags()) surface.cell_tags = domain.input.tags;
      }
      std::vector<Field> quality;
      for (const Field& f : domain.cell_quality)
        if (int(f.values.size()) == mesh.num_cells()) quality.push_back(f);
      MeshFields all, all_surface;
      all.cell_data = quality;
      if (several) parts.clear();
      for (std::size_t i = 0; i < loads.size(); ++i) {
        const LoadResult& l = loads[i];
        MeshFields own;
        own.point_data = volume_fields(spec, disc, out_space, l);
        own.cell_data = quality;
        if (l.errors.cell_estimate.size() == mesh.num_cells()) {
          const Eigen::VectorXd& eta = l.errors.cell_estimate;
          Field f{"error_indicator", 1, std::vector<double>(eta.data(), eta.data() + eta.size())};
          own.cell_data.push_back(f);
          f.name = suffixed(f.name, l.load);
          all.cell_data.push_back(std::move(f));
        }
        for (Field f : own.point_data) {
          f.name = suffixed(f.name, l.load);
          all.point_data.push_back(std::move(f));
        }
        if (l.on_input)
          for (Field f : l.on_input->fields.point_data) {
            const bool shared = f.name == "phi_offset" || f.name == "normal_deviation_deg";
            if (shared && i > 0) continue;  // the same for every load case
            if (!shared) f.name = suffixed(f.name, l.load);
            all_surface.point_data.push_back(std::move(f));
          }
        if (l.on_input)
          for (Field f : l.on_input->fields.cell_data) {
            f.name = suffixed(f.name, l.load);
            all_surface.cell_data.push_back(std::move(f));
          }
        if (several) {
          // One time step of result.pvd per load case, its fields without the suffix.
          const std::string vname = "volume_" + l.load.name + ".vtu";
          io::write_vtu(out.path(vname), volume, own);
          parts.push_back({vname, 0, double(i), l.load.name});
          if (l.on_input) {
            const std::string sname = "surface_" + l.load.name + ".vtu";
            io::write_vtu(out.path(sname), surface, l.on_input->fields);
            parts.push_back({sname, 1, double(i), l.load.name});
          }
        }
      }
      io::write_vtu(out.path("volume.vtu"), volume, all);
      if (domain.on_input()) {
        io::write_vtu(out.path("surface.vtu"), surface, all_surface);
        if (!several) parts.push_back({"surface.vtu", 1, 0.0, "surface"});
      }
      if (domain.on_input() && domain.repair) {
        // meshing.merge_short_edges: the same fields on the input as read, each merged-away
        // vertex with its repaired vertex's values, each face merged away NaN.
        const InputRepair& rep = *domain.repair;
        LagrangeMesh original;
        original.kind = CellKind::triangle;
        original.order = 1;
        original.nodes = rep.original.V;
        original.cells = rep.original.F;
        if (rep.original.has_tags()) original.cell_tags = rep.original.tags;
        std::vector<int> face_of(std::size_t(rep.original.num_faces()), -1);
        for (std::size_t i = 0; i < rep.face_origin.size(); ++i)
          face_of[std::size_t(rep.face_origin[i])] = int(i);
        auto gather = [](const Field& f, const std::vector<int>& from) {
          Field g{f.name, f.components, {}};
          g.values.reserve(from.size() * std::size_t(f.components));
          for (int i : from)
            for (int c = 0; c < f.components; ++c)
              g.values.push_back(
                  i < 0 ? std::nan("")
                        : f.values[std::size_t(i) * std::size_t(f.components) + std::size_t(c)]);
          return g;
        };
        MeshFields on_original;
        for (const Field& f : all_surface.point_data)
          on_original.point_data.push_back(gather(f, rep.vertex_map));
        for (const Field& f : all_surface.cell_data)
          on_original.cell_data.push_back(gather(f, face_of));
        io::write_vtu(out.path("surface_input.vtu"), original, on_original);
      }
      write_text_file_atomic(out.path("resolved_case.json"), spec.resolved.dump(2) + "\n");
      if (domain.curved_map && domain.fibers && !domain.outer_box) {
        // The mesh, φ and the fibers, so that geometry.mesh_dir can reuse this folder. A
        // built-in or repaired (meshing.merge_short_edges) input is saved beside them (input.msh
        // with its tags, recorded relative to the folder).
        std::string input, checksum;
        if (!spec.mesh_dir.empty()) {  // the input and checksum the reused folder was checked by
          input = domain.report.at("reused").at("input").get<std::string>();
          checksum = domain.report.at("reused").at("input_checksum").get<std::string>();
        } else if (!spec.surface.empty() && !(spec.merge_short_edges > 0)) {
          input = std::filesystem::absolute(spec.surface).string();
          checksum = file_checksum(spec.surface);
        } else {
          io::write_surface(out.path("input.msh"), domain.input, io::SurfaceFormat::msh41);
          input = "input.msh";
          checksum = file_checksum(out.path("input.msh"));
        }
        save_mesh_dir(out.path("."), domain.mesh, *domain.curved_map, *domain.fibers, input,
                      checksum);
      }
    }
    io::write_pvd(out.path("result.pvd"), parts);
    if (options.paraview) {
      ParaviewScriptOptions script;
      script.dir = std::filesystem::absolute(spec.output_dir);
      script.field = suffixed(c == 1 ? "u" : "displacement", loads[0].load);
      script.components = c;
      script.surface = domain.on_input();
      script.exact = !loads[0].load.exact.empty();
      write_text_file_atomic(out.path("open_in_paraview.py"), paraview_state_script(script));
    }
    if (ctx.timings) {
      if (options.total) ctx.timings->add("total", options.total->seconds());
      report["time_s"] = timings_json(*ctx.timings);
    }
    report["peak_rss_mb"] = peak_rss_mb();
    if (fem::distributed::active()) {
      // Several ranks (fem/solvers/distributed.hpp): the linear solves are distributed, and the
      // linear problems with Dirichlet data assemble their matrix by rows (solver
      // "assembled_by_rows"): one rank's rows at a time on rank 0, never the whole matrix.
      report["mpi"] = {{"ranks", fem::distributed::size()},
                       {"distributed",
                        "linear solves; matrix storage (assembled by rows on rank 0, one rank's "
                        "rows at a time, where the solver reports assembled_by_rows); all other "
                        "stages on rank 0"},
                       {"peak_rss_mb_per_rank", fem::distributed::peak_rss_mb_per_rank()}};
    }
    write_text_file_atomic(out.path("report.json"), report.dump(2) + "\n");
    out.commit();
  } catch (...) {
    staged.reset();  // removes the staging folder
    std::error_code ec;
    if (!existed) std::filesystem::remove(spec.output_dir, ec);  // only if empty
    throw;
  }
  ctx.update("write output", 1.0);
}

}  // namespace curvefem::pipeline
