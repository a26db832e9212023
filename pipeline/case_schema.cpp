// The case schema table (case_schema.hpp). The documentation of each row is cases/README.md's
// key table, generated from here: edit a row here, then `curvefem schema --update cases/README.md`.
#include "pipeline/case_schema.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "meshing/core/error.hpp"

namespace curvefem::pipeline {
namespace {

using T = CaseKeyType;
constexpr double k_inf_hi = std::numeric_limits<double>::infinity();
constexpr double k_inf_lo = -k_inf_hi;

// clang-format off
// The rules between keys (case_schema.hpp, CaseKeyWhen).
const std::vector<std::string_view> k_elastic = {R"("linear_elasticity")", R"("neo_hookean")"};
const CaseKeyWhen k_curved = {.path = "meshing.method", .values = {R"("curved")"}, .error = R"(only for method "curved")"};
const CaseKeyWhen k_not_reused = {.path = "geometry.mesh_dir", .given = false, .error = R"(the mesh of geometry.mesh_dir is reused as saved (only method "curved" and validate may be given))"};
const CaseKeyWhen k_exterior = {.path = "meshing.exterior", .values = {"true"}, .error = R"(only with "exterior": true)"};
const CaseKeyWhen k_poisson = {.path = "physics.type", .values = {R"("poisson")"}, .error = "only for poisson"};
const CaseKeyWhen k_elasticity = {.path = "physics.type", .values = k_elastic, .error = "only for elasticity"};
const CaseKeyWhen k_both = {.path = "meshing.solve_on", .values = {R"("both")"}, .error = R"(only with meshing.solve_on "both")"};
const CaseKeyWhen k_one_load = {.path = "load_cases[]", .given = false, .error = "give it in each of load_cases (a case with load_cases has no top-level rhs, boundary_conditions, exact or exact_gradient)"};
CaseKeyWhen shape_is(std::string_view key, std::string_view value, std::string_view error) {
  return {.path = key, .values = {value}, .error = error};
}
const CaseKeyWhen k_sphere = shape_is("geometry.builtin_surface.shape", R"("sphere")", "only for the sphere");
const CaseKeyWhen k_torus = shape_is("geometry.builtin_surface.shape", R"("torus")", "only for the torus");
const CaseKeyWhen k_box = shape_is("geometry.builtin_surface.shape", R"("box")", "only for the box");
CaseKeyWhen absent(std::string_view key, std::string_view error) {
  return {.path = key, .given = false, .error = error};
}
CaseKeyWhen present(std::string_view key) { return {.path = key}; }
constexpr std::string_view k_dense_only = "only with a dense surface (geometry.surface or geometry.builtin_surface)";
constexpr std::string_view k_mesh_only = "only with a given tet mesh (geometry.mesh or builtin): on a dense surface the data are already read on it";
const std::vector<CaseKeyDefault> k_rhs_defaults = {{.when = {k_poisson}, .value = R"("0")"}, {.value = R"(["0", "0", "0"])"}};

const std::vector<CaseKeyRow> k_rows = {
    {.keys = {{.path = "geometry.surface", .type = T::path}},
     .type = R"md(path)md",
     .doc = R"md(a dense closed triangle surface (`.obj .off .stl .ply .msh`; OBJ groups / PLY face property / MSH physical tags become face tags). Must pass `curvefem check`, else exit 2 naming `/geometry/surface`)md"},
    {.keys = {{.path = "geometry.builtin_surface", .type = T::object}},
     .type = R"md(object)md",
     .doc = R"md(instead of `surface`, a generated surface: `{"shape": "sphere", "level": 3, "radius": 1}` (icosphere, 20·4^level faces), `{"shape": "torus", "R": 1, "r": 0.4, "nu": 48, "nv": 24}` (around z, 2·nu·nv faces), `{"shape": "box", "lo": [0,0,0], "hi": [1,1,1], "divisions": 4}` (12·n² faces, tags 1..6 = −x, +x, −y, +y, −z, +z); the defaults are the values shown)md"},
    {.keys = {{.path = "geometry.builtin_surface.shape", .type = T::string, .allowed = {"sphere", "torus", "box"}}},
     .type = R"md(`"sphere"` \| `"torus"` \| `"box"`)md",
     .doc = R"md(required: which surface; the other keys of `builtin_surface` are that shape's parameters)md"},
    {.keys = {{.path = "geometry.builtin_surface.level", .type = T::integer, .default_json = R"(3)", .range = CaseKeyRange{0, 7, false, false}, .when = {k_sphere}}},
     .type = R"md(0..7)md",
     .doc = R"md(sphere: icosphere subdivisions (20·4^level faces))md"},
    {.keys = {{.path = "geometry.builtin_surface.radius", .type = T::number, .default_json = R"(1)", .range = CaseKeyRange{0, k_inf_hi, true, false}, .when = {k_sphere}}},
     .type = R"md(number > 0)md",
     .doc = R"md(sphere: radius (centred at the origin))md"},
    {.keys = {{.path = "geometry.builtin_surface.R", .type = T::number, .default_json = R"(1)", .when = {k_torus}},
              {.path = "geometry.builtin_surface.r", .type = T::number, .default_json = R"(0.4)", .when = {k_torus}}},
     .type = R"md(numbers, 0 < r < R)md",
     .doc = R"md(torus: radius of the centre circle (around z) and of the tube)md"},
    {.keys = {{.path = "geometry.builtin_surface.nu", .type = T::integer, .default_json = R"(48)", .range = CaseKeyRange{3, 2000, false, false}, .when = {k_torus}},
              {.path = "geometry.builtin_surface.nv", .type = T::integer, .default_json = R"(24)", .range = CaseKeyRange{3, 2000, false, false}, .when = {k_torus}}},
     .type = R"md(3..2000)md",
     .doc = R"md(torus: segments around z and around the tube)md"},
    {.keys = {{.path = "geometry.builtin_surface.lo", .type = T::array, .default_json = R"([0, 0, 0])", .when = {k_box}},
              {.path = "geometry.builtin_surface.hi", .type = T::array, .default_json = R"([1, 1, 1])", .when = {k_box}}},
     .type = R"md(`[x, y, z]`)md",
     .doc = R"md(box: lower and upper corner (`hi` above `lo` in every coordinate))md"},
    {.keys = {{.path = "geometry.builtin_surface.divisions", .type = T::integer, .default_json = R"(4)", .range = CaseKeyRange{1, 500, false, false}, .when = {k_box}}},
     .type = R"md(1..500)md",
     .doc = R"md(box: n × n squares (two triangles each) per side)md"},
    {.keys = {{.path = "geometry.features", .type = T::any, .default_json = R"("auto")", .allowed = {"auto", "none"}, .when = {absent("geometry.mesh", k_dense_only), absent("geometry.builtin", k_dense_only), absent("geometry.mesh_dir", "the mesh of geometry.mesh_dir is reused as saved")}}},
     .type = R"md(string \| object)md",
     .doc = R"md(feature edges kept sharp by the curved mesher: `"auto"` (dihedral angle > 60°), `"none"`, `{"angle": DEG}`, `{"file": "edges.json"}` (a JSON list of input vertex-index pairs, or `{"edges": [...]}`); only with a surface. Detected feature curves (connected feature edges) whose bounding box is smaller than 2 ε are not kept; a file's edges all are)md"},
    {.keys = {{.path = "geometry.features.angle", .type = T::number, .range = CaseKeyRange{0, 180, true, true}}},
     .type = R"md(number in (0, 180))md",
     .doc = R"md(`{"angle": DEG}`: feature edges are those whose dihedral angle exceeds DEG)md"},
    {.keys = {{.path = "geometry.features.file", .type = T::path}},
     .type = R"md(path)md",
     .doc = R"md(`{"file": "edges.json"}`: the feature edges listed in that file)md"},
    {.keys = {{.path = "geometry.mesh", .type = T::path}},
     .type = R"md(path)md",
     .doc = R"md(a tetrahedral mesh of order 1–4: `.msh` (Gmsh 2.2/4.1; triangles' physical tags become boundary tags) or `.vtu` (method `given`))md"},
    {.keys = {{.path = "geometry.data_surface", .type = T::path, .when = {absent("geometry.surface", k_mesh_only), absent("geometry.builtin_surface", k_mesh_only), absent("geometry.mesh_dir", k_mesh_only)}}},
     .type = R"md(path)md",
     .doc = R"md(with `geometry.mesh` or `builtin`: a dense surface the mesh approximates, with the boundary data painted on it; every boundary value (Dirichlet, Neumann, Robin expressions) is read at the closest point of that surface instead of at the mesh's own point, as a user transferring data from a scan to an external coarse mesh would (issue 22's coarse-linear peer, benchmarks/run_coarse_linear.py). report.json `data_surface`. Selections still act on the mesh (tags, planes, boxes))md"},
    {.keys = {{.path = "geometry.mesh_dir", .type = T::path}},
     .type = R"md(path)md",
     .doc = R"md(instead of a surface or mesh: the output folder of `curvefem mesh` or of a curved `curvefem run` (mesh.msh + boundary_map.json with the shell fibers; a run of a built-in surface also saves input.msh). The curved mesh and φ are reused without meshing (method `curved`; only `meshing.method` and `meshing.validate` may be given, no `features`); the input is read from the path saved with the map and refused (exit 2, naming the file) if its bytes changed (FNV-1a checksum). The mesh is validated again against the ε it was made for (`meshing.validate`). Exterior meshes cannot be reused yet)md"},
    {.keys = {{.path = "geometry.builtin", .type = T::object}},
     .type = R"md(object)md",
     .doc = R"md(instead of `mesh`: `{"shape": "ball", "size": h, "order": k}` (unit ball, Gmsh) or `{"shape": "cube", "divisions": n, "order": k}` (unit cube, 6n³ tets; boundary tags 1..6 = x=0, x=1, y=0, y=1, z=0, z=1))md"},
    {.keys = {{.path = "geometry.builtin.shape", .type = T::string, .allowed = {"ball", "cube"}}},
     .type = R"md(`"ball"` \| `"cube"`)md",
     .doc = R"md(required: the unit ball or the unit cube)md"},
    {.keys = {{.path = "geometry.builtin.size", .type = T::number, .default_json = R"(0.3)", .range = CaseKeyRange{0.02, 2, false, false}, .when = {shape_is("geometry.builtin.shape", R"("ball")", "only for the ball")}}},
     .type = R"md(number in [0.02, 2])md",
     .doc = R"md(ball: target edge length h)md"},
    {.keys = {{.path = "geometry.builtin.divisions", .type = T::integer, .default_json = R"(4)", .range = CaseKeyRange{1, 100, false, false}, .when = {shape_is("geometry.builtin.shape", R"("cube")", "only for the cube")}}},
     .type = R"md(1..100)md",
     .doc = R"md(cube: n, n³ cubes of 6 tets)md"},
    {.keys = {{.path = "geometry.builtin.order", .type = T::integer, .default_json = R"(1)", .range = CaseKeyRange{1, 4, false, false}}},
     .type = R"md(1..4)md",
     .doc = R"md(geometric order k of the built-in mesh)md"},
    {.keys = {{.path = "meshing.method", .type = T::string, .allowed = {"curved", "dense", "given"}, .defaults = {{.when = {present("geometry.surface")}, .value = R"("curved")"}, {.when = {present("geometry.builtin_surface")}, .value = R"("curved")"}, {.when = {present("geometry.mesh_dir")}, .value = R"("curved")"}, {.value = R"("given")"}}}},
     .type = R"md(string)md",
     .default_text = R"md(`"curved"` with a surface, `"given"` with a mesh)md",
     .doc = R"md(`curved`: coarse curved mesh of order k with the bijective boundary map φ (DESIGN.md §1); `dense`: the input itself tetrahedralized (boundary unchanged, order 1, φ = identity) — the classical baseline; `given`: the tet mesh of `geometry.mesh`/`builtin`)md"},
    {.keys = {{.path = "meshing.order", .type = T::integer, .default_json = R"(3)", .range = CaseKeyRange{1, 4, false, false}, .when = {k_not_reused, k_curved}}},
     .type = R"md(1..4)md",
     .doc = R"md(curved: geometric order k)md"},
    {.keys = {{.path = "meshing.eps", .type = T::number_list, .default_json = R"(0.01)", .range = CaseKeyRange{0, 0.5, true, false}, .when = {k_not_reused, k_curved}}},
     .type = R"md(number or list)md",
     .doc = R"md(curved: distance bound ε, relative to the longest bounding-box edge of the input. A list of distinct bounds (e.g. `[0.04, 0.02, 0.01]`, issue 22) meshes every level from one shell and one coarsening (`curvefem mesh --eps-levels`) and solves them coarse to fine; report.json `eps_levels` has a row per level solved (ε, coarse faces, DOFs, degree, estimate, `change_on_input_rms_rel` / `_max_rel`: u_h on the dense input's vertices against the coarser level's, `change_gradient_norm_rel`, and the exact error when known). With `discretization.target_error` each level runs adaptive p and the run stops at the first level whose RMS and gradient changes and estimate are within the target (`reached`, `reason`). The outputs are the last level solved. Measured (`Run.EpsLevels…`, sphere, k = p = 3, mixed Dirichlet/Neumann): ε 4% / 2% / 1%: 48 / 62 / 130 faces, relative L2 error 3.0e-3 / 1.9e-3 / 6.1e-4, change on the input 8.8e-3 / 6.2e-3)md"},
    {.keys = {{.path = "meshing.eps_field", .type = T::expression, .when = {k_not_reused, k_curved}}},
     .type = R"md(string)md",
     .doc = R"md(curved: a spatially varying distance bound, an expression of x, y, z relative to the bbox edge like `eps`; the bound at an input vertex x is min(`eps`, field(x)), inside an input face the linear interpolation of its corners' (meshing/curved/README.md, "Spatially varying ε"). The coarsening and the curving honour it, the factors are saved in `boundary_map.json` and the validator checks every vertex against its own bound (`validation.max_distance_over_local_eps` ≤ 1). A value that is not positive at some vertex is an input error naming it. E.g. `"z > 0 ? 0.004 : 1"` with `eps` 0.02: 182 coarse faces on a sphere instead of 66)md"},
    {.keys = {{.path = "meshing.eps_by_tag", .type = T::object, .range = CaseKeyRange{0, 0.5, true, false}, .when = {k_not_reused, k_curved}}},
     .type = R"md(object)md",
     .doc = R"md(curved: distance bounds per face tag of the input, `{"cap": 0.002, "3": 0.01}` (keys a tag value or a tag name: OBJ group, MSH physical name; values relative like `eps`, in (0, 0.5]); a face's bound is its tag's entry, or `eps` for tags not listed; a vertex takes the smallest bound of its faces and of `eps_field`. Validated per vertex like `eps_field`. A key that names no tag of the input is an input error listing its tags)md"},
    {.keys = {{.path = "meshing.thickness", .type = T::number, .default_json = R"(0.02)", .range = CaseKeyRange{0, 0.5, true, false}, .when = {k_not_reused, k_curved}}},
     .type = R"md(number)md",
     .doc = R"md(curved: cap on the shell's half-thickness (relative))md"},
    {.keys = {{.path = "meshing.feature_chains", .type = T::boolean, .default_json = R"(true)", .when = {k_not_reused, k_curved}}},
     .type = R"md(boolean)md",
     .doc = R"md(curved: the coarsening runs along feature chains (their vertices snapped onto the coarse feature edges in a reference copy of the input; meshing/shell/README.md) instead of keeping every feature vertex; ignored, with a warning, together with `eps_samples`)md"},
    {.keys = {{.path = "meshing.curved_coarsening", .type = T::boolean, .default_json = R"(true)", .when = {k_not_reused, k_curved}}},
     .type = R"md(boolean)md",
     .doc = R"md(curved, order ≥ 2: the coarsening lets an input vertex lie up to 3 ε from the *linear* middle surface when its face's fully curved patch is within ε of it (meshing/curved/README.md, "Curved-aware coarsening"); false: ε on the linear surface (`curvefem mesh --linear-coarsening`))md"},
    {.keys = {{.path = "meshing.eps_samples", .type = T::integer, .default_json = R"(0)", .range = CaseKeyRange{0, 16, false, false}, .when = {k_not_reused, k_curved}}},
     .type = R"md(integer 0 or 2..16)md",
     .doc = R"md(curved: ε is enforced at every input vertex and, with L ≥ 2, also at the non-corner points of the degree-L barycentric lattice of every input triangle (2: edge midpoints; 3: two points per edge and the centroid); they are written to `boundary_map.json` and re-checked by the validator (`distance_points_max_distance_rel` in report.json). On a 768-face torus at ε = 0.6%, the images of these points reached 1.04% without them)md"},
    {.keys = {{.path = "meshing.thickness_per_edge", .type = T::number, .default_json = R"(1)", .range = CaseKeyRange{0, 100, false, false}, .range_note = " (0: off)", .when = {k_not_reused, k_curved}}},
     .type = R"md(number ≥ 0)md",
     .doc = R"md(curved: also cap each vertex's initial half-thickness at this multiple of its mean input edge length (0: off); coarsening grows the shell again where the coarse faces allow. A shell much thicker than the input's triangles makes coarsening stall on dense inputs (refined elephant, ε = 2%: 9,258 coarse faces with 0, 662 with 1))md"},
    {.keys = {{.path = "meshing.merge_short_edges", .type = T::number, .default_json = R"(0)", .range = CaseKeyRange{0, 0.5, false, false}, .range_note = " (0: off)", .when = {k_not_reused, absent("geometry.mesh", k_dense_only), absent("geometry.builtin", k_dense_only)}}},
     .type = R"md(number in [0, 0.5])md",
     .doc = R"md(curved \| dense: mesh the input with its edges shorter than this × the longest bbox edge merged into one of their ends first (`curvefem check --merge-short-edges`, meshing/check/README.md "Repair"; 0: off). Removes the floor a kept needle or fold puts under the worst tet (CGAL's femur.off at K = 3: max curved MIPS 2.95e4 → 1.34e3 with 5e-4); φ then maps to the repaired surface, which `surface.vtu` shows and the run folder saves as `input.msh`; `surface_input.vtu` has the same fields on the input as read (a merged-away vertex takes its vertex's values); report.json `meshing.input_repair`. The run logs the length that would help where the worst tet is on such a feature)md"},
    {.keys = {{.path = "meshing.validate", .type = T::boolean, .default_json = R"(true)", .when = {k_curved}}},
     .type = R"md(bool)md",
     .doc = R"md(curved: independent validation of the mesh (certified Jacobians, embedded boundary, distance) reported under `meshing.validation`; a failed validation still writes the results and exits 3)md"},
    {.keys = {{.path = "meshing.deterministic", .type = T::boolean, .default_json = R"(true)", .when = {k_not_reused, k_curved}}},
     .type = R"md(bool)md",
     .doc = R"md(curved: coarsen on one thread so the same case gives a bit-identical mesh; `false` coarsens on `--threads` workers (about 1.6× faster on two cores, the mesh then varies between runs))md"},
    {.keys = {{.path = "meshing.exterior", .type = T::boolean, .default_json = R"(false)", .when = {k_not_reused, {.path = "meshing.method", .values = {R"("curved")", R"("dense")"}, .error = "takes a dense surface (method curved or dense)"}}}},
     .type = R"md(bool)md",
     .doc = R"md(curved, dense: solve *outside* the input surface, out to its bounding box padded by `meshing.padding` (the inside is not part of the domain); see "Exterior problems" below)md"},
    {.keys = {{.path = "meshing.solve_on", .type = T::string, .default_json = R"("outside")", .allowed = {"outside", "both"}, .when = {k_exterior}}},
     .type = R"md(`"outside"` \| `"both"`)md",
     .doc = R"md(with `exterior`: the domain is the outside of the surface, or the whole box (two regions; the surface is an interface and the outer box the only boundary, so every selection must use `outer_box`))md"},
    {.keys = {{.path = "meshing.padding", .type = T::number, .default_json = R"(0.25)", .range = CaseKeyRange{0, 10, true, false}, .range_note = " (relative to the longest bbox edge)", .when = {k_exterior}}},
     .type = R"md(number in (0, 10])md",
     .doc = R"md(with `exterior`: the box is the input's bounding box padded by this × its longest edge (curved: pushed out where the outer slab surface comes closer than a quarter of the padding))md"},
    {.keys = {{.path = "physics.type", .type = T::string, .default_json = R"("poisson")", .allowed = {"poisson", "linear_elasticity", "neo_hookean"}}},
     .type = R"md(string)md",
     .doc = R"md(`poisson` \| `linear_elasticity` \| `neo_hookean`)md"},
    {.keys = {{.path = "physics.kappa", .type = T::expression, .default_json = R"("1")", .when = {k_poisson}}},
     .type = R"md(expression)md",
     .doc = R"md(Poisson: −∇·(κ∇u) = f)md"},
    {.keys = {{.path = "physics.kappa_inside", .type = T::expression, .when = {k_poisson, k_both}, .default_from = "physics.kappa"}},
     .type = R"md(expression)md",
     .default_text = R"md(`kappa`)md",
     .doc = R"md(Poisson with `solve_on` both: κ inside the surface (`kappa` is then the outside's))md"},
    {.keys = {{.path = "physics.E", .type = T::number, .default_json = R"(1)", .range = CaseKeyRange{0, k_inf_hi, true, false}, .when = {k_elasticity}},
              {.path = "physics.nu", .type = T::number, .default_json = R"(0.3)", .range = CaseKeyRange{-1, 0.5, true, true}, .when = {k_elasticity}}},
     .type = R"md(numbers)md",
     .doc = R"md(elasticity: Young's modulus, Poisson ratio (ν in (−1, 0.5)))md"},
    {.keys = {{.path = "physics.E_inside", .type = T::number, .range = CaseKeyRange{0, k_inf_hi, true, false}, .when = {k_elasticity, k_both}, .default_from = "physics.E"},
              {.path = "physics.nu_inside", .type = T::number, .range = CaseKeyRange{-1, 0.5, true, true}, .when = {k_elasticity, k_both}, .default_from = "physics.nu"}},
     .type = R"md(numbers)md",
     .default_text = R"md(`E`, `nu`)md",
     .doc = R"md(elasticity with `solve_on` both: the inside's material (`E`, `nu` are then the outside's))md"},
    {.keys = {{.path = "physics.load_steps", .type = T::integer, .default_json = R"(1)", .range = CaseKeyRange{1, 10000, false, false}, .when = {{.path = "physics.type", .values = {R"("neo_hookean")"}, .error = "only for neo_hookean"}}}},
     .type = R"md(integer)md",
     .doc = R"md(Neo-Hookean: loads and prescribed displacements applied in this many steps)md"},
    {.keys = {{.path = "discretization.degree", .type = T::integer, .default_json = R"(1)", .range = CaseKeyRange{1, 4, false, false}}},
     .type = R"md(1..4)md",
     .doc = R"md(Lagrange degree p (independent of the mesh order k))md"},
    {.keys = {{.path = "discretization.target_error", .type = T::number, .range = CaseKeyRange{0, 1, true, true}, .range_note = ": the relative H1-semi error estimate to reach"}},
     .type = R"md(number in (0, 1))md",
     .doc = R"md(adaptive p (issue 22): the degree is raised from `degree` up to 4 on the same mesh until the relative gradient-recovery estimate η / ‖∇u_h‖ (`error_estimate.relative`, fem/README.md) of every load case is at most this; report.json `adaptive` lists each iteration (degree, DOFs, estimate, seconds) and says whether the target was reached; the outputs are the last degree's. The estimate does not see the geometric error of ε: on a sphere at ε = 1%, k = 3, it falls 0.239 / 0.020 / 0.0057 / 0.0042 for p = 1..4 while the true error stops near 7e-3 (`Run.AdaptivePRaises…`))md"},
    {.keys = {{.path = "discretization.quadrature", .type = T::any, .default_json = R"("default")", .range = CaseKeyRange{0, 30, false, false}}},
     .type = R"md(0..30 \| `"default"`)md",
     .doc = R"md(quadrature degree of the stiffness; default 2p + 2(k−1))md"},
    {.keys = {{.path = "discretization.partial_dirichlet", .type = T::string, .allowed = {"nitsche", "nodal"}, .defaults = {{.when = {k_poisson}, .value = R"("nitsche")"}, {.value = R"("nodal")"}}}},
     .type = R"md(`"nitsche"` \| `"nodal"`)md",
     .default_text = R"md(Poisson `"nitsche"`; elasticity `"nodal"` (Neo-Hookean's only mode))md",
     .doc = R"md(a boundary face of the mesh that a Dirichlet selection covers only in part (see "Boundary data on the dense input"): imposed weakly by Nitsche's method on the face quadrature points the selection covers, or by fixing the DOFs it covers (the others stay free, and the flux is missing from the weak form on the face's Dirichlet part))md"},
    {.keys = {{.path = "discretization.boundary_values_at", .type = T::string, .allowed = {"input", "mesh", "shifted"}, .defaults = {{.when = {{.path = "physics.type", .values = {R"("neo_hookean")"}}}, .value = R"("input")"}, {.value = R"("shifted")"}}}},
     .type = R"md(`"input"` \| `"mesh"` \| `"shifted"`)md",
     .default_text = R"md(`"shifted"`; Neo-Hookean `"input"`)md",
     .doc = R"md(methods `curved` and `dense`: where a boundary condition's `value` (and Robin's `h`) is evaluated. `input`: at φ⁻¹(x) on the dense input, the data painted there (see "Boundary data on the dense input"); on a curved mesh the boundary lies up to ε from the input, so the data carry an error up to ε·|∇u| that no degree removes. `mesh`: at the mesh's own point x, for values that are fields in space (an analytic temperature, displacement or pressure), consistent with the domain solved on. `shifted` (curved; Poisson and linear elasticity): painted data read on the input as with `input`, the Dirichlet values then continued from φ⁻¹(x) to x with the recovered gradient of the solution, g(φ⁻¹(x)) + G(x)·(x − φ⁻¹(x)) (the shifted boundary method's Taylor condition), by two re-solves with the same stiffness; report.json `physics_details.boundary_shift`. Selections are judged on the input either way. Measured on six dev meshes (5.9k–52k faces), k = 3, ε = 1%, Poisson (benchmarks/results/accuracy.md), relative L2 error against `input`: `shifted` 2.6–5.0 times smaller at P3 (1.0–4.7 at P2, 2.7–4.7 at P4), `mesh` 2.6–46 at P3, 17–406 at P4; linear elasticity on five of them, the faces the data's plane cuts imposed by Nitsche (benchmarks/results/accuracy_elasticity.md): `shifted` 1.8–4.8 at P2–P4 except on fandisk (0.95–1.10: its transport error is in the tractions, which the shift does not correct), `mesh` 1.5–350. Dense meshes: the same (φ = identity))md"},
    {.keys = {{.path = "discretization.geometry", .type = T::string, .default_json = R"("iso")", .allowed = {"iso", "mesh"}}},
     .type = R"md(`"iso"` \| `"mesh"`)md",
     .doc = R"md(a mesh of order k above the degree p: `iso` solves on the degree-p interpolant of every tet's map (meshing/core/geometry_degree.hpp; the corners and the DOF points stay where they are, tets whose interpolant is not certified positive keep their map: `solve_geometry` in report.json, volume.vtu shows the solved geometry); `mesh` solves on the order-k maps (super-parametric). On a degree-k > p map the degree-p space misses the linear fields, rigid rotations included: P2 elasticity on the curved elephant at k = 3 came out at 0.39 of the reference displacement (16% RMS error) with `mesh`, 2.3% with `iso` (k = 2: 1.3%; issue 20, meshing/curved/README.md))md"},
    {.keys = {{.path = "rhs", .type = T::expression, .when = {k_one_load}, .defaults = k_rhs_defaults}},
     .type = R"md(expression(s))md",
     .default_text = R"md(0)md",
     .doc = R"md(Poisson: f; elasticity: body force, an array of three (evaluated in the volume))md"},
    {.keys = {{.path = "boundary_conditions[]", .type = T::array, .default_json = R"([])", .when = {k_one_load}}},
     .type = R"md(array)md",
     .doc = R"md(`{"type": "dirichlet" \| "neumann", "select": S, "value": V}`; Neumann is the flux κ∂u/∂n (Poisson) or the traction σn (elasticity); vector Dirichlet takes `"components": [bool, bool, bool]` (default all true); Poisson also takes `{"type": "robin", "select": S, "h": H, "u_inf": U}`, the convective condition −κ∂u/∂n = h (u − u∞) (h > 0; H and U are expressions, with `nx`, `ny`, `nz` allowed as for Neumann values))md"},
    {.keys = {{.path = "boundary_conditions[].type", .type = T::string, .allowed = {"dirichlet", "neumann", "robin"}}},
     .type = R"md(`"dirichlet"` \| `"neumann"` \| `"robin"`)md",
     .doc = R"md(required: the kind of condition (robin: Poisson only))md"},
    {.keys = {{.path = "boundary_conditions[].value", .type = T::expression, .when = {{.path = "boundary_conditions[].type", .values = {R"("dirichlet")", R"("neumann")"}, .error = "a robin condition takes h and u_inf, not value"}}}},
     .type = R"md(expression(s))md",
     .doc = R"md(required for dirichlet and neumann: the prescribed value, flux or traction (an array of three for vector problems))md"},
    {.keys = {{.path = "boundary_conditions[].components", .type = T::array, .default_json = R"([true, true, true])", .when = {{.path = "boundary_conditions[].type", .values = {R"("dirichlet")"}, .error = "only for vector Dirichlet conditions"}, {.path = "physics.type", .values = k_elastic, .error = "only for vector Dirichlet conditions"}}}},
     .type = R"md(`[bool, bool, bool]`)md",
     .doc = R"md(vector Dirichlet: which components are imposed)md"},
    {.keys = {{.path = "boundary_conditions[].h", .type = T::expression, .when = {{.path = "boundary_conditions[].type", .values = {R"("robin")"}, .error = "only for robin conditions"}}},
              {.path = "boundary_conditions[].u_inf", .type = T::expression, .when = {{.path = "boundary_conditions[].type", .values = {R"("robin")"}, .error = "only for robin conditions"}}}},
     .type = R"md(expressions)md",
     .doc = R"md(robin only (and required there): h and u∞ of −κ∂u/∂n = h (u − u∞))md"},
    {.keys = {{.path = "boundary_conditions[].select", .type = T::selection}},
     .type = R"md(object)md",
     .doc = R"md(exactly one of the kinds below. A selection that selects nothing is an error (exit 2))md"},
    {.keys = {{.path = "boundary_conditions[].select.all", .type = T::boolean}},
     .type = R"md(`true`)md",
     .doc = R"md(the whole boundary)md"},
    {.keys = {{.path = "boundary_conditions[].select.tag", .type = T::integer, .range = CaseKeyRange{0, 1073741824, false, false}}},
     .type = R"md(integer)md",
     .doc = R"md(surface methods: input faces with this tag; `given`: boundary tag of the mesh)md"},
    {.keys = {{.path = "boundary_conditions[].select.box", .type = T::array}},
     .type = R"md(`[[x0,y0,z0],[x1,y1,z1]]`)md",
     .doc = R"md(points with lo ≤ x ≤ hi (closed))md"},
    {.keys = {{.path = "boundary_conditions[].select.plane", .type = T::object}},
     .type = R"md(`{"point": [..], "normal": [..]}`)md",
     .doc = R"md(points on the side the normal points to, (x − point)·normal ≥ 0)md"},
    {.keys = {{.path = "boundary_conditions[].select.plane.point", .type = T::array},
              {.path = "boundary_conditions[].select.plane.normal", .type = T::array}},
     .type = R"md(`[x, y, z]`)md",
     .doc = R"md(required: a point of the plane and a non-zero normal towards the selected side)md"},
    {.keys = {{.path = "boundary_conditions[].select.normal", .type = T::object}},
     .type = R"md(`{"direction": [..], "angle": DEG}`)md",
     .default_text = R"md(angle 0)md",
     .doc = R"md(input faces whose outward normal is within DEG degrees of the direction (surface methods only))md"},
    {.keys = {{.path = "boundary_conditions[].select.normal.direction", .type = T::array}},
     .type = R"md(`[dx, dy, dz]`)md",
     .doc = R"md(required: a non-zero direction)md"},
    {.keys = {{.path = "boundary_conditions[].select.normal.angle", .type = T::number, .default_json = R"(0)", .range = CaseKeyRange{0, 180, false, false}}},
     .type = R"md(number in [0, 180])md",
     .doc = R"md(the largest angle in degrees between a selected face's normal and the direction)md"},
    {.keys = {{.path = "boundary_conditions[].select.and", .type = T::array},
              {.path = "boundary_conditions[].select.or", .type = T::array}},
     .type = R"md(array of selections)md",
     .doc = R"md(all / any of them (surface methods only))md"},
    {.keys = {{.path = "boundary_conditions[].select.not", .type = T::selection}},
     .type = R"md(selection)md",
     .doc = R"md(the complement (surface methods only))md"},
    {.keys = {{.path = "boundary_conditions[].select.outer_box", .type = T::string, .allowed = {"all", "xmin", "xmax", "ymin", "ymax", "zmin", "zmax"}}},
     .type = R"md(`"all"` \| `"xmin"` \| `"xmax"` \| `"ymin"` \| `"ymax"` \| `"zmin"` \| `"zmax"`)md",
     .doc = R"md(`meshing.exterior` only: the outer box, or one of its sides)md"},
    {.keys = {{.path = "exact", .type = T::expression, .when = {k_one_load}}},
     .type = R"md(expression(s))md",
     .doc = R"md(exact solution: L2 and H1 errors in report.json, `exact` and `error` fields in volume.vtu and surface.vtu)md"},
    {.keys = {{.path = "exact_gradient", .type = T::expression, .when = {k_one_load, {.path = "exact", .error = R"(needs "exact")"}}}},
     .type = R"md(expressions)md",
     .doc = R"md(derivatives of `exact` for the H1 error (see below); otherwise finite differences)md"},
    {.keys = {{.path = "load_cases[]", .type = T::array}},
     .type = R"md(array)md",
     .doc = R"md(instead of the top-level `rhs`, `boundary_conditions`, `exact`, `exact_gradient`: `[{"name": N, "rhs": ..., "boundary_conditions": [...], "exact": ..., "exact_gradient": ...}, ...]` (names of letters, digits, `_`, `-`; distinct), each solved on the one mesh and function space of the run (mesh once; cases with the same Dirichlet part share one CHOLMOD factorization with the direct solver: `factorizations`, `factorization_reuses` in report.json). report.json gets `load_cases[]` (errors, surface errors, solver, physics details per case); volume.vtu / surface.vtu hold every case's fields with a `_N` suffix; `volume_N.vtu` / `surface_N.vtu` are result.pvd's time steps, one per case)md"},
    {.keys = {{.path = "load_cases[].name", .type = T::string}},
     .type = R"md(string)md",
     .doc = R"md(required: letters, digits, `_`, `-`; distinct)md"},
    {.keys = {{.path = "load_cases[].rhs", .type = T::expression, .defaults = k_rhs_defaults},
              {.path = "load_cases[].exact", .type = T::expression},
              {.path = "load_cases[].exact_gradient", .type = T::expression, .when = {{.path = "load_cases[].exact", .error = R"(needs "exact")"}}}},
     .type = R"md(as at the top level)md",
     .default_text = R"md(as at the top level)md",
     .doc = R"md(the load case's `rhs`, `exact` and `exact_gradient`)md"},
    {.keys = {{.path = "load_cases[].boundary_conditions[]", .type = T::array, .default_json = R"([])"}},
     .type = R"md(array)md",
     .doc = R"md(the load case's boundary conditions, with the keys of the top-level `boundary_conditions[]`)md"},
    {.keys = {{.path = "solver.type", .type = T::string, .default_json = R"("auto")", .allowed = {"auto", "direct", "cg"}}},
     .type = R"md(string)md",
     .doc = R"md(`direct` (CHOLMOD supernodal) \| `cg` (PETSc CG + GAMG) \| `auto`: direct up to 25k unknowns (Poisson, elasticity P1), 40k (elasticity P2), 120k (elasticity P3–P4), cg above — the crossovers measured in benchmarks/results/solver_crossover.md)md"},
    {.keys = {{.path = "solver.preconditioner", .type = T::string, .default_json = R"("gamg")", .allowed = {"gamg", "hypre", "ml"}}},
     .type = R"md(string)md",
     .doc = R"md(`cg`: `gamg` (PETSc smoothed aggregation; takes the near-nullspace) \| `hypre` (hypre BoomerAMG, classical AMG; no near-nullspace) \| `ml` (Trilinos ML smoothed aggregation; takes the near-nullspace). benchmarks/results/solver_crossover.md compares them)md"},
    {.keys = {{.path = "solver.parallel_ptap", .type = T::string, .default_json = R"("auto")", .allowed = {"auto", "allatonce", "scalable"}}},
     .type = R"md(string)md",
     .doc = R"md(`cg` + `gamg` under `mpirun -n N`, N > 1: PETSc's algorithm for the parallel Galerkin products of GAMG's set-up (`-matptap_via`). `allatonce` needs far less memory per rank with elasticity's rigid-body modes (P2, 1.07M unknowns on 2 ranks: 1.54 GB against 2.66 GB per rank) at 2.9× the set-up time (197 s against 67 s); `scalable` is PETSc's own default; `auto`: `allatonce` with a near-nullspace of several modes (elasticity), `scalable` otherwise. benchmarks/results/mpi.md; ignored on one process)md"},
    {.keys = {{.path = "solver.rank_balance", .type = T::string, .default_json = R"("memory")", .allowed = {"memory", "rows"}}},
     .type = R"md(string)md",
     .doc = R"md(under `mpirun -n N`, N > 1: how the rows are split between the ranks. `memory`: rank 0, which also holds the mesh, the space and the run's other data, gets fewer rows, so that the ranks' peak memory is about even (the shares follow from each rank's heap in use when the solve starts and the solver's estimated memory; report.json `solver.rank_shares`, `solver.rank_heap_mb`); `rows`: equal rows per rank. benchmarks/results/mpi.md; ignored on one process)md"},
    {.keys = {{.path = "solver.rtol", .type = T::number, .default_json = R"(1e-10)", .range = CaseKeyRange{0, k_inf_hi, true, false}},
              {.path = "solver.max_iterations", .type = T::integer, .default_json = R"(5000)", .range = CaseKeyRange{1, 1000000, false, false}}},
     .type = R"md(number, integer)md",
     .doc = R"md(for `cg`)md"},
    {.keys = {{.path = "solver.near_nullspace", .type = T::boolean, .default_json = R"(true)"}},
     .type = R"md(boolean)md",
     .doc = R"md(`cg`, elasticity: GAMG gets the rigid-body modes of the DOF points as its near-nullspace (`false`: GAMG's default, translations only; to compare — fem/README.md has the iteration counts))md"},
    {.keys = {{.path = "output.dir", .type = T::path, .default_json = R"("out")"}},
     .type = R"md(path)md",
     .doc = R"md(results: `volume.vtu`, `surface.vtu`, `result.pvd`, `resolved_case.json`, `report.json` (last))md"},
    {.keys = {{.path = "output.surface_values", .type = T::string, .default_json = R"("extended")", .allowed = {"extended", "image"}}},
     .type = R"md(`"extended"` \| `"image"`)md",
     .doc = R"md(curved: the solution on an input vertex v (surface.vtu, the `surface_*` errors, the ε levels' changes on the input) is u_h at its image φ(v) on the mesh's boundary, up to ε away from v. `extended`: u_h(φ(v)) + ∇u_h(φ(v))·(v − φ(v)), the discrete solution continued to first order along the offset (mapping/surface_transfer.hpp), except where a Dirichlet condition holds v (per component): there the value is the data g(v), as on a node of a dense mesh; `image`: u_h(φ(v)) everywhere. report.json `surface_values`. Dense meshes: the same (φ(v) = v). Measured in benchmarks/results/accuracy.md)md"},
};
// The study file of `curvefem study` (cases/README.md, Studies; parsed by study_file.cpp).
const std::vector<CaseKeyRow> k_study_rows = {
    {.keys = {{.path = "base", .type = T::any}},
     .type = R"md(path \| object)md",
     .doc = R"md(the case: a case file (relative to the study file) or an inline case object (its relative paths then resolve against the study file's folder). It must be a valid case by itself and have `exact`; its `output` is ignored)md"},
    {.keys = {{.path = "sweep", .type = T::object}},
     .type = R"md(object)md",
     .doc = R"md(JSON pointer ([RFC 6901](https://www.rfc-editor.org/rfc/rfc6901)) into the case → non-empty array of distinct numbers, strings or booleans. Each value is written at its pointer (missing objects are created). The runs are the cartesian product, first key outermost. E.g. `/discretization/degree` (p), `/meshing/order` (k), `/meshing/eps` (ε), `/geometry/builtin_surface/level`, `/geometry/builtin/size`, `/geometry/builtin/divisions`, `/geometry/builtin/order`, `/meshing/method`. Pointers under `/output` are refused)md"},
    {.keys = {{.path = "refine", .type = T::string}},
     .type = R"md(string)md",
     .default_text = R"md(the last sweep key)md",
     .doc = R"md(the key that varies along each curve (its pointer or its name); every combination of the other keys is one curve (a *series*))md"},
    {.keys = {{.path = "x", .type = T::string, .default_json = R"("dofs")", .allowed = {"dofs", "tets"}}},
     .type = R"md(`"dofs"` \| `"tets"`)md",
     .doc = R"md(horizontal axis of `study.png` and the rate shown in its legend)md"},
    {.keys = {{.path = "description", .type = T::string}},
     .type = R"md(string)md",
     .doc = R"md(free text, echoed into `study.json`)md"},
    {.keys = {{.path = "output", .type = T::object}},
     .type = R"md(object)md",
     .doc = R"md(`{"dir": ...}`)md"},
    {.keys = {{.path = "output.dir", .type = T::path}},
     .type = R"md(path)md",
     .default_text = R"md(`"out/<study file name>"`)md",
     .doc = R"md(relative to the study file; `-o DIR` overrides)md"},
};
// clang-format on

std::string number_text(double v) {
  std::ostringstream s;
  s.precision(15);
  s << v;
  return s.str();
}

std::string default_column(const CaseKeyRow& row) {
  if (!row.default_text.empty()) return std::string(row.default_text);
  std::string out;
  bool any = false;
  for (const CaseKey& k : row.keys) {
    if (!out.empty()) out += ", ";
    if (k.default_json.empty()) {
      out += "—";
      continue;
    }
    any = true;
    const bool is_string = k.default_json.front() == '"';
    out += is_string ? "`" + std::string(k.default_json) + "`" : std::string(k.default_json);
  }
  return any ? out : "—";
}

/// `path` without the `[]` of its components.
std::string plain(std::string_view path) {
  std::string out;
  for (std::size_t i = 0; i < path.size(); ++i)
    if (!(path[i] == '[' && i + 1 < path.size() && path[i + 1] == ']')) {
      out += path[i];
    } else {
      ++i;
    }
  return out;
}

}  // namespace

std::string CaseKeyRange::text(bool integer) const {
  auto num = [&](double v) {
    return integer ? std::to_string(static_cast<long long>(v)) : number_text(v);
  };
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  if (integer && has_lo && has_hi) return num(lo) + ".." + num(hi);
  if (has_lo && has_hi)
    return std::string(lo_open ? "(" : "[") + num(lo) + ", " + num(hi) + (hi_open ? ")" : "]");
  if (has_lo) return std::string(lo_open ? "> " : ">= ") + num(lo);
  if (has_hi) return std::string(hi_open ? "< " : "<= ") + num(hi);
  return "any value";
}

bool CaseKeyRange::contains(double v) const {
  if (std::isnan(v)) return false;
  if (lo_open ? !(v > lo) : !(v >= lo)) return false;
  if (hi_open ? !(v < hi) : !(v <= hi)) return false;
  return true;
}

namespace {
const CaseKey& find_key(const std::vector<CaseKeyRow>& rows, std::string_view path,
                        const char* table) {
  for (const CaseKeyRow& row : rows)
    for (const CaseKey& k : row.keys)
      if (k.path == path) return k;
  throw Error(std::string(table) + ": no key " + std::string(path) + " (pipeline/case_schema.cpp)");
}
}  // namespace

const CaseKey& case_key(std::string_view path) { return find_key(k_rows, path, "case schema"); }
const CaseKey& study_key(std::string_view path) {
  return find_key(k_study_rows, path, "study schema");
}

namespace {

std::set<std::string> section_keys(const std::vector<CaseKeyRow>& rows, std::string_view section,
                                   const char* table) {
  const std::string prefix = section.empty() ? std::string() : std::string(section) + ".";
  std::set<std::string> keys;
  for (const CaseKeyRow& row : rows)
    for (const CaseKey& k : row.keys) {
      if (k.path.substr(0, prefix.size()) != prefix) continue;
      std::string_view rest = k.path.substr(prefix.size());
      rest = rest.substr(0, rest.find('.'));
      keys.insert(plain(rest));
    }
  if (keys.empty())
    throw Error(std::string(table) + ": no keys under " + std::string(section) +
                " (pipeline/case_schema.cpp)");
  return keys;
}

/// "`meshing.method` is `"curved"` and `geometry.mesh_dir` is absent" ("" without rules).
std::string rules_text(const std::vector<CaseKeyWhen>& when) {
  std::string out;
  for (const CaseKeyWhen& w : when) {
    if (!out.empty()) out += " and ";
    out += "`" + std::string(w.path) + "` is ";
    if (w.values.empty()) {
      out += w.given ? "given" : "absent";
      continue;
    }
    for (std::size_t i = 0; i < w.values.size(); ++i)
      out += std::string(i == 0                     ? ""
                         : i + 1 == w.values.size() ? " or "
                                                    : ", ") +
             "`" + std::string(w.values[i]) + "`";
  }
  return out;
}

/// The row's rules, for the meaning column: " *(only when …)*", per key when they differ.
std::string rules_column(const CaseKeyRow& row) {
  bool same = true;
  for (const CaseKey& k : row.keys)
    same = same && rules_text(k.when) == rules_text(row.keys[0].when);
  if (same) {
    const std::string t = rules_text(row.keys[0].when);
    return t.empty() ? "" : " *(only when " + t + ")*";
  }
  std::string out;
  for (const CaseKey& k : row.keys) {
    const std::string t = rules_text(k.when);
    if (t.empty()) continue;
    out += std::string(out.empty() ? " *(" : "; ") + "`" + std::string(k.path) + "` only when " + t;
  }
  return out.empty() ? out : out + ")*";
}

std::string schema_markdown(const std::vector<CaseKeyRow>& rows) {
  std::string out = "| key | type | default | meaning |\n|---|---|---|---|\n";
  for (const CaseKeyRow& row : rows) {
    std::string keys;
    for (const CaseKey& k : row.keys)
      keys += (keys.empty() ? "`" : ", `") + std::string(k.path) + "`";
    out += "| " + keys + " | " + std::string(row.type) + " | " + default_column(row) + " | " +
           std::string(row.doc) + rules_column(row) + " |\n";
  }
  return out;
}

nlohmann::json rules_json(const std::vector<CaseKeyWhen>& when) {
  nlohmann::json out = nlohmann::json::array();
  for (const CaseKeyWhen& w : when) {
    nlohmann::json o = {{"path", std::string(w.path)}};
    if (w.values.empty()) {
      o["given"] = w.given;
    } else {
      o["values"] = nlohmann::json::array();
      for (const auto v : w.values) o["values"].push_back(nlohmann::json::parse(v));
    }
    out.push_back(std::move(o));
  }
  return out;
}

nlohmann::json schema_json(const std::vector<CaseKeyRow>& rows) {
  using json = nlohmann::json;
  json out = json::array();
  for (const CaseKeyRow& row : rows)
    for (const CaseKey& k : row.keys) {
      json o = {{"path", std::string(k.path)},
                {"type", std::string(to_string(k.type))},
                {"default", k.default_json.empty() ? json() : json::parse(k.default_json)},
                {"default_text", default_column(row)},
                {"allowed", json::array()},
                {"minimum", nullptr},
                {"maximum", nullptr},
                {"minimum_exclusive", false},
                {"maximum_exclusive", false},
                {"type_text", std::string(row.type)},
                {"doc", std::string(row.doc)}};
      for (const auto a : k.allowed) o["allowed"].push_back(std::string(a));
      o["when"] = rules_json(k.when);
      o["defaults"] = json::array();
      for (const CaseKeyDefault& d : k.defaults)
        o["defaults"].push_back({{"when", rules_json(d.when)}, {"value", json::parse(d.value)}});
      o["default_from"] = k.default_from.empty() ? json() : json(std::string(k.default_from));
      if (k.range) {
        if (std::isfinite(k.range->lo)) o["minimum"] = k.range->lo;
        if (std::isfinite(k.range->hi)) o["maximum"] = k.range->hi;
        o["minimum_exclusive"] = k.range->lo_open;
        o["maximum_exclusive"] = k.range->hi_open;
      }
      out.push_back(std::move(o));
    }
  return out;
}

}  // namespace

std::string_view to_string(CaseKeyType t) {
  switch (t) {
    case T::object:
      return "object";
    case T::array:
      return "array";
    case T::string:
      return "string";
    case T::number:
      return "number";
    case T::integer:
      return "integer";
    case T::boolean:
      return "boolean";
    case T::path:
      return "path";
    case T::expression:
      return "expression";
    case T::selection:
      return "selection";
    case T::number_list:
      return "number_list";
    case T::any:
      return "any";
  }
  return "any";
}

const std::vector<CaseKeyRow>& case_schema() { return k_rows; }
const std::vector<CaseKeyRow>& study_schema() { return k_study_rows; }

std::set<std::string> case_section_keys(std::string_view section) {
  return section_keys(k_rows, section, "case schema");
}
std::set<std::string> study_section_keys(std::string_view section) {
  return section_keys(k_study_rows, section, "study schema");
}
std::string case_schema_markdown() { return schema_markdown(k_rows); }
std::string study_schema_markdown() { return schema_markdown(k_study_rows); }
nlohmann::json case_schema_json() { return schema_json(k_rows); }
nlohmann::json study_schema_json() { return schema_json(k_study_rows); }

namespace {

using json = nlohmann::json;

/// One object of a case being resolved: its schema path, the given object (or null) and the
/// resolved object so far.
struct Frame {
  std::string section;
  const json* given;
  const json* out;
};

/// A direct child of a section, in table order.
struct Child {
  std::string name;     ///< the JSON key
  std::string path;     ///< its schema path ("boundary_conditions[]")
  const CaseKey* key;   ///< its row, or null for a section without one ("meshing")
  bool array = false;   ///< `[]`: an array of objects
  bool parent = false;  ///< the table has keys below it
};

class Resolver {
 public:
  Resolver(const std::string& file, const std::function<json(const CaseKey&, const json&)>& norm)
      : file_(file), normalize_(norm) {
    for (const CaseKeyRow& row : k_rows)
      for (const CaseKey& k : row.keys) {
        for (const CaseKeyWhen& w : k.when)
          if (!w.values.empty()) by_value_.insert(std::string(w.path));
        for (const CaseKeyDefault& d : k.defaults)
          for (const CaseKeyWhen& w : d.when)
            if (!w.values.empty()) by_value_.insert(std::string(w.path));
      }
  }

