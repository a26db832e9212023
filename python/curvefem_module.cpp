// The `curvefem` Python module's native part (`curvefem._curvefem`, pybind11): the pipeline
// library's stages (pipeline/stages.hpp) and run_case, with arrays as NumPy arrays and reports as
// JSON text (curvefem/__init__.py turns them into dicts). Long stages release the GIL; progress
// callbacks take it back. curvefem errors become Python exceptions carrying the CLI's exit code.
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <tbb/global_control.h>

#include <filesystem>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "fem/solvers/linear_solver.hpp"
#include "meshing/check/check_surface.hpp"
#include "meshing/check/merge_short_edges.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/io/vtu_io.hpp"
#include "meshing/param/deform.hpp"
#include "pipeline/case_file.hpp"
#include "pipeline/case_schema.hpp"
#include "pipeline/mesh_dir.hpp"
#include "pipeline/report_json.hpp"
#include "pipeline/run_case.hpp"
#include "pipeline/stages.hpp"
#include "pipeline/study.hpp"
#include "pipeline/study_file.hpp"

namespace py = pybind11;
using namespace curvefem;
using namespace curvefem::pipeline;

namespace {

/// A Python progress callable as a ProgressFn that may be copied and called from any thread.
ProgressFn progress_of(const py::object& callback) {
  if (callback.is_none()) return {};
  std::shared_ptr<py::object> held(new py::object(callback), [](py::object* o) {
    py::gil_scoped_acquire gil;
    delete o;
  });
  return [held](std::string_view stage, double fraction) {
    py::gil_scoped_acquire gil;
    try {
      (*held)(std::string(stage), fraction);
    } catch (py::error_already_set& e) {
      e.discard_as_unraisable("curvefem progress callback");
    }
  };
}

/// oneTBB uses at most `threads` workers while it lives (0: all cores).
std::unique_ptr<tbb::global_control> limit_threads(int threads) {
  if (threads <= 0) return nullptr;
  curvefem::fem::set_blas_threads(threads);  // the BLAS under CHOLMOD and PETSc too
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                               static_cast<std::size_t>(threads));
}

/// The load case `name` of a case ("": the first).
LoadCase load_of(const CaseSpec& spec, const std::string& name) {
  const std::vector<LoadCase> loads = spec.loads();
  if (name.empty()) return loads.front();
  for (const LoadCase& l : loads)
    if (l.name == name) return l;
  throw InputError("no load case named '" + name + "'", {.file = spec.case_file.string()});
}

}  // namespace

