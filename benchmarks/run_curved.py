#!/usr/bin/python3
"""Curved-mesher benchmark over the dev meshes (/work/shared/data/dev/MANIFEST.tsv).

For every mesh and order K it runs `curvefem mesh INPUT -o DIR --order K --eps EPS -q --threads T`
(timeout per run), reads DIR/report.json (every guarantee in it comes from the independent
validator), and records the exit code (0 valid, 3 a guarantee failed, 2 bad input, other =
crash / timeout), wall time and peak RSS. The dense-linear baseline (the input itself
tetrahedralized with its boundary unchanged) is counted with `tetfill_tool` when it is built.
The authors' reference implementation (bichon) was measured on this kind of machine for four of
the meshes (reference-notes/bichon-measured.md); its numbers are printed beside ours.

Usage (from the repository root):
  /usr/bin/python3 benchmarks/run_curved.py [--meshes spot.obj ...] [--orders 3 4] [--eps 0.01]
      [--threads 2] [--timeout 900] [--exe build/tools/curvefem/curvefem]
Writes benchmarks/results/curved.md; raw JSON lines go to /tmp/curved_runs.jsonl.
Standard library only.
"""
import argparse
import datetime
import json
import math
import os
import resource
import shlex
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from curved_stages import coarsening_seconds  # noqa: E402

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--data", default="/work/shared/data/dev")
ap.add_argument("--meshes", nargs="+")
ap.add_argument("--orders", nargs="+", type=int, default=[3, 4])
ap.add_argument("--eps", type=float, default=0.01)
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--timeout", type=float, default=900)
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--tetfill-tool", default=None)
ap.add_argument("--exterior", action="store_true",
                help="mesh with --exterior too (outer slab layer and the region out to the padded "
                     "box); tets then count all four parts")
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/curved.md"))
ap.add_argument("--work", default="/tmp/curved_bench")
ap.add_argument("--render-from", metavar="JSONL",
                help="run nothing: render --out from these raw records (the last record per mesh "
                     "and order wins)")
args = ap.parse_args()
command = "/usr/bin/python3 " + " ".join(shlex.quote(a) for a in ["benchmarks/run_curved.py"] + sys.argv[1:])

# reference-notes/bichon-measured.md: P4 tets (cubic surface), eps 1e-2, 2 threads, this machine type.
BICHON = {
    "knight_decimated": dict(seconds=161.7, rss=237, tets=2191, tris=656),
    "spot": dict(seconds=152.8, rss=130, tets=1207, tris=356),
    "bunny": dict(seconds=169.4, rss=174, tets=1992, tris=564),
    "fandisk": dict(seconds=177.0, rss=187, tets=676, tris=312),
}


def manifest():
    with open(os.path.join(args.data, "MANIFEST.tsv")) as f:
        rows = [l.rstrip("\n").split("\t") for l in f if l.strip()]
    return [dict(zip(rows[0], r)) for r in rows[1:]]


def run(cmd, timeout):
    start = time.time()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        out, err = p.communicate(timeout=timeout)
        code = p.returncode
    except subprocess.TimeoutExpired:
        p.kill()
        out, err = p.communicate()
        code = "timeout"
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return code, time.time() - start, out, err, usage.ru_maxrss / 1024.0


def dense_baseline(path):
    tool = args.tetfill_tool or os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(
        args.exe))), "benchmarks/tetfill_tool")
    if not os.path.exists(tool):
        return None
    code, secs, out, err, _ = run([tool, path], args.timeout)
    if code != 0:
        return {"failed": str(code), "message": (err or out).strip().splitlines()[-1:]}
    try:
        return json.loads(out.strip().splitlines()[-1])
    except (ValueError, IndexError):
        return None