  json object(const std::string& section, const json* given, const std::string& pointer) {
    if (given && !given->is_object()) fail(pointer, "expected an object");
    const std::vector<Child> kids = children(section);
    if (given)
      for (const auto& [key, value] : given->items()) {
        bool known = false;
        for (const Child& c : kids) known = known || c.name == key;
        if (known) continue;
        std::string list;
        for (const auto& a : case_section_keys(section)) list += (list.empty() ? "" : ", ") + a;
        fail(pointer + "/" + key, "unknown key (allowed here: " + list + ")");
      }
    json out = json::object();
    frames_.push_back({section, given, &out});
    for (const Child& c : kids) {
      const json* g = nullptr;
      if (given) {
        auto it = given->find(c.name);
        if (it != given->end()) g = &*it;
      }
      const std::string at = pointer + "/" + c.name;
      if (!c.key) {  // a section: always there
        out[c.name] = object(c.path, g, at);
        continue;
      }
      const CaseKey& k = *c.key;
      if (const CaseKeyWhen* failing = first_failing(k.when)) {
        if (g) fail(at, std::string(failing->error));
        continue;
      }
      if (!g) {
        if (std::optional<json> d = default_of(k)) out[c.name] = normalize(k, *d);
        continue;
      }
      if (by_value_.count(std::string(k.path))) check_rule_value(k, *g, at);
      if (c.array) {
        if (!g->is_array()) fail(at, "expected an array");
        // The elements of load_cases[].boundary_conditions[] have the keys of the top-level
        // boundary_conditions[] (the table documents them once).
        const std::string element = children(c.path).empty() ? plain_last(c.path) : c.path;
        json list = json::array();
        for (std::size_t i = 0; i < g->size(); ++i)
          list.push_back(object(element, &(*g)[i], at + "/" + std::to_string(i)));
        out[c.name] = std::move(list);
      } else if (c.parent && g->is_object() && k.type != CaseKeyType::selection) {
        out[c.name] = object(c.path, g, at);
      } else {
        out[c.name] = normalize(k, *g);
      }
    }
    frames_.pop_back();
    return out;
  }

