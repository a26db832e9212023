#!/usr/bin/python3
"""Accuracy you can ask for (issue 22): error against DOFs and against whole-run time, per dev
mesh, for every way a user could solve the same Poisson problem on a dense input surface.

Problem per mesh (bounding-box centre c, longest edge L, X = (x - c) / L): -Δu = f with the
manufactured u = sin 3X₁ cos 2X₂ exp X₃ (f = 12u / L²), the flux ∇u·n above the plane
z = c_z + 0.1 L and Dirichlet u below it, the data painted on the dense input (n = the input's
normal; the peer's data at the input's closest point, its normal its own mesh's). With
--physics elasticity: linear elasticity (E = 1, ν = 0.3) with u = (sin 3X₂, sin 3X₃, sin 3X₁)
(divergence-free: f = −μΔu), the traction σn above the plane and u below, the faces the plane
cuts imposed by Nitsche (discretization.partial_dirichlet; elasticity's default, nodal, is made
for clamps and leaves an error floor at a cut through smooth data). The reference is the exact u, so every error below is the true
one (the geometric error of each mesh included).
Methods, all through `curvefem run`, one process each, one after the other:
  dense P1, P2, P3     the input tetrahedralized by Gmsh with its boundary unchanged (P3: the
                       reference of the integral QoI below);
  Mesh_3 + P2          the coarse-linear peer: CGAL Mesh_3 (python3-pygalmesh) on the input with
                       max_facet_distance = ε·L (ε in --peer-eps), min facet angle 25°, radius-edge
                       ratio 3, then P2 on its straight tets with the data read at the input's
                       closest point (geometry.data_surface); mesh time = the Mesh_3 call;
  curved k=3 Pp        the curved pipeline at ε = --eps (default features): P2 meshes; P3 and P4
                       reuse that mesh (geometry.mesh_dir), their whole-run time adds its meshing;
  curved adaptive      meshing.eps = --levels (one shell, one coarsening) with
                       discretization.target_error = dense P1's relative surface RMS error: adaptive
                       p per level, stops at the first level within the target (cases/README.md).
  Where the curved runs read the boundary values (discretization.boundary_values_at): `input`
  (default: at φ⁻¹(x), the data painted on the input), `shifted` (Dirichlet values continued from
  φ⁻¹(x) to x with the recovered gradient, one re-solve) and `mesh` (at x: the data as a field in
  space, the best a painted-data transfer could do); P2–P4 and the adaptive run for each, plus P3
  with the solution read at φ(v) only (output.surface_values "image") against the default
  continuation to v.
Errors: `surf RMS` = RMS over the input's vertices of u_h (transferred back) - u, relative to
the RMS of u there (report.json surface_l2_error / surface_l2_norm_exact); `surf max` = the max
there over max |u| is not reported, so absolute (u is O(1)); `L2` and `H1` = volume errors
relative to the exact norms on each run's own domain.
Integral QoI: ∫f u_h over each run's own domain (elasticity ∫b·u_h), the volume part of the load
functional (report.json physics_details.load_functional.volume), relative to dense P3's (a
converged dense reference: P2's distance to it is in the table). Not the whole l(u_h): the plane
cuts boundary faces, whose data are integrated with an indicator at the quadrature points, and
that term is first-order accurate at the cut whatever the degree.
Time: whole process wall, and `run s` = report time_s.total minus the benchmark's own error
integration (errors, error_estimate).

Usage (from the repository root; needs ../shared/data/dev, gmsh, python3-pygalmesh, meshio):
  /usr/bin/python3 benchmarks/run_accuracy.py [--meshes spot fertility ...] [--eps 0.01]
      [--levels 0.04 0.02 0.01 0.005] [--peer-eps 0.02 0.01 0.005] [--physics elasticity]
      [--work /tmp/accuracy]
      [--out benchmarks/results/accuracy.md] [--note TEXT] [--render-from WORK/runs.jsonl]
"""
import argparse
import datetime
import functools
import json
import math
import os
import shlex
import subprocess
import sys
import time