def main():
    if args.render_from:
        latest = {}
        with open(args.render_from) as f:
            for line in f:
                if line.strip():
                    r = json.loads(line)
                    latest[(r["mesh"], r["order"])] = r
        order = {os.path.splitext(m["file"])[0]: i for i, m in enumerate(manifest())}
        render(sorted(latest.values(), key=lambda r: (order.get(r["mesh"], 1 << 30), r["order"])))
        return
    meshes = [m["file"] for m in manifest()]
    if args.meshes:
        meshes = [m for m in meshes if m in args.meshes]
    os.makedirs(args.work, exist_ok=True)
    records = []
    raw = open("/tmp/curved_runs%s.jsonl" % ("_exterior" if args.exterior else ""), "a")
    for mesh in meshes:
        name = os.path.splitext(mesh)[0]
        path = os.path.join(args.data, mesh)
        base = dense_baseline(path)
        for k in args.orders:
            out_dir = os.path.join(args.work, "%s_k%d" % (name, k))
            subprocess.run(["rm", "-rf", out_dir])
            load = os.getloadavg()[0]
            code, secs, out, err, rss = run([args.exe, "mesh", path, "-o", out_dir, "--order",
                                            str(k), "--eps", str(args.eps), "-q", "--threads",
                                            str(args.threads)] +
                                           (["--exterior"] if args.exterior else []), args.timeout)
            rep = None
            try:
                with open(os.path.join(out_dir, "report.json")) as f:
                    rep = json.load(f)
            except (OSError, ValueError):
                pass
            rec = dict(mesh=name, order=k, exit=code, wall=secs, load=load, report=rep,
                       dense=base, error=(err.strip().splitlines() or [""])[-1])
            records.append(rec)
            raw.write(json.dumps(rec) + "\n")
            raw.flush()
            print("%-22s k=%d exit=%s %.1fs %s" % (name, k, code, secs,
                  "" if rep else rec["error"]), flush=True)
    render(records)


def fmt(x, f="%.3g"):
    return "–" if x is None else (f % x)


