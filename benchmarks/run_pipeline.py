#!/usr/bin/python3
"""Whole-pipeline benchmark: curved vs dense-linear on the shipped dense-surface cases, plus the
benchmark-only cases of benchmarks/cases/ on the real meshes of ../shared/data (DATA_CASES; run
by default when that data is there, skipped otherwise).

For every case it runs `curvefem run CASE -o DIR` (log in WORK/CASE/METHOD.log) twice, one after
the other:
  curved  the case as shipped (coarse curved mesh of order k, P_p, boundary map phi);
  dense   the same case with "meshing": {"method": "dense"} and degree 1 (the input itself
          tetrahedralized, P1: the classical pipeline).
It reads both report.json files (DOFs, tets, stage times, volume and dense-surface errors) and,
for cases without an exact solution, compares the two solutions on the dense input vertices
(surface.vtu, read with Debian's python3-vtk9), and with a dense run of higher degree where that
is affordable (REFERENCE_DEGREE). Then it runs the two sphere studies (cases/study_sphere_*.json)
for error vs DOFs of both pipelines on one shape. One run each, sequential; `uptime` is recorded
before every run. Goal (thesis, 8 s vs 50 min): >= 50x fewer DOFs and >= 20x less total time at
equal or better error.

Usage (from the repository root, after `tools/bootstrap build` and `tools/bootstrap data`):
  /usr/bin/python3 benchmarks/run_pipeline.py [--exe build/tools/curvefem/curvefem]
      [--cases poisson_curved_bracket ...] [--work out-pipeline] [--timeout 7200]
Writes benchmarks/results/pipeline.md (a final "## Notes (hand-written, ...)" section of the
previous file is kept); the runs stay in --work; --reuse keeps unchanged runs of a previous call.
"""
import argparse
import datetime
import json
import math
import re
import os
import shlex
import subprocess
import sys
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CASES = ["poisson_curved_sphere", "poisson_curved_bracket", "elasticity_curved_elephant",
         "neo_hookean_curved_elephant", "potential_flow_sphere_exterior"]
# Benchmark-only cases on the real meshes of ../shared/data (benchmarks/cases/; not shipped in
# cases/, whose cases run without ../shared). Run by default when the data is there.
DATA_CASES = {"poisson_curved_igea": "data/dev/igea.obj"}
SHARED = os.path.join(os.path.dirname(root), "shared")
CASES += [n for n, f in DATA_CASES.items() if os.path.exists(os.path.join(SHARED, f))]
# Cases without an exact solution get a third run where it is affordable: the dense mesh at a
# higher degree, as the reference both pipelines are measured against.
REFERENCE_DEGREE = {"elasticity_curved_elephant": 2}
METHODS = ("curved", "dense", "reference")
NOTES_HEADER = "## Notes (hand-written, kept by run_pipeline.py)"
ap = argparse.ArgumentParser()
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--cases", nargs="+", default=CASES)
ap.add_argument("--work", default=os.path.join(root, "out-pipeline"))
ap.add_argument("--timeout", type=float, default=7200)
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/pipeline.md"))
ap.add_argument("--reuse", action="store_true",
                help="keep a run of a previous invocation (same --work) whose case variant is "
                     "unchanged; only changed or new runs are run again")
ap.add_argument("--rerun", nargs="*", default=[], metavar="METHOD",
                help="with --reuse: run these methods again even if unchanged (e.g. curved after a "
                "mesher change)")
ap.add_argument("--studies", action=argparse.BooleanOptionalAction, default=True,
                help="also run cases/study_sphere_curved_p2.json and study_sphere_dense_p1.json "
                     "(error vs DOFs for both pipelines on one shape)")
args = ap.parse_args()
command = "/usr/bin/python3 " + " ".join(
    shlex.quote(a) for a in ["benchmarks/run_pipeline.py"] + sys.argv[1:])


def sh(cmd):
    return subprocess.run(cmd, shell=True, capture_output=True, text=True).stdout.strip()


def absolute_paths(case, case_dir):
    g = case["geometry"]
    for key in ("surface", "mesh"):
        if key in g:
            g[key] = os.path.normpath(os.path.join(case_dir, g[key]))
    f = g.get("features")
    if isinstance(f, dict) and "file" in f:
        f["file"] = os.path.normpath(os.path.join(case_dir, f["file"]))
    return case


def case_path(name):
    bench = os.path.join(root, "benchmarks", "cases", name + ".json")
    return bench if os.path.exists(bench) else os.path.join(root, "cases", name + ".json")