 private:
  [[noreturn]] void fail(const std::string& pointer, const std::string& what) const {
    throw InputError((pointer.empty() ? std::string("/") : pointer) + ": " + what, {.file = file_});
  }

  json normalize(const CaseKey& k, const json& v) const {
    return normalize_ ? normalize_(k, v) : v;
  }

  /// "load_cases[].boundary_conditions[]" → "boundary_conditions[]".
  static std::string plain_last(const std::string& path) {
    const auto dot = path.rfind('.');
    return dot == std::string::npos ? path : path.substr(dot + 1);
  }

  static std::vector<Child> children(const std::string& section) {
    const std::string prefix = section.empty() ? std::string() : section + ".";
    std::vector<Child> out;
    for (const CaseKeyRow& row : k_rows)
      for (const CaseKey& k : row.keys) {
        if (k.path.size() <= prefix.size() || k.path.substr(0, prefix.size()) != prefix) continue;
        const std::string_view rest = k.path.substr(prefix.size());
        const std::string first(rest.substr(0, rest.find('.')));
        const std::string path = prefix + first;
        const bool deeper = rest.find('.') != std::string_view::npos;
        auto it =
            std::find_if(out.begin(), out.end(), [&](const Child& c) { return c.path == path; });
        if (it == out.end()) {
          const bool array = first.size() > 2 && first.substr(first.size() - 2) == "[]";
          out.push_back({array ? first.substr(0, first.size() - 2) : first, path, nullptr, array});
          it = out.end() - 1;
        }
        if (deeper)
          it->parent = true;
        else
          it->key = &k;
      }
    return out;
  }