from manufactured import obj_bbox, scaled_solution

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--data", default=os.path.join(os.path.dirname(root), "shared", "data", "dev"))
ap.add_argument("--meshes", nargs="+",
                default=["spot", "fertility", "homer", "fandisk", "rocker_arm", "armadillo"])
ap.add_argument("--eps", type=float, default=0.01)
ap.add_argument("--physics", choices=["poisson", "elasticity"], default="poisson")
ap.add_argument("--levels", nargs="+", type=float, default=[0.04, 0.02, 0.01, 0.005])
ap.add_argument("--peer-eps", nargs="+", type=float, default=[0.02, 0.01, 0.005])
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--timeout", type=float, default=1800)
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--work", default="/tmp/accuracy_bench")
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/accuracy.md"))
ap.add_argument("--note", default="")
ap.add_argument("--render-from", help="write the tables from a previous runs.jsonl only")
args = ap.parse_args()
command = "/usr/bin/python3 " + " ".join(
    shlex.quote(a) for a in ["benchmarks/run_accuracy.py"] + sys.argv[1:])


@functools.lru_cache(maxsize=None)
def problem(path):
    u, grad, f, c, L, X = scaled_solution(*obj_bbox(path))
    return u, f, L, grad, c, X


def case(path, geometry, meshing, degree, extra=None):
    u, f, L, grad, c, X = problem(path)
    # Neumann above z0 = c_z + 0.1 L, so that the solution on the surface is computed there (with
    # Dirichlet everywhere the dense runs would carry the data exactly). Planes, not normal
    # cones: the peer's given mesh can only be selected by position.
    z0 = [c[0], c[1], c[2] + 0.1 * L]
    flux = "(%s)*nx + (%s)*ny + (%s)*nz" % tuple(grad)
    c = {"geometry": geometry, "meshing": meshing, "physics": {"type": "poisson"},
         "discretization": {"degree": degree}, "rhs": f, "exact": u, "exact_gradient": grad,
         "boundary_conditions": [
             {"type": "dirichlet", "select": {"plane": {"point": z0, "normal": [0, 0, -1]}},
              "value": u},
             {"type": "neumann", "select": {"plane": {"point": z0, "normal": [0, 0, 1]}},
              "value": flux}]}
    if args.physics == "elasticity":
        # u = (sin 3X₂, sin 3X₃, sin 3X₁): div u = 0, so σ = 2μ ε(u) and f = −μ Δu = 9μ/L² u;
        # E = 1, ν = 0.3. The traction above z0 is σ n with the normal of the data's surface.
        mu = 1 / (2 * 1.3)
        disp = ["sin(3*%s)" % X[1], "sin(3*%s)" % X[2], "sin(3*%s)" % X[0]]
        a, b, cc = ("%.17g*cos(3*%s)" % (3 * mu / L, X[i]) for i in (1, 2, 0))  # σ12, σ23, σ13
        traction = ["(%s)*ny + (%s)*nz" % (a, cc), "(%s)*nx + (%s)*nz" % (a, b),
                    "(%s)*nx + (%s)*ny" % (cc, b)]
        c.update({"physics": {"type": "linear_elasticity", "E": 1, "nu": 0.3},
                  "rhs": ["%.17g*%s" % (9 * mu / (L * L), d) for d in disp], "exact": disp})
        c.pop("exact_gradient")
        c["boundary_conditions"][0]["value"] = disp
        c["boundary_conditions"][1]["value"] = traction
        # The plane cuts boundary faces, and the data are smooth across it: Nitsche on the cut
        # faces (elasticity's default, nodal, leaves an error floor there: dense P3 on spot
        # 8.6e-4 relative L2 nodal, 1.5e-7 Nitsche).
        c["discretization"]["partial_dirichlet"] = "nitsche"
    for k, v in (extra or {}).items():
        c.setdefault(k, {}).update(v)
    return c