def variant(name, method):
    path = case_path(name)
    with open(path) as f:
        case = absolute_paths(json.load(f), os.path.dirname(path))
    if method in ("dense", "reference"):
        # Keep the domain keys (exterior problems): only the mesher changes.
        case["meshing"] = {"method": "dense", **{k: v for k, v in case.get("meshing", {}).items()
                                                 if k in ("exterior", "padding", "solve_on")}}
        case.setdefault("discretization", {})["degree"] = REFERENCE_DEGREE.get(name, 1) \
            if method == "reference" else 1
    out = os.path.join(args.work, name, method)
    case["output"] = {"dir": out}
    os.makedirs(os.path.join(args.work, name), exist_ok=True)
    file = os.path.join(args.work, name, method + ".json")
    with open(file, "w") as f:
        json.dump(case, f, indent=1)
    return file, out, case


def previous_runs():
    try:
        with open(os.path.join(args.work, "pipeline_runs.json")) as f:
            return {(p[m]["case"], m): p[m] for p in json.load(f) for m in METHODS if m in p}
    except (OSError, ValueError, KeyError):
        return {}


PREVIOUS = previous_runs() if args.reuse else {}


def run(name, method):
    old = PREVIOUS.get((name, method))
    file, out, case = variant(name, method)
    if old and old.get("case_json") == case and old.get("report") and method not in args.rerun:
        old["reused"] = True
        print("%-28s %-6s reused (%s)" % (name, method, old["uptime"]), file=sys.stderr)
        return old
    load = sh("uptime")
    cmd = [args.exe, "run", file, "-o", out]
    log = os.path.join(args.work, name, method + ".log")
    start = time.time()
    with open(log, "w") as f:
        try:
            code = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT,
                                  timeout=args.timeout).returncode
        except subprocess.TimeoutExpired:
            code = "timeout"
    wall = time.time() - start
    with open(log) as f:
        text = f.read()
    r = {"case": name, "method": method, "exit": code, "wall_s": wall, "uptime": load,
         "command": " ".join(shlex.quote(c) for c in cmd), "log": log,
         "stderr": ("killed after %g s; " % args.timeout if code == "timeout" else "") +
         "\n".join(text.strip().splitlines()[-3:]), "exact": "exact" in case, "out": out,
         "case_json": case}
    # Sizes from the log, for a run that did not finish (the last "N unknowns", "N tetrahedra").
    for key, pattern in (("log_unknowns", r"(\d+) unknowns"), ("log_tets", r"mesh: (\d+) tetrahedra")):
        found = re.findall(pattern, text)
        if found:
            r[key] = int(found[-1])
    rep = os.path.join(out, "report.json")
    if code in (0, 3) and os.path.exists(rep):
        with open(rep) as f:
            r["report"] = json.load(f)
    print("%-28s %-6s exit %s  %.1f s" % (name, method, code, wall), file=sys.stderr)
    return r


STUDIES = {"curved": "study_sphere_curved_p2", "dense": "study_sphere_dense_p1"}


def run_study(method):
    name = STUDIES[method]
    out = os.path.join(args.work, name)
    cmd = [args.exe, "study", os.path.join(root, "cases", name + ".json"), "-o", out, "-q"]
    load = sh("uptime")
    start = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.time() - start
    print("%-28s exit %s  %.1f s" % (name, p.returncode, wall), file=sys.stderr)
    rows = []
    csv_file = os.path.join(out, "study.csv")
    if os.path.exists(csv_file):
        import csv
        with open(csv_file) as f:
            rows = [r for r in csv.DictReader(f) if r["status"] == "ok"]
    return {"name": name, "method": method, "exit": p.returncode, "wall_s": wall, "uptime": load,
            "command": " ".join(shlex.quote(c) for c in cmd), "rows": rows,
            "stderr": p.stderr.strip()[-600:]}