  /// The resolved (else given) value of the table key `path`, seen from the innermost object
  /// being resolved that holds it; null when it has none.
  const json* value_of(std::string_view path) const {
    const Frame* f = &frames_.front();
    for (const Frame& fr : frames_)
      if (!fr.section.empty() && path.substr(0, fr.section.size() + 1) == fr.section + ".") f = &fr;
    const std::string_view rest = f->section.empty() ? path : path.substr(f->section.size() + 1);
    const json* out = f->out;
    const json* given = f->given;
    for (std::string part : case_path_components(rest)) {
      if (part.size() > 2 && part.substr(part.size() - 2) == "[]") part.resize(part.size() - 2);
      CF_VERIFY(part.find("[]") == std::string::npos,
                "a case key rule looks into an array it is not in: " + std::string(path));
      auto step = [&](const json* j) -> const json* {
        if (!j || !j->is_object()) return nullptr;
        auto it = j->find(part);
        return it == j->end() ? nullptr : &*it;
      };
      out = step(out);
      given = step(given);
    }
    return out ? out : given;
  }

  /// Whether a rule holds. A value rule on a key that has no value, no default and no rules of
  /// its own (a required key left out: the parser names it) holds, so that the refusal names
  /// the missing key rather than the keys that depend on it.
  bool holds(const CaseKeyWhen& w) const {
    const json* v = value_of(w.path);
    if (w.values.empty()) return (v != nullptr) == w.given;
    if (!v) {
      const CaseKey& target = case_key(w.path);
      return target.default_json.empty() && target.defaults.empty() &&
             target.default_from.empty() && target.when.empty();
    }
    for (const std::string_view text : w.values)
      if (json::parse(text) == *v) return true;
    return false;
  }
  const CaseKeyWhen* first_failing(const std::vector<CaseKeyWhen>& when) const {
    for (const CaseKeyWhen& w : when)
      if (!holds(w)) return &w;
    return nullptr;
  }

