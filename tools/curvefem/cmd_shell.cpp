// `curvefem shell INPUT -o DIR [--thickness R] [--no-simplify] [--zoom R] [--pillar-cos C]
// [--remesh-section L] [--displacement-map L] [--cages K] [--texture TILE] [--boolean OP --with B]
// [--threads N]`:
// builds the prismatic shell of a closed surface (meshing/shell), verifies it with independent code
// and writes shell.vtu (prisms as VTK_WEDGE, cell data `half`: 0 base→mid, 1 mid→top,
// `input_face`), middle.obj and report.json. Without
// --no-simplify the shell is coarsened by collapses that keep it positive, a section of the input
// and separated from it (meshing/shell/simplify.hpp). With --remesh-section the middle surface is
// also remeshed isotropically as a section of the shell (meshing/shell/section_remesh.hpp) into
// remeshed.obj, and the roundtrip input → remeshed → input of a smooth field through P is reported.
// With
// --displacement-map a displacement map is baked through P (meshing/shell/displacement_map.hpp)
// and the surface it rebuilds is checked against the input and against normal projection; with
// --cages K nested cages are built around the input (meshing/shell/nested_cages.hpp; a cage's
// pinch points are shortened away before the next layer is built on it, and where a shell has
// zero thickness the cage is filled with a small tetrahedron), with --texture a tile
// is copied into every prism (meshing/shell/geometric_texture.hpp) of a copy of the shell whose
// top (base) surface, where the tile reaches, was first freed of self-intersections, with
// --boolean the shell is built on INPUT OP B (meshing/shell/boolean.hpp) and both operands'
// fields are carried onto its coarse remeshing; each is checked by
// tools/curvefem/shell_applications.hpp.
// Exit 0 when the shell verifies in full (positive, separated, a section, every input vertex
// mapped back by P⁻¹ then P) and every requested application checks out, 3 otherwise (the
// outputs are written and report.json says what failed), 2 for bad input.
// Where the input's own shell is not a section, the input is first refined by topological
// beveling (meshing/shell/bevel.hpp; same geometry) and the shell built, simplified and verified
// on the refined surface; `input_face` in shell.vtu still names faces of the input.
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "meshing/check/self_intersections.hpp"
#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/shell/bevel.hpp"
#include "meshing/shell/projection.hpp"
#include "meshing/shell/section.hpp"
#include "meshing/shell/section_remesh.hpp"
#include "meshing/shell/section_transfer.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/simplify.hpp"
#include "meshing/shell/verify.hpp"
#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"
#include "tools/curvefem/shell_applications.hpp"