PYBIND11_MODULE(_curvefem, m) {
  m.doc() = "curvefem: coarse curved tetrahedral meshes with a bijective boundary map, and p-FEM";

  // Exception classes: curvefem.Error (a RuntimeError) and one subclass per error kind, each
  // instance with `exit_code` (the CLI's: 2 input, 3 meshing/solver, 4 I/O).
  auto make = [&m](const char* name, PyObject* base) {
    PyObject* type =
        PyErr_NewException((std::string("curvefem._curvefem.") + name).c_str(), base, nullptr);
    m.attr(name) = py::handle(type);
    return type;
  };
  static PyObject* error = make("Error", PyExc_RuntimeError);
  static PyObject* input_error = make("InputError", error);
  static PyObject* meshing_error = make("MeshingError", error);
  static PyObject* solver_error = make("SolverError", error);
  static PyObject* io_error = make("IoError", error);
  py::register_exception_translator([](std::exception_ptr p) {
    auto raise = [](PyObject* type, const Error& e) {
      py::object instance = py::reinterpret_borrow<py::object>(type)(e.what());
      instance.attr("exit_code") = e.exit_code();
      PyErr_SetObject(type, instance.ptr());
    };
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      raise(input_error, e);
    } catch (const MeshingError& e) {
      raise(meshing_error, e);
    } catch (const SolverError& e) {
      raise(solver_error, e);
    } catch (const IoError& e) {
      raise(io_error, e);
    } catch (const Error& e) {
      raise(error, e);
    }
  });

  m.def(
      "set_log_level", [](const std::string& level) { log::set_level(log::parse_level(level)); },
      py::arg("level"), "trace | debug | info | warn | error | off");

  m.def(
      "check_surface",
      [](const std::string& path) {
        const SurfaceMesh s = io::read_surface(path);
        return check_report_json(check::check_surface(s, {})).dump();
      },
      py::arg("path"), "The `curvefem check` report of a surface file, as JSON text.");

  m.def(
      "merge_short_edges",
      [](const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, double length) {
        if (V.cols() != 3 || F.cols() != 3)
          throw InputError("merge_short_edges: vertices and faces must have 3 columns");
        if (F.size() > 0 && (F.minCoeff() < 0 || F.maxCoeff() >= V.rows()))
          throw InputError("merge_short_edges: a face index is out of range");
        SurfaceMesh s;
        s.V = V;
        s.F = F;
        const check::MergeShortEdgesResult r =
            check::merge_short_edges(s, {.max_length = length * bbox_longest_edge(V)});
        std::vector<std::tuple<int, int, double>> pairs;
        for (const check::MergedEdge& e : r.merged) pairs.emplace_back(e.removed, e.kept, e.length);
        return std::make_tuple(r.mesh.V, r.mesh.F, r.vertex_map, r.face_origin, pairs, r.candidates,
                               r.refused, r.max_moved);
      },
      py::arg("vertices"), py::arg("faces"), py::arg("length"),
      "check::merge_short_edges (the Python function of that name wraps it).");

  py::class_<SurfaceMesh, std::shared_ptr<SurfaceMesh>>(m, "Surface")
      .def_property_readonly("vertices", [](const SurfaceMesh& s) { return s.V; })
      .def_property_readonly("faces", [](const SurfaceMesh& s) { return s.F; })
      .def_property_readonly("tags", [](const SurfaceMesh& s) { return s.tags; });

  py::class_<CaseSpec, std::shared_ptr<CaseSpec>>(m, "Case")
      .def_property_readonly("resolved_json", [](const CaseSpec& c) { return c.resolved.dump(); })
      .def_property_readonly("output_dir", [](const CaseSpec& c) { return c.output_dir.string(); })
      .def_property_readonly("method", [](const CaseSpec& c) { return to_string(c.method); })
      .def_property_readonly("physics", [](const CaseSpec& c) { return to_string(c.physics); })
      .def_property_readonly("degree", [](const CaseSpec& c) { return c.degree; })
      .def_property_readonly("order", [](const CaseSpec& c) { return c.order; })
      .def_property_readonly("eps", [](const CaseSpec& c) { return c.eps; })
      .def_property_readonly("components", &CaseSpec::components);

  m.def(
      "read_case",
      [](const std::string& path, const std::string& output) {
        return std::make_shared<CaseSpec>(read_case(path, output));
      },
      py::arg("path"), py::arg("output_dir") = "");
  m.def(
      "read_case_json",
      [](const std::string& text, const std::string& path, const std::string& output) {
        nlohmann::json j;
        try {
          j = nlohmann::json::parse(text);
        } catch (const nlohmann::json::parse_error& e) {
          throw InputError(std::string("invalid JSON: ") + e.what(), {.file = path});
        }
        return std::make_shared<CaseSpec>(read_case_json(j, path, output));
      },
      py::arg("text"), py::arg("path"), py::arg("output_dir") = "");
  m.def(
      "case_schema_json", [] { return case_schema_json().dump(); },
      "The case-file keys (pipeline/case_schema.hpp) as a JSON array of objects.");
  m.def("case_schema_markdown", &case_schema_markdown,
        "cases/README.md's key table, generated from the schema.");

  m.def(
      "load_surface",
      [](const CaseSpec& spec) {
        py::gil_scoped_release release;
        return std::make_shared<SurfaceMesh>(load_surface(spec));
      },
      py::arg("case"));

  py::class_<Domain, std::shared_ptr<Domain>>(
      m, "Domain",
      "The mesh a case runs on (stage 2: curvefem.mesh or curvefem.load_mesh): the tetrahedra of "
      "order k and, for curved | dense meshes, the dense input and the boundary map phi.")
      .def_property_readonly(
          "method", [](const Domain& d) { return to_string(d.method); }, "curved | dense | given")
      .def_property_readonly(
          "nodes", [](const Domain& d) { return d.mesh.nodes; },
          "#N x 3 Lagrange node coordinates of the tet mesh (order k).")
      .def_property_readonly(
          "cells", [](const Domain& d) { return d.mesh.cells; },
          "#C x (k+1)(k+2)(k+3)/6 node ids per tet, canonical local order (docs/conventions.md): "
          "the 4 corners first, then edge, face and interior nodes.")
      .def_property_readonly(
          "cell_tags", [](const Domain& d) { return d.mesh.cell_tags; },
          "#C region tags, or empty.")
      .def_property_readonly(
          "order", [](const Domain& d) { return d.mesh.order; }, "The geometric order k (1..4).")
      .def_property_readonly(
          "valid", [](const Domain& d) { return d.valid; },
          "curved: the independent validation passed (or was not asked for).")
      .def_property_readonly(
          "report_json", [](const Domain& d) { return d.report.dump(); },
          "report.json's \"meshing\" section, as JSON text (Domain.report: a dict).")
      .def_property_readonly(
          "input_vertices", [](const Domain& d) { return d.input.V; },
          "#V x 3 vertices of the dense input (curved | dense; empty for given meshes).")
      .def_property_readonly(
          "input_faces", [](const Domain& d) { return d.input.F; },
          "#F x 3 triangles of the dense input.")
      .def_property_readonly(
          "vertex_face", [](const Domain& d) { return d.map().vertex_face; },
          "phi as (face, u, v), part 1: per input vertex, the boundary triangle (a row of "
          "boundary_cells) its image lies in; -1 for an unreferenced vertex.")
      .def_property_readonly(
          "vertex_uv", [](const Domain& d) { return d.map().vertex_uv; },
          "phi as (face, u, v), part 2: #V x 2 reference coordinates in that triangle.")
      .def_property_readonly(
          "boundary_nodes", [](const Domain& d) { return d.map().boundary.nodes; },
          "#B x 3 nodes of the curved boundary triangles phi maps onto (order k).")
      .def_property_readonly(
          "boundary_cells", [](const Domain& d) { return d.map().boundary.cells; },
          "#T x (k+1)(k+2)/2 node ids (rows of boundary_nodes) per boundary triangle, "
          "canonical order: corners, edges (0,1) (0,2) (1,2), interior.")
      .def_property_readonly(
          "boundary_node_to_volume",
          [](const Domain& d) { return d.map().boundary_node_to_volume; },
          "Per boundary node, the row of nodes it is (-1: not tied to the volume mesh).")
      .def_property_readonly(
          "cell_quality",
          [](const Domain& d) {
            std::vector<std::tuple<std::string, int, std::vector<double>>> out;
            for (const Field& f : d.cell_quality) out.emplace_back(f.name, f.components, f.values);
            return out;
          },
          "curved: the validator's per-tet fields (name, components, values), as in mesh.vtu.")
      .def(
          "phi",
          [](const Domain& d) {
            const BoundaryMap& map = d.map();
            Eigen::MatrixXd X(map.num_input_vertices(), 3);
            for (int v = 0; v < map.num_input_vertices(); ++v)
              X.row(v) = map.vertex_face[v] >= 0 ? Eigen::RowVector3d(map.image(v).transpose())
                                                 : Eigen::RowVector3d::Constant(std::nan(""));
            return X;
          },
          "φ(v) for every input vertex (#V × 3; NaN for unreferenced vertices).");

  m.def(
      "load_mesh_dir",
      [](const std::string& dir, bool validate, int threads, const py::object& progress) {
        CaseSpec spec;
        spec.method = MeshingMethod::curved;
        spec.mesh_dir = std::filesystem::absolute(dir).lexically_normal();
        spec.validate = validate;
        for (const char* name : {"mesh.msh", "boundary_map.json", "report.json"})
          if (!std::filesystem::is_regular_file(spec.mesh_dir / name))
            throw InputError("no " + std::string(name) +
                                 " in it (not a `curvefem mesh` or curved `curvefem run` output)",
                             {.file = spec.mesh_dir.string()});
        const ProgressFn fn = progress_of(progress);
        py::gil_scoped_release release;
        const auto limit = limit_threads(threads);
        return std::make_shared<Domain>(load_mesh_dir(spec, {.threads = threads, .progress = fn}));
      },
      py::arg("dir"), py::arg("validate") = true, py::arg("threads") = 0,
      py::arg("progress") = py::none(),
      "The Domain of a saved curved mesh folder (pipeline/mesh_dir.hpp), without meshing.");

  m.def(
      "vtk_node_permutation",
      [](int order) { return io::vtk_node_permutation(CellKind::tetrahedron, order); },
      py::arg("order"),
      "perm with VTK local node i = canonical local node perm[i] for a tet of this order (VTK "
      "quadratic tetra for 2, VTK_LAGRANGE_TETRAHEDRON for 3, 4).");

  m.def(
      "mesh_domain",
      [](const CaseSpec& spec, std::shared_ptr<SurfaceMesh> input, int threads,
         const py::object& progress) {
        const ProgressFn fn = progress_of(progress);
        py::gil_scoped_release release;
        const auto limit = limit_threads(threads);
        return std::make_shared<Domain>(mesh_domain(spec, input ? *input : SurfaceMesh{},
                                                    {.threads = threads, .progress = fn}));
      },
      py::arg("case"), py::arg("surface") = nullptr, py::arg("threads") = 0,
      py::arg("progress") = py::none());

  py::class_<Discretization, std::shared_ptr<Discretization>>(m, "Discretization")
      .def_property_readonly("nodes", [](const Discretization& d) { return d.mesh.nodes; })
      .def_property_readonly("cells", [](const Discretization& d) { return d.mesh.cells; })
      .def_property_readonly("order", [](const Discretization& d) { return d.mesh.order; })
      .def_property_readonly("degree", [](const Discretization& d) { return d.space.degree; })
      .def_property_readonly("dof_points",
                             [](const Discretization& d) { return d.space.dof_points; })
      .def_property_readonly(
          "dof_cells", [](const Discretization& d) { return d.space.cell_dofs; },
          "#C x (p+1)(p+2)(p+3)/6 DOF ids (rows of dof_points) per tet, canonical order.")
      .def_property_readonly("dofs", [](const Discretization& d) {
        return static_cast<long long>(d.space.num_dofs) * d.components;
      });

  m.def(
      "discretize",
      [](const CaseSpec& spec, const Domain& domain) {
        py::gil_scoped_release release;
        return std::make_shared<Discretization>(discretize(spec, domain));
      },
      py::arg("case"), py::arg("domain"), py::keep_alive<0, 2>());

  py::class_<Solution, std::shared_ptr<Solution>>(m, "Solution")
      .def_property_readonly(
          "values",
          [](const Solution& s) {
            return Eigen::MatrixXd(
                s.u.reshaped(s.components, s.u.size() / s.components).transpose());
          })
      .def_property_readonly("components", [](const Solution& s) { return s.components; })
      .def_property_readonly("null_space_dim", [](const Solution& s) { return s.null_space_dim; })
      .def_property_readonly("physics_json", [](const Solution& s) { return s.physics.dump(); })
      .def_property_readonly("solver_method", [](const Solution& s) { return s.solve.method; })
      .def_property_readonly("solver_iterations",
                             [](const Solution& s) { return s.solve.iterations; });

  m.def(
      "solve",
      [](const CaseSpec& spec, const Domain& domain, const Discretization& disc,
         const std::string& load, int threads, const py::object& progress) {
        const ProgressFn fn = progress_of(progress);
        py::gil_scoped_release release;
        const auto limit = limit_threads(threads);
        const LoadCase l = load_of(spec, load);
        const BoundaryData data = bind_boundary(spec, l.boundary_conditions, domain, disc);
        return std::make_shared<Solution>(
            solve(spec, disc, data, l.rhs, {.threads = threads, .progress = fn}));
      },
      py::arg("case"), py::arg("domain"), py::arg("discretization"), py::arg("load") = "",
      py::arg("threads") = 0, py::arg("progress") = py::none(), py::keep_alive<0, 3>());

  py::class_<ErrorResult, std::shared_ptr<ErrorResult>>(m, "Errors")
      .def_property_readonly("report_json", [](const ErrorResult& e) { return e.report.dump(); });
  m.def(
      "compute_errors",
      [](const CaseSpec& spec, const Discretization& disc, const Solution& solution,
         const std::string& load) {
        py::gil_scoped_release release;
        return std::make_shared<ErrorResult>(compute_errors(load_of(spec, load), disc, solution));
      },
      py::arg("case"), py::arg("discretization"), py::arg("solution"), py::arg("load") = "");

  py::class_<InputSolution, std::shared_ptr<InputSolution>>(m, "InputSolution")
      .def_property_readonly("values", [](const InputSolution& s) { return s.values; })
      .def_property_readonly("images", [](const InputSolution& s) { return s.images; })
      .def_property_readonly("report_json", [](const InputSolution& s) { return s.report.dump(); });
  m.def(
      "transfer_to_input",
      [](const CaseSpec& spec, const Domain& domain, const Discretization& disc,
         const Solution& solution, std::shared_ptr<ErrorResult> errors, const std::string& load) {
        py::gil_scoped_release release;
        // Without errors: u_h(φ(v)) and φ(v) only (no exact / error fields).
        return std::make_shared<InputSolution>(
            transfer_to_input(load_of(spec, load), domain, disc, solution,
                              errors ? *errors : ErrorResult{}, {}, spec.surface_values));
      },
      py::arg("case"), py::arg("domain"), py::arg("discretization"), py::arg("solution"),
      py::arg("errors") = nullptr, py::arg("load") = "");

  py::class_<RunOutcome, std::shared_ptr<RunOutcome>>(m, "RunOutcome")
      .def_property_readonly("report_json", [](const RunOutcome& o) { return o.report.dump(); })
      .def_property_readonly("exit_code", [](const RunOutcome& o) { return o.exit_code; })
      .def_property_readonly("timings",
                             [](const RunOutcome& o) {
                               std::vector<std::pair<std::string, double>> t;
                               for (const auto& [stage, s] : o.timings.stages())
                                 t.emplace_back(stage, s);
                               return t;
                             })
      .def_property_readonly("domain",
                             [](const RunOutcome& o) {
                               return std::const_pointer_cast<Domain>(
                                   std::shared_ptr<const Domain>(o.results, &o.results->domain));
                             })
      .def_property_readonly(
          "discretization",
          [](const RunOutcome& o) {
            return std::const_pointer_cast<Discretization>(
                std::shared_ptr<const Discretization>(o.results, &o.results->disc));
          })
      .def_property_readonly("load_names",
                             [](const RunOutcome& o) {
                               std::vector<std::string> names;
                               for (const LoadResult& l : o.results->loads)
                                 names.push_back(l.load.name);
                               return names;
                             })
      .def(
          "solution",
          [](const RunOutcome& o, std::size_t i) {
            if (i >= o.results->loads.size()) throw py::index_error("no such load case");
            return std::const_pointer_cast<Solution>(
                std::shared_ptr<const Solution>(o.results, &o.results->loads[i].solution));
          },
          py::arg("index") = 0)
      .def(
          "on_input",
          [](const RunOutcome& o, std::size_t i) {
            if (i >= o.results->loads.size()) throw py::index_error("no such load case");
            const LoadResult& l = o.results->loads[i];
            return l.on_input ? std::const_pointer_cast<InputSolution>(
                                    std::shared_ptr<const InputSolution>(o.results, &*l.on_input))
                              : nullptr;
          },
          py::arg("index") = 0);

  m.def(
      "run_case",
      [](const CaseSpec& spec, int threads, bool paraview, bool write, const py::object& progress) {
        const ProgressFn fn = progress_of(progress);
        py::gil_scoped_release release;
        const auto limit = limit_threads(threads);
        return std::make_shared<RunOutcome>(
            run_case(spec, {.threads = threads, .paraview = paraview, .write = write}, fn));
      },
      py::arg("case"), py::arg("threads") = 0, py::arg("paraview") = false, py::arg("write") = true,
      py::arg("progress") = py::none());

  m.def(
      "deform",
      [](const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const Eigen::VectorXi& target_vertices,
         const Eigen::MatrixXd& target_positions, double grow, double box, int iterations,
         double tolerance, bool untangle, double arap, bool way_back_targets,
         double rebuild_quality, bool sliver_rests, int threads) {
        namespace pa = meshing::param;
        if (target_vertices.size() != target_positions.rows() ||
            (target_positions.size() > 0 && target_positions.cols() != 3))
          throw InputError("deform: targets need one row (x, y, z) per target vertex");
        SurfaceMesh surface;
        surface.V = V;
        surface.F = F;
        std::vector<pa::PositionTarget> targets;
        for (Eigen::Index i = 0; i < target_vertices.size(); ++i)
          targets.push_back({target_vertices[i], target_positions.row(i).transpose()});
        pa::DeformRequest request;
        request.targets = std::move(targets);
        request.options.grow = grow;
        request.options.box_scale = box;
        request.options.max_iterations = iterations;
        request.options.tolerance = tolerance;
        request.untangle = untangle;
        request.options.arap_weight = arap;
        request.options.rebuild_quality = rebuild_quality;
        request.options.replace_slivers = sliver_rests;
        request.untangle_options.way_back_targets = way_back_targets;
        py::gil_scoped_release release;
        const auto limit = limit_threads(threads);
        // The same validation and exact checks as `curvefem deform` (meshing/param/deform.hpp).
        const pa::DeformOutcome outcome = pa::deform_checked(surface, request);
        const pa::Deform3dResult& result = outcome.result;
        nlohmann::ordered_json report;
        if (outcome.untangle)
          report["untangle"] = {
              {"input_self_intersecting_pairs", outcome.untangle->input_pairs},
              {"genus", outcome.untangle->genus},
              {"flow_steps", outcome.untangle->flow_pairs.size()},
              {"max_distance_to_input_rel", outcome.untangle->max_distance_rel},
              {"mean_distance_to_input_rel", outcome.untangle->mean_distance_rel},
              {"way_back_targets", way_back_targets},
              {"edge_length_error_mean", outcome.untangle->edge_length_error_mean},
              {"edge_length_error_max", outcome.untangle->edge_length_error_max}};
        nlohmann::ordered_json energy = nlohmann::ordered_json::array();
        for (const auto& st : result.history) energy.push_back(st.energy);
        report["iterations"] = result.history.back().iteration;
        report["stop_reason"] = result.stop_reason;
        report["energy"] = result.history.back().energy;
        report["energy_per_iteration"] = energy;
        report["target_error_rel"] = result.history.back().target_error;
        report["self_intersecting_pairs"] = outcome.final_pairs;
        report["max_self_intersecting_pairs_over_iterations"] = outcome.max_pairs_over_iterations;
        report["naive_self_intersecting_pairs"] = outcome.naive_pairs;
        report["non_positive_tets"] = outcome.tiling.non_positive_tets;
        report["tiling_boundary_mismatches"] = outcome.tiling.boundary_mismatches;
        report["valid"] = outcome.valid();
        report["seconds"] = result.seconds;
        report["scaffold_kept"] = result.scaffold_kept;
        int slivers = 0;
        for (const auto& st : result.history) slivers = std::max(slivers, st.slivers);
        report["sliver_rests"] = sliver_rests;
        report["max_slivers"] = slivers;
        return std::make_tuple(result.V, report.dump());
      },
      py::arg("V"), py::arg("F"), py::arg("target_vertices"), py::arg("target_positions"),
      py::arg("grow") = 1.0, py::arg("box") = 2.0, py::arg("iterations") = 50,
      py::arg("tolerance") = 1e-5, py::arg("untangle") = false, py::arg("arap") = 0.0,
      py::arg("way_back_targets") = true, py::arg("rebuild_quality") = 0.5,
      py::arg("sliver_rests") = false, py::arg("threads") = 0,
      "SCAF with a tet scaffold (meshing/param/scaf3d.hpp); returns (V, report JSON text). arap: "
      "weight of a surface ARAP term toward the input's shape; way_back_targets=False with "
      "untangle: the ARAP term alone brings the surface back (thesis Fig. 3.9); rebuild_quality: "
      "the scaffold is rebuilt when its worst tet fell below this x the last rebuild's (0: every "
      "iteration); sliver_rests: a flat scaffold tet's rest is a small regular tet, so the "
      "scaffold keeps sheets of the surface apart (thesis 3.2.2).");

  m.def(
      "run_study",
      [](const std::string& text, const std::string& path, const std::string& output, int threads,
         const py::object& progress) {
        const ProgressFn fn = progress_of(progress);
        // A file path (text empty) or a study already as JSON text (path names it).
        const StudySpec study =
            text.empty() ? read_study(path, output)
                         : read_study_json(nlohmann::ordered_json::parse(text), path, output);
        py::gil_scoped_release release;
        const auto limit = limit_threads(threads);
        const int total = static_cast<int>(study.runs.size());
        StudyCallbacks callbacks;
        if (fn)
          callbacks.start = [fn, total](int i, const StudyRun& run) -> ProgressFn {
            const std::string prefix =
                "[" + std::to_string(i + 1) + "/" + std::to_string(total) + "] " + run.name + ": ";
            return [fn, prefix](std::string_view stage, double fraction) {
              fn(prefix + std::string(stage), fraction);
            };
          };
        const StudyOutcome outcome = run_study(study, {.threads = threads}, callbacks);
        return std::make_tuple(outcome.report.dump(), outcome.exit_code());
      },
      py::arg("text"), py::arg("path"), py::arg("output") = "", py::arg("threads") = 0,
      py::arg("progress") = py::none(),
      "Runs a study (pipeline/study.hpp); returns (study.json text, exit code).");
}