def run(spec, out):
    path = out + ".json"
    with open(path, "w") as fh:
        json.dump(spec, fh, indent=1)
    cmd = [args.exe, "run", path, "-o", out, "-q", "--threads", str(args.threads)]
    start = time.time()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
        code, err = p.returncode, (p.stderr.strip().splitlines() or [""])[-1]
    except subprocess.TimeoutExpired:
        code, err = "timeout", ""
    wall = time.time() - start
    rep = {}
    try:
        with open(os.path.join(out, "report.json")) as fh:
            rep = json.load(fh)
    except (OSError, ValueError):
        pass
    return code, wall, rep, err


def record(mesh, method, code, wall, rep, err, extra_s=0.0, **kw):
    t = rep.get("time_s", {})
    run_s = t.get("total", math.nan) - t.get("errors", 0.0) - t.get("error_estimate", 0.0)

    def rel(a, b):
        return rep[a] / rep[b] if a in rep and rep.get(b) else None

    r = {"mesh": mesh, "method": method, "exit": code, "error": err[:160],
         "dofs": rep.get("dofs"), "tets": rep.get("tets"),
         "surf_rms": rel("surface_l2_error", "surface_l2_norm_exact"),
         "surf_max": rep.get("surface_max_error"),
         "unmapped": rep.get("surface_unmapped_vertices"),
         "l2": rel("l2_error", "l2_norm_exact"), "h1": rel("h1_semi_error", "h1_semi_norm_exact"),
         "mesh_s": t.get("meshing", 0.0) + t.get("load_surface", 0.0) + extra_s,
         "run_s": run_s + extra_s, "wall": wall + extra_s,
         "valid": rep.get("mesh_valid"), "physics": args.physics,
         "qoi": rep.get("physics_details", {}).get("load_functional", {}).get("volume"),
         "qoi_all": rep.get("physics_details", {}).get("load_functional", {}).get("value"), **kw}
    print(json.dumps({k: r[k] for k in ("mesh", "method", "exit", "dofs", "surf_rms", "run_s")}),
          file=sys.stderr, flush=True)
    return r