def render(records):
    w = []
    w.append("# Curved meshing benchmark (issue 6)%s\n" % (", with `--exterior`" if args.exterior
                                                            else ""))
    w.append("Generated %s by `%s` at commit %s, on %d cores; eps = %g of the longest bbox edge, "
             "%d threads.\n" % (datetime.datetime.now().strftime("%Y-%m-%d %H:%M"), command,
                                subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"],
                                               capture_output=True, text=True).stdout.strip(),
                                os.cpu_count(), args.eps, args.threads))
    w.append("Every figure below comes from the run's report.json, whose guarantees are computed "
             "by the independent validator (certified det J per tet, boundary faces, embedding "
             "of the subdivided curved boundary, distance at every input vertex). `valid` = all "
             "hold. Dense = the input itself tetrahedralized with its boundary unchanged "
             "(tetfill_tool); ratio = dense tets / curved tets; dense s = Gmsh's tetrahedralization "
             "of the input in that tool (its `gmsh_seconds`, same run), time / dense = the whole "
             "`curvefem mesh` run (curving, validation and map roundtrip included) over it.\n")
    w.append("time s (coarsening): the whole run, and in parentheses the coarsening with every "
             "attempt it took: the stages `coarsen`, `coarsen (linear phase)`, `repair`, "
             "`repair (failed)` and each `discarded attempt N` (a discarded attempt's curving and "
             "checks included).\n")
    w.append("| mesh | K | exit | valid | input F | boundary F | tets (slab+interior%s) | dense tets | "
             % ("+outer slab+exterior" if args.exterior else "") +
             "ratio | dense s | max dist | min sJ slab / interior%s | mean MIPS | time s (coarsening) | time / dense | "
             % (" / outer slab / exterior" if args.exterior else "") +
             "RSS MB | load |")
    w.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    ok = 0
    times = []
    for r in records:
        rep = r["report"] or {}
        val = rep.get("validation", {})
        q = val.get("quality_by_tag", {})
        dense = (r["dense"] or {}).get("tets")
        tets = rep.get("output_tets")
        valid = rep.get("valid")
        ok += bool(valid and r["exit"] == 0)
        if rep:
            times.append(rep["time_s"]["total"])
        dense_s = (r["dense"] or {}).get("gmsh_seconds")
        total_s = rep.get("time_s", {}).get("total")
        w.append("| %s | %d | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s / %s | %s | %s (%s) | %s | %s | %.1f |" % (
            r["mesh"], r["order"], r["exit"], "yes" if valid else "NO",
            rep.get("input_faces", "–"), rep.get("output_boundary_faces", "–"),
            ("%s (%s+%s+%s+%s)" % (tets, rep.get("slab_tets"), rep.get("interior_tets"),
                                   rep.get("outer_slab_tets"), rep.get("exterior_tets"))
             if rep.get("exterior") else
             "%s (%s+%s)" % (tets, rep.get("slab_tets"), rep.get("interior_tets"))) if tets else "–",
            dense or "–",
            fmt(dense / tets, "%.1f") if dense and tets and not rep.get("exterior") else "–",
            fmt(dense_s, "%.2f"),
            fmt(rep.get("max_distance_rel")),
            fmt(q.get("slab", {}).get("min_scaled_jacobian")),
            fmt(q.get("interior", {}).get("min_scaled_jacobian")) + (
                " / %s / %s" % (fmt(q.get("outer_slab", {}).get("min_scaled_jacobian")),
                                fmt(q.get("exterior", {}).get("min_scaled_jacobian")))
                if rep.get("exterior") else ""),
            fmt(val.get("mean_mips"), "%.0f"),
            fmt(rep.get("time_s", {}).get("total"), "%.1f"),
            fmt(coarsening_seconds(rep), "%.1f"),
            fmt(total_s / dense_s, "%.1f") if total_s and dense_s else "–",
            fmt(rep.get("peak_rss_mb"), "%.0f"), r["load"]))
    w.append("")
    w.append("- Valid runs: %d of %d." % (ok, len(records)))
    if times:
        w.append("- Median total time: %.1f s (goal: under 60 s)." % statistics.median(times))
    # The 10x goal, per order; and how time grows with input size: the least-squares slope of
    # log(time) over log(input faces) (1 = linear).
    for k in args.orders:
        ratios = [(r["mesh"], r["dense"]["tets"] / r["report"]["output_tets"]) for r in records
                  if r["order"] == k and r["report"] and not r["report"].get("exterior")
                  and (r["dense"] or {}).get("tets")
                  and r["report"].get("output_tets")]
        against = [(r["mesh"], r["report"]["time_s"]["total"] / r["dense"]["gmsh_seconds"])
                   for r in records
                   if r["order"] == k and r["report"] and r["report"].get("input_faces", 0) >= 10000
                   and (r["dense"] or {}).get("gmsh_seconds")]
        if against:
            fast = [m for m, x in against if x <= 1]
            w.append("- K = %d, inputs of >= 10k faces: the curved run took %.1f-%.1fx Gmsh's dense "
                     "tetrahedralization (median %.1fx); no slower on %d of %d (%s)."
                     % (k, min(x for _, x in against), max(x for _, x in against),
                        statistics.median(x for _, x in against), len(fast), len(against),
                        ", ".join(fast) or "none"))
        if ratios:
            met = [m for m, x in ratios if x >= 10]
            w.append("- K = %d: tets >= 10x below the dense-linear baseline on %d of %d meshes (%s)."
                     % (k, len(met), len(ratios), ", ".join(met) or "none"))
        pts = [(math.log(r["report"]["input_faces"]), math.log(r["report"]["time_s"][key]))
               for r in records if r["order"] == k and r["report"]
               for key in ["total"] if r["report"]["time_s"].get(key, 0) > 0]
        cpts = [(math.log(r["report"]["input_faces"]), math.log(r["report"]["time_s"]["coarsen"]))
                for r in records if r["order"] == k and r["report"]
                and r["report"]["time_s"].get("coarsen", 0) > 0]
        def slope(p):
            n = len(p)
            mx, my = sum(a for a, _ in p) / n, sum(b for _, b in p) / n
            sxx = sum((a - mx) ** 2 for a, _ in p)
            return sum((a - mx) * (b - my) for a, b in p) / sxx if sxx > 0 else float("nan")
        if len(pts) >= 3:
            w.append("- K = %d: time ~ (input faces)^%.2f over the %d runs (least squares on "
                     "log-log; 1 = linear); the coarsening alone (kept attempt) ^%.2f."
                     % (k, slope(pts), len(pts), slope(cpts) if len(cpts) >= 3 else float("nan")))
    # Why coarsening stopped: the collapses the shell refused, by the first failed check.
    why_rows = []
    for r in records:
        refused = ((r["report"] or {}).get("coarsening") or {}).get("collapses_refused")
        if r["order"] != min(args.orders) or not refused:
            continue
        total = sum(refused.values())
        top = sorted(refused.items(), key=lambda kv: -kv[1])
        why_rows.append("| %s | %d | %s |" % (r["mesh"], total, ", ".join(
            "%s %.0f%%" % (k, 100.0 * v / total) for k, v in top if total and v > 0.05 * total)))
    if why_rows:
        w.append("\n## Why coarsening stopped (K = %d)\n" % min(args.orders))
        w.append("Collapses the coarsening refused, by the first check that failed "
                 "(`coarsening.collapses_refused` in report.json; attempts, not distinct edges: "
                 "an edge is tried again in every round). shape = the coarse triangle MIPS bound "
                 "(10); distance = the eps bound at an input vertex; positivity / intersection / "
                 "section = shell invariants I1 / I3 / I2 of a new prism; coverage = an input "
                 "face left without a prism. Reasons above 5% are listed.\n")
        w.append("| mesh | refused | main reasons |")
        w.append("|---|---|---|")
        w += why_rows
    # How much of the boundary is curved: faces at full curving, blended toward the linear
    # triangle, or linear; why step 3 refused full curving; how many faces the deeper slab layer
    # let curve again; coarsening pans and splits.
    curve_rows = []
    for r in records:
        rep = r["report"] or {}
        if "faces_fully_curved" not in rep or r["order"] == 1:
            continue
        refused = rep.get("curve_refused") or {}
        co = rep.get("coarsening") or {}
        attempts = co.get("curved_attempts")
        if attempts is None:
            attempts = "–"
        elif not co.get("curved_aware"):
            attempts = "%d (linear)" % attempts
        elif co.get("curved_widened"):
            attempts = "%d (widened)" % attempts
        curve_rows.append("| %s | %d | %s / %s / %s | %s / %s | %s | %s | %s | %s |" % (
            r["mesh"], r["order"], rep.get("faces_fully_curved"), rep.get("faces_blended"),
            rep.get("faces_linear"), refused.get("certificate", "–"),
            refused.get("distance", "–"), rep.get("faces_recurved", "–"), co.get("pans", "–"),
            co.get("splits", "–"), attempts))
    if curve_rows:
        w.append("\n## Curving\n")
        w.append("Boundary faces at full curving (α = 1) / blended toward the linear triangle / "
                 "linear, counted after the thicken step; the faces whose full curving was "
                 "refused on the shell's own slabs, because a slab tet was not certified positive "
                 "or an input vertex was farther than eps (`curve_refused`); the faces the deeper "
                 "slab layer let curve again (`faces_recurved`); coarsening pans and splits; the "
                 "curved-aware attempt kept (`coarsening.curved_attempts`; (linear) = every "
                 "curved-aware attempt discarded, (widened) = the linear-bound set was widened "
                 "around slabs pulled above the shell's base).\n")
        w.append("| mesh | K | curved / blended / linear | refused: certificate / distance | "
                 "recurved | pans | splits | attempt |")
        w.append("|---|---|---|---|---|---|---|---|")
        w += curve_rows
    w.append("\n## Beside the reference implementation (bichon, P4 tets, measured here)\n")
    w.append("| mesh | bichon s | bichon tets | bichon surface tris | curvefem K=4 s | curvefem K=4 tets | "
             "curvefem boundary tris | speed ratio |")
    w.append("|---|---|---|---|---|---|---|---|")
    for r in records:
        if r["order"] != 4 or r["mesh"] not in BICHON or not r["report"]:
            continue
        b, rep = BICHON[r["mesh"]], r["report"]
        t = rep["time_s"]["total"]
        w.append("| %s | %.1f | %d | %d | %.1f | %d | %d | %.1f× |" % (
            r["mesh"], b["seconds"], b["tets"], b["tris"], t, rep["output_tets"],
            rep["output_boundary_faces"], b["seconds"] / t))
    w.append("\nThe bichon numbers are from reference-notes/bichon-measured.md (same machine type, "
             "not the same run).")
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w") as f:
        f.write("\n".join(w) + "\n")
    print("wrote", args.out)


if __name__ == "__main__":
    main()