def study_section(studies):
    L = ["## Error vs DOFs on one shape (the two sphere studies)", ""]
    L.append("Same physics as `poisson_curved_sphere.json` (u = sin x cos y eᶻ, mixed Dirichlet / "
             "Neumann painted on the input). curved: k = 3, p = 2 on the level-5 icosphere "
             "(20,480 faces), ε swept; dense: P1 on the icosphere of level 2–5 (the input "
             "itself is refined).")
    L.append("")
    L.append("| pipeline | run | DOFs | tets | meshing s | solve s | total s | L2 error | "
             "surface L2 |")
    L.append("|---|---|---|---|---|---|---|---|---|")
    for st in studies:
        for r in st["rows"]:
            L.append("| %s | %s | %s | %s | %.1f | %.1f | %.1f | %.3g | %.3g |"
                     % (st["method"], r["name"], r["dofs"], r["tets"], float(r["meshing_s"]),
                        float(r["solve_s"]), float(r["total_s"]), float(r["l2_error"]),
                        float(r["surface_l2_error"])))
    by = {st["method"]: st["rows"] for st in studies}
    if by.get("curved") and by.get("dense"):
        best_dense = min(by["dense"], key=lambda r: float(r["l2_error"]))
        e = float(best_dense["l2_error"])
        ok = [r for r in by["curved"] if float(r["l2_error"]) <= e]
        c = min(ok, key=lambda r: int(r["dofs"])) if ok else \
            min(by["curved"], key=lambda r: float(r["l2_error"]))
        L.append("")
        L.append("Most accurate dense run (%s, L2 %.3g) vs %s curved run (%s, L2 %.3g): "
                 "DOFs %.1f× fewer, total time %.1f× less, L2 error ratio curved / dense %.2f."
                 % (best_dense["name"], e,
                    "the cheapest equally accurate" if ok else "the most accurate",
                    c["name"], float(c["l2_error"]),
                    int(best_dense["dofs"]) / int(c["dofs"]),
                    float(best_dense["total_s"]) / float(c["total_s"]),
                    float(c["l2_error"]) / e))
    L.append("")
    for st in studies:
        L.append("- `%s` (exit %s, wall %.1f s) — load before: `%s`"
                 % (st["command"].replace(root + "/", ""), st["exit"], st["wall_s"],
                    st["uptime"]))
    L.append("")
    return L


def surface_field(out):
    """The solution field on the dense input: (name, list of tuples) from surface.vtu."""
    import vtk  # Debian python3-vtk9 (/usr/bin/python3)
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(os.path.join(out, "surface.vtu"))
    reader.Update()
    pd = reader.GetOutput().GetPointData()
    for name in ("displacement", "u"):
        a = pd.GetArray(name)
        if a is not None:
            c = a.GetNumberOfComponents()
            return name, [[a.GetComponent(i, k) for k in range(c)]
                          for i in range(a.GetNumberOfTuples())]
    return None, []


def agreement(curved, dense):
    """Curved vs dense solution at the dense input vertices: RMS and max of the difference,
    relative to the max of the dense solution; and how many vertices carry a finite value."""
    name, a = surface_field(curved["out"])
    _, b = surface_field(dense["out"])
    if not a or len(a) != len(b):
        return None
    norm = lambda v: math.sqrt(sum(x * x for x in v))
    finite = sum(1 for v in a if all(math.isfinite(x) for x in v))
    diff = [norm([x - y for x, y in zip(u, v)]) for u, v in zip(a, b)]
    scale = max(norm(v) for v in b) or 1.0
    return {"field": name, "vertices": len(a), "finite": finite,
            "rms_rel": math.sqrt(sum(d * d for d in diff) / len(diff)) / scale,
            "max_rel": max(diff) / scale, "max_dense": scale,
            "max_curved": max(norm(v) for v in a)}


def times(rep):
    t = rep["time_s"]
    mesh = sum(t.get(k, 0.0) for k in ("load_surface", "meshing", "load_mesh"))
    solve = sum(t.get(k, 0.0) for k in ("build_space", "assembly", "solve", "newton"))
    return mesh, solve, t["total"], t["total"] - t.get("errors", 0.0) - t.get("error_estimate", 0.0)


def fmt(x, spec="%.3g"):
    return "—" if x is None else spec % x


def final_energy(rep):
    """Potential energy at the last Newton iterate of a nonlinear run, or None."""
    newton = (rep or {}).get("physics_details", {}).get("newton") or []
    return newton[-1].get("energy") if newton else None


def ratio(a, b):
    return None if a is None or b is None or b == 0 else a / b