def measure(name):
    src = os.path.join(args.data, name + ".obj")
    d = os.path.join(args.work, name)
    os.makedirs(d, exist_ok=True)
    rows = []
    faces = sum(1 for line in open(src) if line.startswith("f "))
    geo = {"surface": src}
    for p in (1, 2, 3):
        code, wall, rep, err = run(case(src, geo, {"method": "dense"}, p),
                                   os.path.join(d, "dense_p%d" % p))
        rows.append(record(name, "dense P%d" % p, code, wall, rep, err, faces=faces))
    target = rows[0]["surf_rms"]
    # The coarse-linear peer at several distance bounds.
    try:
        import meshio
        import pygalmesh
        surf = meshio.read(src)
        off = os.path.join(d, "input.off")
        meshio.write(off, meshio.Mesh(surf.points, [("triangle", surf.get_cells_type("triangle"))]))
        L = problem(src)[2]
        for eps in args.peer_eps:
            start = time.time()
            vol = pygalmesh.generate_volume_mesh_from_surface_mesh(
                off, min_facet_angle=25.0, max_facet_distance=eps * L,
                max_circumradius_edge_ratio=3.0, verbose=False, seed=1)
            msh = os.path.join(d, "mesh3_eps%g.msh" % eps)
            meshio.write(msh, meshio.Mesh(vol.points, [("tetra", vol.get_cells_type("tetra"))]),
                         file_format="gmsh")
            mesh_s = time.time() - start
            code, wall, rep, err = run(
                case(src, {"mesh": msh, "data_surface": src}, {"method": "given"}, 2),
                os.path.join(d, "peer_eps%g" % eps))
            rows.append(record(name, "Mesh_3 ε=%g + P2" % eps, code, wall, rep, err,
                               extra_s=mesh_s, faces=faces, peer=True))
    except Exception as e:  # a failed peer is a row, not the end of the benchmark
        rows.append({"mesh": name, "method": "Mesh_3 + P2", "exit": "error", "error": str(e)[:160]})
    # Curved at one ε: P2 meshes, P3 and P4 reuse its mesh and add its meshing time.
    out2 = os.path.join(d, "curved_p2")
    code, wall, rep, err = run(case(src, geo, {"method": "curved", "order": 3, "eps": args.eps}, 2,
                                    INPUT), out2)
    rows.append(record(name, "curved k=3 ε=%g P2" % args.eps, code, wall, rep, err, faces=faces))
    mesh_s = rows[-1]["mesh_s"] if code == 0 else None
    for p in (3, 4):
        if mesh_s is None:
            break
        code, wall, rep, err = run(case(src, {"mesh_dir": out2}, {"method": "curved"}, p, INPUT),
                                   os.path.join(d, "curved_p%d" % p))
        rows.append(record(name, "curved k=3 ε=%g P%d" % (args.eps, p), code, wall, rep, err,
                           extra_s=mesh_s, faces=faces))
    # The same mesh: P3 with u_h read at φ(v) only (output.surface_values "image"), and P2–P4
    # with the values read at the mesh's own points (discretization.boundary_values_at "mesh").
    if mesh_s is not None:
        code, wall, rep, err = run(case(src, {"mesh_dir": out2}, {"method": "curved"}, 3,
                                        dict(INPUT, output={"surface_values": "image"})),
                                   os.path.join(d, "curved_p3_image"))
        rows.append(record(name, "curved k=3 ε=%g P3, image" % args.eps, code, wall, rep, err,
                           extra_s=mesh_s, faces=faces))
        for at in ("shifted", "mesh"):
            for p in (2, 3, 4):
                code, wall, rep, err = run(
                    case(src, {"mesh_dir": out2}, {"method": "curved"}, p,
                         {"discretization": {"boundary_values_at": at}}),
                    os.path.join(d, "curved_p%d_%s" % (p, at)))
                rows.append(record(name, "curved k=3 ε=%g P%d%s" % (args.eps, p, SUFFIX[at]), code,
                                   wall, rep, err, extra_s=mesh_s, faces=faces))
    # Curved adaptive: ε levels from one coarsening, adaptive p per level, dense P1's accuracy.
    for at in ("input", "shifted", "mesh") if target else ():
        spec = case(src, geo, {"method": "curved", "order": 3, "eps": args.levels}, 2,
                    {"discretization": {"target_error": target, "boundary_values_at": at}})
        code, wall, rep, err = run(spec, os.path.join(d, "curved_adaptive_" + at))
        el = rep.get("eps_levels") if isinstance(rep.get("eps_levels"), dict) else {}
        rows.append(record(name, "curved adaptive" + SUFFIX[at],
                           code, wall, rep, err, faces=faces, target=target,
                           reached=el.get("reached"), reason=el.get("reason"),
                           levels=[{k: x.get(k) for k in ("eps", "degree", "dofs")}
                                   for x in el.get("levels", [])]))
    return rows


READING = "## Reading (by hand; kept by run_accuracy.py)"
# The curved rows without a suffix read the values on the input (the default until 2026-12-04).
INPUT = {"discretization": {"boundary_values_at": "input"}}
# Row-name suffix per discretization.boundary_values_at.
SUFFIX = {"input": "", "shifted": ", shifted", "mesh": ", data at mesh"}


def kind_of(method):
    return next((k for k, s in SUFFIX.items() if s and method.endswith(s)), "input")


def short(method):
    """The row name without "curved " and the boundary-values suffix."""
    s = SUFFIX[kind_of(method)]
    return method.replace("curved ", "")[:-len(s) if s else None]


def g(x, spec="%.3g"):
    return "—" if x is None or (isinstance(x, float) and math.isnan(x)) else spec % x