namespace curvefem::cli {
namespace {

namespace sh = meshing::shell;

struct ShellArgs {
  std::string input, output;
  double thickness = 0.02;
  bool no_simplify = false;
  double remesh_section = 0;  // target edge relative to the longest bbox edge; 0: no remeshing
  double zoom = 0.1;
  double pillar_cos = sh::SimplifyOptions{}.section_cos;
  double pillar_cos_relative = sh::SimplifyOptions{}.section_cos_relative;
  int displacement_level = 0;  // --displacement-map L; 0: none
  int cages = 0;               // --cages K; 0: none
  std::string texture;         // --texture TILE; empty: none
  std::string boolean, with;   // --boolean OP --with B
  bool allow_self_intersections = false;
  GlobalOptions global;
};

// VTU (ascii) with one VTK_WEDGE (13) per half-prism; VTK's wedge lists the bottom triangle then
// the top one, both counter-clockwise seen from the same side, which our (base, mid, top) order is.
void write_wedges(const std::filesystem::path& path, const sh::Shell& s) {
  const int nv = int(s.mid.rows()), nf = int(s.F.rows());
  std::ostringstream out;
  out.precision(17);
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
         "byte_order=\"LittleEndian\">\n"
      << "<UnstructuredGrid><Piece NumberOfPoints=\"" << 3 * nv << "\" NumberOfCells=\"" << 2 * nf
      << "\">\n"
      << "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const Eigen::MatrixXd* M : {&s.base, &s.mid, &s.top})
    for (int v = 0; v < nv; ++v)
      out << (*M)(v, 0) << ' ' << (*M)(v, 1) << ' ' << (*M)(v, 2) << '\n';
  out << "</DataArray></Points>\n<Cells><DataArray type=\"Int64\" Name=\"connectivity\" "
         "format=\"ascii\">\n";
  for (int half = 0; half < 2; ++half)
    for (int f = 0; f < nf; ++f) {
      for (int k = 0; k < 3; ++k) out << half * nv + s.F(f, k) << ' ';
      for (int k = 0; k < 3; ++k) out << (half + 1) * nv + s.F(f, k) << ' ';
      out << '\n';
    }
  out << "</DataArray><DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (int c = 1; c <= 2 * nf; ++c) out << 6 * c << '\n';
  out << "</DataArray><DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (int c = 0; c < 2 * nf; ++c) out << "13\n";
  out << "</DataArray></Cells>\n<CellData><DataArray type=\"Int32\" Name=\"half\" "
         "format=\"ascii\">\n";
  for (int half = 0; half < 2; ++half)
    for (int f = 0; f < nf; ++f) out << half << '\n';
  out << "</DataArray><DataArray type=\"Int32\" Name=\"input_face\" format=\"ascii\">\n";
  for (int half = 0; half < 2; ++half)
    for (int f = 0; f < nf; ++f) out << s.face_parent[f] << '\n';
  out << "</DataArray></CellData>\n</Piece></UnstructuredGrid></VTKFile>\n";
  write_text_file_atomic(path, out.str());
}

// --remesh-section: isotropic remeshing of the middle surface kept a section of the shell, then
// the smooth test field carried input → remeshed → input through P. Fills `remeshed` and returns
// the report's `section_remesh` object (with `error` when the middle surface is no section).
nlohmann::ordered_json run_section_remesh(const sh::Shell& shell, const SurfaceMesh& input,
                                          double target_rel, int threads, SurfaceMesh& remeshed) {
  const double unit = bbox_longest_edge(input.V);
  nlohmann::ordered_json j = {{"target_edge_rel", target_rel}, {"target_edge", target_rel * unit}};
  Stopwatch clock;
  const sh::ShellProjection projection(shell, input);
  sh::SectionRemeshOptions options;
  options.target_edge = target_rel * unit;
  options.threads = threads > 0 ? threads : 2;
  sh::SectionRemeshResult r;
  try {
    r = sh::remesh_section(projection, options);
  } catch (const MeshingError& e) {
    j["is_section_verified"] = false;
    j["error"] = e.what();
    return j;
  }
  remeshed = r.mesh;
  const double remesh_s = clock.seconds();
  const Eigen::Vector3d center =
      0.5 * (input.V.colwise().minCoeff() + input.V.colwise().maxCoeff()).transpose();
  const Eigen::VectorXd f = sh::smooth_test_field(input.V, center, 0.5 * unit);
  const sh::FieldRoundtrip rt = sh::field_roundtrip(projection, input, r.mesh, f);
  j["vertices"] = r.mesh.num_vertices();
  j["faces"] = r.mesh.num_faces();
  j["is_section_verified"] = r.result.is_section();
  j["section_check"] = {{"manifold", r.result.manifold},
                        {"vertices_outside", r.result.vertices_outside},
                        {"faces_crossing_cage", r.result.faces_crossing_cage},
                        {"faces_not_transversal", r.result.faces_not_transversal},
                        {"degree_failures", r.result.degree_failures}};
  j["field"] = "sin(3x) cos(2y) + z^2 at (p - bbox center) / (longest bbox edge / 2)";
  j["field_roundtrip_max_error"] = rt.max_error;
  j["field_roundtrip_mean_error"] = rt.mean_error;
  j["field_roundtrip_failures"] = rt.failures;
  j["time_s"] = {{"remesh", remesh_s - r.result.seconds},
                 {"is_section", r.result.seconds},
                 {"roundtrip", clock.seconds() - remesh_s},
                 {"total", clock.seconds()}};
  return j;
}

}  // namespace

void register_shell(CLI::App& app) {
  auto args = std::make_shared<ShellArgs>();
  CLI::App* sub = app.add_subcommand(
      "shell", "build and verify the bijective prismatic shell of a closed surface");
  sub->add_option("input", args->input, "closed, oriented surface (.obj .off .stl .ply .msh)")
      ->required();
  sub->add_option("-o,--output", args->output, "output folder")->required();
  sub->add_option("--thickness", args->thickness,
                  "cap on each half-pillar, relative to the longest bbox edge")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--no-simplify", args->no_simplify, "keep the input as the middle surface");
  sub->add_option("--remesh-section", args->remesh_section,
                  "also remesh the middle surface isotropically to this edge length (relative to "
                  "the longest bbox edge), keeping it a section; writes remeshed.obj")
      ->check(CLI::PositiveNumber);
  sub->add_option("--zoom", args->zoom,
                  "simplification may grow each half-pillar up to this length, relative to the "
                  "longest bbox edge (0: never grow)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--pillar-cos", args->pillar_cos,
                  "distortion bound of simplification: each input face a new prism covers makes "
                  "at least this cosine with its pillars (0: the bare section condition)")
      ->check(CLI::Range(0.0, 0.5));
  sub->add_option("--pillar-cos-relative", args->pillar_cos_relative,
                  "where the input's own shell leans further than --pillar-cos from an input "
                  "face (a knife edge), the bound there is this fraction of its cosine (0: the "
                  "absolute bound everywhere)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--displacement-map", args->displacement_level,
                  "bake a displacement map of this level (samples per coarse face edge) through "
                  "P: writes displacement_map.txt, cage.obj and the rebuilt displaced.obj")
      ->check(CLI::Range(1, 64));
  sub->add_option("--cages", args->cages,
                  "also build this many nested cages around the input (each the top surface of a "
                  "shell around the one inside it): cage_1.obj ...")
      ->check(CLI::Range(1, 16));
  sub->add_option("--texture", args->texture,
                  "copy a tile into every prism above the input (geometric texture): knob, ring, "
                  "spike, or an OBJ whose vertices (a, b, t) lie in the unit prism; the shell's "
                  "surfaces the tile reaches are freed of self-intersections first; writes "
                  "textured.obj");
  auto* boolean_opt =
      sub->add_option("--boolean", args->boolean,
                      "build the shell on INPUT OP B (union, intersection, difference; CGAL "
                      "corefinement) and carry a field of each operand onto the result and its "
                      "coarse remeshing: result.vtu, remeshed.vtu")
          ->check(CLI::IsMember({"union", "intersection", "difference"}));
  auto* with_opt = sub->add_option("--with", args->with, "the second operand B of --boolean")
                       ->check(CLI::ExistingFile);
  boolean_opt->needs(with_opt);
  with_opt->needs(boolean_opt);
  sub->add_flag("--allow-self-intersections", args->allow_self_intersections,
                "the input may pass through itself: build a locally injective shell (thesis "
                "4.5), whose invariants hold against each prism's own sheet of the input; for "
                "remeshing and attribute transfer, not for volume meshing");
  add_global_options(*sub, args->global);
  add_command(sub, [args]() {
    auto progress = apply_global_options(args->global);
    Stopwatch total;
    std::unique_ptr<BooleanInput> boolean;
    if (!args->boolean.empty())
      boolean = std::make_unique<BooleanInput>(
          prepare_boolean(io::read_surface(args->input), args->with, args->boolean));
    const SurfaceMesh input = boolean ? boolean->result.mesh : io::read_surface(args->input);
    const SurfaceMesh tile = args->texture.empty() ? SurfaceMesh() : load_tile(args->texture);
    if (args->allow_self_intersections &&
        (args->remesh_section > 0 || args->displacement_level > 0 || args->cages > 0 ||
         !args->texture.empty() || !args->boolean.empty()))
      throw InputError(
          "--allow-self-intersections builds a locally injective shell; --remesh-section, "
          "--displacement-map, --cages, --texture and --boolean need an embedded one");
    int input_pairs = 0;
    if (args->allow_self_intersections) {
      std::vector<char> degenerate(std::size_t(input.num_faces()), 0);
      input_pairs =
          int(check::find_self_intersections(input.V, input.F, degenerate, true).pairs.size());
    }
    sh::ShellOptions options;
    options.local_sheets = args->allow_self_intersections;
    options.max_thickness_rel = args->thickness;
    options.threads = args->global.threads;
    sh::ShellStats stats;
    sh::BeveledShell beveled;
    try {
      beveled = sh::build_beveled_shell(input, options, stats, {}, progress->callback());
    } catch (const MeshingError& e) {
      // An input passing through itself has no embedded shell: say so, and what to do.
      if (args->allow_self_intersections) throw;
      std::vector<char> degenerate(std::size_t(input.num_faces()), 0);
      const auto pairs = check::find_self_intersections(input.V, input.F, degenerate, true).pairs;
      if (pairs.empty()) throw;
      throw InputError(std::string(e.what()) + ": the input has " + std::to_string(pairs.size()) +
                       " self-intersecting face pairs (faces " +
                       std::to_string(pairs.front().first) + " and " +
                       std::to_string(pairs.front().second) +
                       ", ...); --allow-self-intersections builds a locally injective shell");
    }
    sh::Shell shell = std::move(beveled.shell);
    const SurfaceMesh& surface = beveled.surface.mesh;  // the input, or its beveled refinement
    sh::SimplifyStats simplify;
    if (!args->no_simplify) {
      sh::SimplifyOptions so;
      so.threads = args->global.threads > 0 ? args->global.threads : 2;
      so.zoom = args->zoom * bbox_longest_edge(input.V);
      so.section_cos = args->pillar_cos;
      so.section_cos_relative = args->pillar_cos_relative;
      shell = sh::simplify_shell(shell, surface, so, simplify);
      stats.stage_seconds.emplace_back("simplify", simplify.seconds);
    }
    const sh::ShellVerification check = sh::verify_shell(shell, surface);
    // Attribute transfer on a locally injective shell (thesis Fig. 4.28): the smooth test field
    // carried input → middle surface → input by prism coordinates.
    nlohmann::ordered_json field_transfer = nullptr;
    if (args->allow_self_intersections) {
      const sh::ShellProjection onto_input(shell, surface);
      const Eigen::Vector3d center = 0.5 * (surface.V.colwise().minCoeff().transpose() +
                                            surface.V.colwise().maxCoeff().transpose());
      const Eigen::VectorXd values =
          sh::smooth_test_field(surface.V, center, 0.5 * bbox_longest_edge(surface.V));
      const sh::FieldRoundtrip t = sh::middle_field_roundtrip(onto_input, surface, values);
      field_transfer = {{"field", "sin(3x) cos(2y) + z^2, x = (p - bbox centre) / (bbox edge / 2)"},
                        {"field_range", values.maxCoeff() - values.minCoeff()},
                        {"failures", t.failures},
                        {"max_error", t.max_error},
                        {"mean_error", t.mean_error}};
    }
    StagedOutputDir out(args->output);
    SurfaceMesh remeshed;
    nlohmann::ordered_json section_remesh = nullptr;
    if (args->remesh_section > 0)
      section_remesh =
          run_section_remesh(shell, surface, args->remesh_section, args->global.threads, remeshed);
    nlohmann::ordered_json displacement = nullptr;
    if (args->displacement_level > 0) {
      displacement = run_displacement_map(shell, surface, args->displacement_level, out);
    }
    nlohmann::ordered_json boolean_block = nullptr;
    if (boolean) boolean_block = run_boolean_transfer(*boolean, shell, beveled.surface, out);
    nlohmann::ordered_json texture = nullptr;
    if (!args->texture.empty())
      texture = run_geometric_texture(shell, surface, tile, args->texture, out);
    sh::restore_input_ids(shell, beveled.surface);
    nlohmann::ordered_json cages = nullptr;
    if (args->cages > 0) {
      sh::NestedCageOptions co;
      co.layers = args->cages;
      co.shell = options;
      co.simplify = !args->no_simplify;
      co.zoom_rel = args->zoom;
      co.threads = options.threads > 0 ? options.threads : 2;
      cages = run_nested_cages(input, co, out);
    }

    write_wedges(out.path("shell.vtu"), shell);
    SurfaceMesh middle;
    middle.V = shell.mid;
    middle.F = shell.F;
    io::write_surface(out.path("middle.obj"), middle, io::SurfaceFormat::obj);
    if (remeshed.num_faces() > 0)
      io::write_surface(out.path("remeshed.obj"), remeshed, io::SurfaceFormat::obj);
    nlohmann::ordered_json stages = nlohmann::ordered_json::object();
    for (const auto& [name, s] : stats.stage_seconds) stages[name] = s;
    stages["verification"] = check.seconds;
    nlohmann::ordered_json report = {
        {"input", args->input},
        {"input_faces", stats.input_faces},
        {"input_vertices", stats.input_vertices},
        {"prisms", int(shell.F.rows())},
        {"simplified", !args->no_simplify},
        {"prisms_per_input_face", double(shell.F.rows()) / double(stats.input_faces)},
        {"simplify_collapses", simplify.collapses},
        {"simplify_flips", simplify.flips},
        {"simplify_pillar_rotations", simplify.rotations},
        {"simplify_zooms", simplify.zooms},
        {"simplify_pans", simplify.pans},
        {"simplify_splits", simplify.splits},
        {"simplify_collapses_refused",
         {{"shape", simplify.collapse_rejections.shape},
          {"distance", simplify.collapse_rejections.distance},
          {"positivity", simplify.collapse_rejections.positivity},
          {"intersection", simplify.collapse_rejections.intersection},
          {"section", simplify.collapse_rejections.section},
          {"coverage", simplify.collapse_rejections.coverage}}},
        {"singular_vertices", stats.singular_vertices},
        {"pinch_splits", stats.pinch_splits},
        {"beveling", beveled.stats.needed ? "applied" : "not needed"},
        {"beveled_faces", beveled.stats.beveled_faces},
        {"bevel_rounds", beveled.stats.rounds},
        {"non_section_prisms_before_beveling", beveled.stats.non_section_before},
        {"min_thickness_rel", stats.min_thickness_rel},
        {"median_thickness_rel", stats.median_thickness_rel},
        {"max_thickness_rel", stats.max_thickness_rel},
        {"simplified_thickness_rel",
         args->no_simplify
             ? nlohmann::ordered_json(nullptr)
             : nlohmann::ordered_json{{"min",
                                       simplify.min_half_thickness / bbox_longest_edge(input.V)},
                                      {"median",
                                       simplify.median_half_thickness / bbox_longest_edge(input.V)},
                                      {"max",
                                       simplify.max_half_thickness / bbox_longest_edge(input.V)}}},
        {"positive_verified", check.positive()},
        {"non_positive_prisms", check.non_positive_faces},
        {"intersection_free_verified", check.separated()},
        {"input_faces_intersecting_shell", check.intersecting_input_faces},
        {"is_section_verified", check.section()},
        {"non_section_prisms", check.non_section_faces},
        {"min_pillar_cos", check.min_pillar_cos},
        {"pillar_cos_bound", args->no_simplify ? 0.0 : args->pillar_cos},
        {"pillar_cos_relative", args->no_simplify ? 0.0 : args->pillar_cos_relative},
        {"pillar_cos_relaxed_pillars", simplify.relaxed_pillars},
        {"min_pillar_cos_bound", args->no_simplify ? 0.0 : simplify.min_section_bound},
        {"roundtrip_max_error_rel", check.roundtrip_max_error_rel},
        {"roundtrip_failures", check.roundtrip_failures},
        {"time_s", stages},
        {"peak_rss_mb", peak_rss_mb()}};
    if (args->remesh_section > 0) report["section_remesh"] = section_remesh;
    if (args->displacement_level > 0) report["displacement_map"] = displacement;
    if (args->cages > 0) report["nested_cages"] = cages;
    if (!args->texture.empty()) report["geometric_texture"] = texture;
    if (boolean) report["boolean"] = boolean_block;
    int middle_pairs = 0;
    if (args->allow_self_intersections) {
      // What "locally injective" leaves: the middle surface passes through itself where the input
      // does; each prism's invariants and the roundtrip were verified against its own sheet.
      std::vector<char> degenerate(std::size_t(shell.F.rows()), 0);
      middle_pairs =
          int(check::find_self_intersections(shell.mid, shell.F, degenerate, true).pairs.size());
      report["local_sheets"] = {{"locally_injective_only", true},
                                {"input_self_intersecting_pairs", input_pairs},
                                {"middle_self_intersecting_pairs", middle_pairs},
                                {"field_roundtrip", field_transfer}};
    }
    report["time_s"]["total"] = total.seconds();
    write_text_file_atomic(out.path("report.json"), report.dump(2) + "\n");
    out.commit();
    progress.reset();
    std::printf(
        "shell: %d prisms, %d singular, thickness median %.3g (min %.3g) of bbox; positive %s, "
        "intersection-free %s, section %s (%d prisms fail), roundtrip %.2g; %.2f s; %s\n",
        int(shell.F.rows()), stats.singular_vertices, stats.median_thickness_rel,
        stats.min_thickness_rel, check.positive() ? "yes" : "NO", check.separated() ? "yes" : "NO",
        check.section() ? "yes" : "NO", check.non_section_faces, check.roundtrip_max_error_rel,
        total.seconds(), out.final_path("report.json").string().c_str());
    if (args->allow_self_intersections)
      std::printf(
          "locally injective shell: the input has %d self-intersecting face pairs, the middle "
          "surface %d; every prism checked against its own sheet of the input; a smooth field "
          "input -> middle -> input: max error %.3g of range %.3g, %d unmapped\n",
          input_pairs, middle_pairs, field_transfer["max_error"].get<double>(),
          field_transfer["field_range"].get<double>(), field_transfer["failures"].get<int>());
    const bool remesh_ok =
        args->remesh_section <= 0 || section_remesh.value("is_section_verified", false);
    if (args->remesh_section > 0) {
      std::string line = section_remesh.value("error", "");
      if (line.empty())
        line = std::to_string(section_remesh["faces"].get<int>()) + " faces, section " +
               (remesh_ok ? "yes" : "NO") + ", field roundtrip max error " +
               std::to_string(section_remesh["field_roundtrip_max_error"].get<double>());
      std::printf("section remesh: %s\n", line.c_str());
    }
    bool displacement_ok = true;
    if (args->displacement_level > 0) {
      const auto& d = displacement;
      displacement_ok = displacement_map_ok(d);
      std::printf(
          "displacement map: level %d, %d samples, %d missed, every rebuilt vertex on its fiber "
          "and on the input: %s; rebuilt %d faces, %d self-intersecting pairs, Hausdorff %.3g of "
          "bbox (along normals: %d pairs, %.3g)\n",
          args->displacement_level, d["samples"].get<int>(), d["failures"].get<int>(),
          displacement_ok ? "yes" : "NO", d["rebuilt_faces"].get<int>(),
          d["rebuilt"]["self_intersecting_pairs"].get<int>(),
          d["rebuilt"]["hausdorff_rel"].get<double>(),
          d["along_normals"]["self_intersecting_pairs"].get<int>(),
          d["along_normals"]["hausdorff_rel"].get<double>());
      if (d["rebuilt"]["self_intersecting_pairs"].get<int>() > 0)
        log::warn("displacement map: the rebuilt surface has ",
                  d["rebuilt"]["self_intersecting_pairs"].get<int>(),
                  " self-intersecting face pairs: chords between samples across a fold of the "
                  "input; the samples themselves map one to one");
    }
    const bool cages_ok = args->cages <= 0 || nested_cages_ok(cages);
    if (args->cages > 0) {
      std::string sizes;
      for (const auto& l : cages["per_layer"])
        sizes += (sizes.empty() ? "" : ", ") + std::to_string(l["faces"].get<int>());
      std::printf(
          "nested cages: %d layers (%s faces), %d intersecting pairs between layers, "
          "each embedded, nested and mapped to the input: %s\n",
          args->cages, sizes.c_str(), cages["intersecting_pairs_between_layers"].get<int>(),
          cages_ok ? "yes" : "NO");
    }
    const bool texture_ok = args->texture.empty() || geometric_texture_ok(texture);
    if (!args->texture.empty())
      std::printf(
          "geometric texture: %d copies of %s (%d pinched prisms left out), %d faces, %d "
          "self-intersecting pairs (%d pairs with the input): %s\n",
          texture["copies"].get<int>(), args->texture.c_str(),
          texture["prisms_pinched_skipped"].get<int>(), texture["faces"].get<int>(),
          texture["self_intersecting_pairs"].get<int>(), texture["pairs_with_input"].get<int>(),
          texture_ok ? "ok" : "FAILED");
    const bool boolean_checks_ok = !boolean || boolean_ok(boolean_block);
    if (boolean)
      std::printf(
          "boolean %s: %d result faces (%d from %s, %d from %s), remeshed to %d; every "
          "coarse vertex mapped onto its operand: %s (field error %.2g)\n",
          args->boolean.c_str(), boolean_block["result_faces"].get<int>(),
          boolean_block["result_faces_from_a"].get<int>(), args->input.c_str(),
          boolean_block["result_faces_from_b"].get<int>(), args->with.c_str(),
          boolean_block["remeshed_faces"].get<int>(), boolean_checks_ok ? "yes" : "NO",
          boolean_block["field_max_error"].get<double>());
    std::fflush(stdout);
    return boolean_checks_ok && texture_ok && check.valid() && remesh_ok && displacement_ok &&
                   cages_ok
               ? 0
               : 3;
  });
}

}  // namespace curvefem::cli