  std::optional<json> default_of(const CaseKey& k) const {
    for (const CaseKeyDefault& d : k.defaults) {
      bool all = true;
      for (const CaseKeyWhen& w : d.when)
        all = all && (w.values.empty() || value_of(w.path)) && holds(w);
      if (d.when.empty() || all) return json::parse(d.value);
    }
    if (!k.default_json.empty()) return json::parse(k.default_json);
    if (!k.default_from.empty())
      if (const json* v = value_of(k.default_from)) return *v;
    return std::nullopt;
  }

  /// A key other keys' rules compare by value: its own value is checked first, so that a
  /// misspelt value is named as such instead of the keys that depend on it.
  void check_rule_value(const CaseKey& k, const json& v, const std::string& at) const {
    if (k.type == CaseKeyType::boolean && !v.is_boolean()) fail(at, "expected true/false");
    if (k.allowed.empty()) return;
    if (!v.is_string()) fail(at, "expected a string");
    const std::string s = v.get<std::string>();
    if (std::find(k.allowed.begin(), k.allowed.end(), s) != k.allowed.end()) return;
    std::string list;
    for (std::size_t i = 0; i < k.allowed.size(); ++i)
      list += (i == 0 ? "" : i + 1 == k.allowed.size() ? " or " : ", ") + std::string(k.allowed[i]);
    fail(at, "'" + s + "': expected " + list);
  }