def interp_loglog(pts, x):
    """Error of a (dofs, error) curve at `x` DOFs, log-log linear, None outside its range."""
    pts = sorted(p for p in pts if p[0] and p[1])
    for (x0, y0), (x1, y1) in zip(pts, pts[1:]):
        if x0 <= x <= x1 and x1 > x0:
            t = (math.log(x) - math.log(x0)) / (math.log(x1) - math.log(x0))
            return math.exp(math.log(y0) + t * (math.log(y1) - math.log(y0)))
    return None


def render(rows):
    when = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    head = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"], capture_output=True,
                          text=True).stdout.strip()
    elastic = rows and rows[0].get("physics") == "elasticity"
    problem_text = (
        "Linear elasticity (E = 1, ν = 0.3), u = (sin 3X₂, sin 3X₃, sin 3X₁) (X = (x − c)/L), "
        "body force −μΔu, the traction σn above z = c_z + 0.1 L, u given below"
        if elastic else
        "Poisson, u = sin 3X₁ cos 2X₂ exp X₃ (X = (x − c)/L), flux ∇u·n above z = c_z + 0.1 L, "
        "Dirichlet u below")
    L = ["# Accuracy against DOFs and time: curved, dense and coarse-linear (issue 22)" +
         (", linear elasticity" if elastic else ""), "",
         f"Generated {when} by `{command}`; HEAD {head}; 2 cores, {args.threads} threads, one "
         "run at a time." + (" " + args.note if args.note else ""), "",
         problem_text + ", the data painted on the input; errors against the exact u "
         "(geometric error included). surf RMS = "
         "RMS of |u_h − u| over the input's vertices relative to the RMS of |u|; surf max absolute "
         "(u is O(1)); L2, H1 = relative volume errors on each run's own domain. run s = whole "
         "run without the benchmark's error integration (report time_s), mesh s its meshing "
         "part (Mesh_3's call for the peer; the P2 mesh's for curved P3/P4).", ""]
    by_mesh = {}
    for r in rows:
        by_mesh.setdefault(r["mesh"], []).append(r)
    L[-2] += (" QoI = ∫f u_h (elasticity ∫b·u_h) on the run's own domain, the volume part of "
              "the load functional (physics_details.load_functional.volume), relative to dense "
              "P3's, whose value is given.")
    L += ["| mesh | faces | method | exit | DOFs | tets | surf RMS | surf max | L2 | H1 | QoI "
          "| mesh s | run s |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, rs in by_mesh.items():
        ref = next((r.get("qoi") for r in rs if r["method"] == "dense P3" and r.get("exit") == 0),
                   None)
        for r in rs:
            q = (abs(r["qoi"] - ref) / abs(ref) if ref and r.get("qoi") is not None
                 and r["method"] != "dense P3" else None)
            L.append(f"| {name} | {r.get('faces', '—')} | {r['method']} | {r['exit']} | "
                     f"{r.get('dofs') or '—'} | {r.get('tets') or '—'} | {g(r.get('surf_rms'))} | "
                     f"{g(r.get('surf_max'))} | {g(r.get('l2'))} | {g(r.get('h1'))} | "
                     f"{g(q) if q is not None else ('ref. ' + g(r.get('qoi'), '%.6g') if r['method'] == 'dense P3' and r.get('qoi') is not None else '—')} | "
                     f"{g(r.get('mesh_s'), '%.1f')} | {g(r.get('run_s'), '%.1f')} |")
    L += ["", "## Goals (issue 22), per mesh", "",
          "Against dense P1 and dense P2: the cheapest curved row (fixed ε or adaptive) whose surf "
          "RMS is at most theirs, its DOFs and run time as fractions of theirs (goal at dense P1's "
          "accuracy: ≤ 1/10 DOFs and ≤ 1/5 time on ≥ 20k faces, no slower on 5k–10k; at dense "
          "P2's: ≤ 1/10 DOFs and less time). Against the peer: the peer's volume L2 error interpolated "
          "(log-log, between its ε runs) at each curved row's DOFs over the curved row's (goal "
          "≥ 5; the peer's solution is not transferred to the input's vertices, so its surf "
          "columns are empty).", "",
          "| mesh | faces | curved values read | vs dense P1 (curved row, DOFs, time) | vs dense "
          "P2 | peer L2 / curved L2 at equal DOFs |", "|---|---|---|---|---|---|"]
    for name, rs in by_mesh.items():
        peer = [(r["dofs"], r["l2"]) for r in rs if r.get("peer") and r.get("exit") == 0]
        for at in ("input", "shifted", "mesh"):
            ok = [r for r in rs if r["method"].startswith("curved") and r.get("exit") == 0
                  and r.get("surf_rms") and kind_of(r["method"]) == at
                  and not r["method"].endswith("image")]
            cells = []
            for ref_name in ("dense P1", "dense P2"):
                ref = next((r for r in rs if r["method"] == ref_name and r.get("exit") == 0), None)
                if not ref or not ref.get("surf_rms"):
                    cells.append("—")
                    continue
                good = [r for r in ok if r["surf_rms"] <= ref["surf_rms"]]
                if not good:
                    best = min(ok, key=lambda r: r["surf_rms"], default=None)
                    cells.append("not reached (best %s vs %s)" % (
                        g(best["surf_rms"]) if best else "—", g(ref["surf_rms"])))
                    continue
                b = min(good, key=lambda r: r["run_s"])
                cells.append("%s: %.2f× DOFs, %.2f× time" % (
                    short(b["method"]),
                    b["dofs"] / ref["dofs"], b["run_s"] / ref["run_s"]))
            ratios = []
            for r in ok:
                e = interp_loglog(peer, r["dofs"])
                if e and r.get("l2"):
                    ratios.append("%s %.1f" % (short(r["method"]), e / r["l2"]))
            L.append(f"| {name} | {rs[0].get('faces', '—')} | {at} | {cells[0]} | {cells[1]} | "
                     f"{'; '.join(ratios) if ratios else 'no curved row in the peer DOF range'} |")
    adaptive = [r for r in rows if r["method"].startswith("curved adaptive")]
    if adaptive:
        L += ["", "## Adaptive runs", "", "| mesh | run | target (dense P1 surf RMS) | reached | "
              "reason | levels solved (ε: degree, DOFs) |", "|---|---|---|---|---|---|"]
        for r in adaptive:
            lv = "; ".join("%g: P%s, %s" % (x.get("eps"), x.get("degree"), x.get("dofs"))
                           for x in r.get("levels") or [])
            L.append(f"| {r['mesh']} | {r['method']} | {g(r.get('target'))} | {r.get('reached')} | "
                     f"{r.get('reason') or '—'} | {lv or '—'} |")
    return "\n".join(L) + "\n"


def main():
    if args.render_from:
        with open(args.render_from) as f:
            rows = [json.loads(line) for line in f if line.strip()]
    else:
        if not os.path.isdir(args.data):
            sys.exit(f"no dev data at {args.data} (../shared/data/dev): nothing to measure")
        os.makedirs(args.work, exist_ok=True)
        rows = []
        with open(os.path.join(args.work, "runs.jsonl"), "a") as jl:
            for name in args.meshes:
                for r in measure(name):
                    rows.append(r)
                    jl.write(json.dumps(r) + "\n")
                    jl.flush()
    text = render(rows)
    # The hand-written reading of an earlier run is kept (this script writes the rest).
    try:
        with open(args.out) as f:
            old = f.read()
        if READING in old:
            text += "\n" + old[old.index(READING):]
    except OSError:
        pass
    with open(args.out + ".tmp", "w") as f:
        f.write(text)
    os.replace(args.out + ".tmp", args.out)
    print(args.out)


main()