def main():
    if not os.path.exists(args.exe):
        sys.exit("no curvefem executable at %s (tools/bootstrap build, or --exe)" % args.exe)
    started = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    commit = sh("git -C %s rev-parse --short HEAD" % shlex.quote(root))
    dirty = sh("git -C %s status --porcelain --untracked-files=no" % shlex.quote(root))
    results = []
    for name in args.cases:
        pair = {m: run(name, m) for m in ("curved", "dense")}
        if name in REFERENCE_DEGREE:
            pair["reference"] = run(name, "reference")
        results.append(pair)
        with open(os.path.join(args.work, "pipeline_runs.json"), "w") as f:
            json.dump(results, f, indent=1)
    studies = [run_study(m) for m in ("curved", "dense")] if args.studies else []

    L = ["# Pipeline benchmark: curved vs dense-linear (issue 7)", ""]
    built = datetime.datetime.fromtimestamp(os.path.getmtime(args.exe)).strftime("%Y-%m-%d %H:%M")
    L.append("Generated %s by `%s`; HEAD %s%s; `%s` built %s from the working tree; %s cores "
             "(`nproc`); one run each, sequential%s."
             % (started, command, commit, " (+ uncommitted changes)" if dirty else "",
                os.path.relpath(args.exe, root), built, sh("nproc"),
                "; runs marked *reused* come from an earlier invocation (their own date and load "
                "are given)" if any(p[m].get("reused") for p in results for m in p
                                    if m in METHODS) else ""))
    L.append("")
    L.append("curved = the case as shipped (coarse curved mesh of order k, P_p, boundary data and "
             "solution through φ); dense = the same case with `meshing.method` dense and P1 (the "
             "input tetrahedralized by Gmsh with its boundary unchanged). Times from report.json: "
             "meshing = load_surface + meshing, solve = build_space + assembly + solve (+ newton), "
             "total = the whole run including error evaluation and output (total − errors leaves "
             "the error evaluation out: it integrates the exact solution and its finite-difference "
             "gradient, a cost a user without an exact solution does not pay). L2 = volume L2 error; surface "
             "L2 / max = error at the dense input vertices. Without an exact solution, the "
             "curved solution is compared with the dense one at the dense input vertices "
             "(surface.vtu): RMS and max of the difference relative to max |dense|; where affordable "
             "(REFERENCE_DEGREE) both are also compared with a dense run of higher degree "
             "(method `reference` in the first table).")
    L.append("")
    L.append("| case | method | k / p | input faces | DOFs | tets | meshing s | solve s | total s "
             "| total − errors s | L2 error | surface L2 | surface max | exit |")
    L.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    verdicts = []
    energy_cases = []
    for pair in results:
        for m in [m for m in METHODS if m in pair]:
            r = pair[m]
            rep = r.get("report")
            if not rep:
                L.append("| %s | %s | | | ≥ %s (log) | %s (log) | | | > %.0f | | | | | %s |"
                         % (r["case"], m, r.get("log_unknowns", "?"), r.get("log_tets", "?"),
                            r["wall_s"], r["exit"]))
                continue
            mesh, solve, total, no_err = times(rep)
            L.append("| %s | %s | %s / %s | %s | %d | %d | %.1f | %.1f | %.1f | %.1f | %s | %s | %s "
                     "| %s |"
                     % (r["case"], m, rep.get("order"), rep.get("degree"),
                        rep["meshing"].get("input_faces", "—"), rep["dofs"], rep["tets"], mesh,
                        solve, total, no_err, fmt(rep.get("l2_error")),
                        fmt(rep.get("surface_l2_error")),
                        fmt(rep.get("surface_max_error")), r["exit"]))
    L.append("")
    L.append("## Ratios dense / curved (goal: DOFs >= 50, total time >= 20, at equal or better "
             "error)")
    L.append("")
    L.append("| case | DOFs | tets | total time | total − errors | L2 error curved / dense | "
             "surface L2 curved / dense | curved vs dense on the input (RMS / max, rel.) | "
             "goal met |")
    L.append("|---|---|---|---|---|---|---|---|---|")
    for pair in results:
        c, d = pair["curved"].get("report"), pair["dense"].get("report")
        name = pair["curved"]["case"]
        if c and not d and pair["dense"]["exit"] == "timeout":
            # Lower bounds: the dense run was stopped; its sizes come from its log.
            du = pair["dense"].get("log_unknowns")
            L.append("| %s | ≥ %s× (log) | | > %.0f× (dense stopped at %.0f s) | | | | | %s |"
                     % (name, fmt(ratio(du, c["dofs"]), "%.2f"),
                        pair["dense"]["wall_s"] / times(c)[2], pair["dense"]["wall_s"],
                        "time: yes" if pair["dense"]["wall_s"] / times(c)[2] >= 20 else "?"))
            verdicts.append((name, False))
            continue
        if not c or not d:
            L.append("| %s | a run failed | | | | | | | no |" % name)
            verdicts.append((name, False))
            continue
        rd, rt = ratio(d["dofs"], c["dofs"]), ratio(times(d)[2], times(c)[2])
        rl = ratio(c.get("l2_error"), d.get("l2_error"))
        rs = ratio(c.get("surface_l2_error"), d.get("surface_l2_error"))
        ag = agreement(pair["curved"], pair["dense"])
        pair["agreement"] = ag
        agree = "—" if not ag else "%.2g / %.2g (%d of %d vertices finite)" % (
            ag["rms_rel"], ag["max_rel"], ag["finite"], ag["vertices"])
        if pair.get("reference", {}).get("report"):
            ref = {m: agreement(pair[m], pair["reference"]) for m in ("curved", "dense")}
            pair["agreement_reference"] = ref
            if ref["curved"] and ref["dense"]:
                agree += "; vs the P%d dense reference: curved %.2g / %.2g, dense %.2g / %.2g" % (
                    pair["reference"]["report"]["degree"], ref["curved"]["rms_rel"],
                    ref["curved"]["max_rel"], ref["dense"]["rms_rel"], ref["dense"]["max_rel"])
        # Equal or better error: volume L2 and dense-surface L2 (when there is an exact solution).
        error_ok = None if rl is None else (rl <= 1.0 and (rs is None or rs <= 1.0))
        ref = pair.get("agreement_reference")
        if error_ok is None and ref and ref["curved"] and ref["dense"]:
            error_ok = ref["curved"]["rms_rel"] <= ref["dense"]["rms_rel"]
        # Hyperelasticity without a reference: conforming approximations of the same minimum
        # problem have potential energies above the exact one, so the lower final energy is the
        # better solution in the energy sense (the two domains differ by up to eps).
        ec, ed = final_energy(c), final_energy(d)
        if ec is not None and ed is not None:
            agree += "; final energy curved %.5g, dense %.5g" % (ec, ed)
            if error_ok is None:
                error_ok = ec <= ed
                energy_cases.append(name)
        met = rd >= 50 and rt >= 20 and error_ok is not False
        verdicts.append((name, met))
        L.append("| %s | %.2f× | %.2f× | %.2f× | %.2f× | %s | %s | %s | %s |"
                 % (name, rd, ratio(d["tets"], c["tets"]), rt, ratio(times(d)[3], times(c)[3]),
                    fmt(rl, "%.2f"), fmt(rs, "%.2f"),
                    agree, ("yes" if met else "no") + (
                        "" if error_ok is not None else " (no exact solution or reference: "
                                                        "DOFs, time only)")))
    L.append("")
    L.append("Goal met on %d of %d cases." % (sum(v for _, v in verdicts), len(verdicts)))
    if energy_cases:
        L.append("Error for %s (no exact solution, no dense reference): the lower final potential "
                 "energy counts as the better solution (conforming approximations of the same "
                 "minimum problem lie above the exact energy; the curved domain differs from the "
                 "dense one by up to eps)." % ", ".join(energy_cases))
    L.append("")
    if studies:
        L += study_section(studies)
    L.append("## Runs")
    L.append("")
    for pair in results:
        for m in [m for m in METHODS if m in pair]:
            r = pair[m]
            L.append("- `%s` (exit %s, wall %.1f s)%s — load before: `%s`"
                     % (r["command"].replace(root + "/", ""), r["exit"], r["wall_s"],
                        " *reused*" if r.get("reused") else "", r["uptime"]))
            if r["exit"] not in (0,):
                L.append("  stderr: `%s`" % r["stderr"].replace("\n", " | ")[-600:])
    L.append("")
    L.append("Case variants (absolute paths, dense overrides) and reports are in `%s`."
             % os.path.relpath(args.work, root))
    # A hand-written "## Notes" section at the end of the previous file is kept.
    notes = ""
    if os.path.exists(args.out):
        with open(args.out) as f:
            old = f.read()
        if NOTES_HEADER in old:
            notes = "\n" + old[old.index(NOTES_HEADER):].rstrip() + "\n"
    with open(args.out, "w") as f:
        f.write("\n".join(L) + "\n" + notes)
    with open(os.path.join(args.work, "pipeline_runs.json"), "w") as f:
        json.dump(results, f, indent=1)
    print("wrote %s" % args.out, file=sys.stderr)


main()