  const std::string& file_;
  const std::function<json(const CaseKey&, const json&)>& normalize_;
  std::set<std::string> by_value_;
  std::vector<Frame> frames_;
};

}  // namespace

std::vector<std::string> case_path_components(std::string_view path) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (true) {
    const auto dot = path.find('.', start);
    out.emplace_back(path.substr(start, dot == std::string_view::npos ? dot : dot - start));
    if (dot == std::string_view::npos) return out;
    start = dot + 1;
  }
}

nlohmann::json resolve_case(
    const nlohmann::json& given, const std::string& file,
    const std::function<nlohmann::json(const CaseKey&, const nlohmann::json&)>& normalize) {
  Resolver r(file, normalize);
  return r.object("", &given, "");
}

std::string replace_schema_block(const std::string& readme, const std::string& table,
                                 std::string_view begin_marker, std::string_view end_marker) {
  const auto begin = readme.find(begin_marker);
  const auto end = readme.find(end_marker);
  if (begin == std::string::npos || end == std::string::npos || end < begin)
    throw Error("no " + std::string(begin_marker) + " ... " + std::string(end_marker) +
                " block in the text");
  // Blank lines around the table keep it a Markdown table of its own.
  return readme.substr(0, begin + begin_marker.size()) + "\n\n" + table + "\n" + readme.substr(end);
}

}  // namespace curvefem::pipeline
