#!/usr/bin/python3
"""SCAF with a tetrahedral scaffold (issue 25, thesis §3.2.3): runs `curvefem deform` and writes
benchmarks/results/deform.md.

Inputs:
  split_ring      a rectangular ring (radii 1..1.4, height 0.4) with a slit of 0.3, its two end
                  caps sent to each other's place by positional targets (written here as OBJ +
                  target file): applied as they are, the ends cross; SCAF must stop them at contact
  split_ring_tangled  the same ring with its end caps already swapped (self-intersecting, genus
                  0), run with --untangle: flowed until embedded, then pulled back toward itself
  <dev> grow S    a dev mesh whose rest shape is S times the input, inside its bounding box padded
                  by (B - 1) / 2 x its longest extent on every side (`--box B`; the thesis'
                  Fig. 3.10 "bunny grown inside a box")
Every iteration's surface is checked for self-intersection by meshing/check (exact) and the final
object + scaffold tets by the exact tiling verifier (report.json); the time per iteration
excludes those checks.

Usage (from the repository root):
  /usr/bin/python3 benchmarks/run_deform.py [--exe build/tools/curvefem/curvefem]
Standard library only.
"""
import argparse
import datetime
import json
import math
import os
import subprocess
import tempfile

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--data", default=os.path.join(root, "../shared/data/dev"))
ap.add_argument("--dev", nargs="*", default=["knight_decimated", "spot", "bunny"])
ap.add_argument("--grow", type=float, default=1.5)
ap.add_argument("--box", type=float, default=1.2)
ap.add_argument("--iterations", type=int, default=30)
ap.add_argument("--every", type=int, default=1,
                help="1: also run every input with the scaffold rebuilt every iteration "
                     "(--rebuild-quality 0, the thesis) to compare with the default; 0: not")
ap.add_argument("--extra", default="",
                help="more `curvefem deform` options for every run, e.g. --extra=--sliver-rests")
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/deform.md"))
args = ap.parse_args()


def split_ring(r_in, r_out, height, gap, n):
    """The same ring as meshing/core/adversarial.cpp's make_split_ring, outward."""
    delta = math.asin(0.5 * gap / r_in)
    prof = [(r_in, 0), (r_out, 0), (r_out, height), (r_in, height)]
    V = []
    for i in range(n + 1):
        a = delta + (2 * math.pi - 2 * delta) * i / n
        for r, z in prof:
            V.append((r * math.cos(a), r * math.sin(a), z))
    F = []
    for i in range(n):
        for j in range(4):
            a, b = 4 * i + j, 4 * i + (j + 1) % 4
            c, d = 4 * (i + 1) + (j + 1) % 4, 4 * (i + 1) + j
            F += [(a, b, c), (a, c, d)]
    e = 4 * n
    F += [(0, 2, 1), (0, 3, 2), (e, e + 1, e + 2), (e, e + 2, e + 3)]
    vol = sum(V[f[0]][0] * (V[f[1]][1] * V[f[2]][2] - V[f[1]][2] * V[f[2]][1]) -
              V[f[0]][1] * (V[f[1]][0] * V[f[2]][2] - V[f[1]][2] * V[f[2]][0]) +
              V[f[0]][2] * (V[f[1]][0] * V[f[2]][1] - V[f[1]][1] * V[f[2]][0]) for f in F)
    if vol < 0:
        F = [(a, c, b) for a, b, c in F]
    return V, F


def run(name, inp, extra, work):
    out = os.path.join(work, name + ".obj")
    rep = os.path.join(work, name + ".json")
    cmd = [args.exe, "deform", "-q", inp, "-o", out, "--iterations", str(args.iterations),
           "--report", rep] + extra + args.extra.split()
    p = subprocess.run(cmd, capture_output=True, text=True)
    r = json.load(open(rep)) if os.path.exists(rep) else {}
    return {"name": name, "cmd": " ".join(cmd[1:]).replace(work + "/", ""), "exit": p.returncode,
            "report": r, "stderr": p.stderr.strip()[-300:], "inp": inp, "extra": extra}


rows = []
with tempfile.TemporaryDirectory() as work:
    n = 32
    V, F = split_ring(1.0, 1.4, 0.4, 0.3, n)
    ring = os.path.join(work, "split_ring_in.obj")
    with open(ring, "w") as f:
        for v in V:
            f.write("v %.17g %.17g %.17g\n" % v)
        for t in F:
            f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))
    targets = os.path.join(work, "targets.txt")
    with open(targets, "w") as f:
        for k in range(4):
            a, b = k, 4 * n + k
            f.write("%d %.17g %.17g %.17g\n" % ((a,) + V[b]))
            f.write("%d %.17g %.17g %.17g\n" % ((b,) + V[a]))
    rows.append(run("split_ring", ring, ["--targets", targets], work))
    tangled = os.path.join(work, "split_ring_tangled_in.obj")
    T = list(V)
    for k in range(4):
        T[k], T[4 * n + k] = V[4 * n + k], V[k]
    with open(tangled, "w") as f:
        for v in T:
            f.write("v %.17g %.17g %.17g\n" % v)
        for t in F:
            f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))
    rows.append(run("split_ring_tangled", tangled, ["--untangle"], work))
    # The thesis' way back (Fig. 3.9): no positional targets, the surface ARAP term alone.
    rows.append(run("split_ring_tangled_arap", tangled,
                    ["--untangle", "--arap", "1000", "--no-way-back-targets"], work))
    for name in args.dev:
        path = os.path.join(args.data, name + ".obj")
        if not os.path.exists(path):
            print("skipping %s: %s not found" % (name, path))
            continue
        rows.append(run("%s_grow" % name, path,
                        ["--grow", str(args.grow), "--box", str(args.box)], work))
    every = []
    if args.every:
        for row in list(rows):
            every.append(run(row["name"] + "_every", row["inp"],
                             row["extra"] + ["--rebuild-quality", "0"], work))
    for row in rows + every:
        print(row["name"], row["exit"], row["report"].get("valid"), row["stderr"])

lines = ["# SCAF with a tetrahedral scaffold — `curvefem deform` (issue 25, thesis §3.2.3)", ""]
lines.append("Written by `benchmarks/run_deform.py` on %s UTC, 2-core machine. Command: "
             "`/usr/bin/python3 benchmarks/run_deform.py` (defaults: --iterations %d, dev meshes "
             "grown %g× inside their bounding box padded by (%g − 1) / 2 × its longest extent)." %
             (datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M"), args.iterations, args.grow,
              args.box))
lines.append("")
lines.append("Self-intersecting pairs: exact (meshing/check) on the surface after every iteration "
             "(max over iterations) and at the end; naive: the targets applied as they are. "
             "Non-positive tets: exact orientation of every object and scaffold tet of the final "
             "tiling (meshing/tetfill's verifier), which also checks both meshes' boundary "
             "chains. E = objective, E_M = the object's volume-weighted mean symmetric Dirichlet "
             "energy (6 for a rigid motion of the rest shape). Target error: max distance to a "
             "target / box diagonal.")
lines.append("")
lines.append("| input | faces | object tets | scaffold tets | it. (stop) | E first → last | E_M last "
             "| target error first → last | σ min / max | self-int. pairs (max over it.) | naive "
             "| non-positive tets | valid | s/it (scaffold, assemble, solve) | total s |")
lines.append("|" + "---|" * 15)
for row in rows:
    r = row["report"]
    if not r:
        lines.append("| %s | failed (exit %d): %s |" % (row["name"], row["exit"], row["stderr"]))
        continue
    h = r["history"]
    it = max(1, r["iterations"])
    mean = lambda k: sum(x["time_s"][k] for x in h[1:]) / it
    lines.append(
        "| %s | %d | %d | %d | %d (%s) | %.4g → %.4g | %.4g | %.3g → %.3g | %.3g / %.3g | %d (%d) | %s "
        "| %d | %s | %.2f (%.2f, %.2f, %.2f) | %.1f |" %
        (row["name"], r["faces"], r["object_tets"], r["scaffold_tets"], r["iterations"],
         r["stop_reason"], r["initial_objective"], r["objective"], r["energy"],
         r["initial_target_error_rel"], r["target_error_rel"], r["min_singular_value"],
         r["max_singular_value"], r["self_intersecting_pairs"],
         r["max_self_intersecting_pairs_over_iterations"],
         "–" if r["naive_self_intersecting_pairs"] is None else r["naive_self_intersecting_pairs"],
         r["non_positive_tets"], "yes" if r["valid"] else "NO", r["time_s"]["per_iteration"],
         mean("scaffold"), mean("assemble"), mean("solve"), r["time_s"]["total"]))
lines.append("")
unt = [row for row in rows if row["report"].get("untangle")]
if unt:
    lines.append("With --untangle (naive = the input's own self-intersecting pairs): the flow, and "
                 "the distance of the result to the input (/ the input's bounding box diagonal). "
                 "Way back: positional targets at every vertex (the default), or the surface ARAP "
                 "term alone (`--arap W --no-way-back-targets`, the thesis' way). Edge length "
                 "error: |l - l0| / l0 over the surface edges against the input (its shape).")
    lines.append("")
    lines.append("| input | way back | input pairs | flow steps | pairs after each flow step | "
                 "flow s | max distance | mean distance | edge length error mean / max |")
    lines.append("|---|---|---|---|---|---|---|---|---|")
    for row in unt:
        u = row["report"]["untangle"]
        way = ("targets" if u.get("way_back_targets", True) else "ARAP") + (
            " + ARAP %g" % row["report"]["arap_weight"]
            if u.get("way_back_targets", True) and row["report"].get("arap_weight", 0) > 0 else
            " %g" % row["report"]["arap_weight"] if not u.get("way_back_targets", True) else "")
        lines.append("| %s | %s | %d | %d | %s | %.3f | %.3g | %.3g | %.3g / %.3g |" %
                     (row["name"], way, u["input_self_intersecting_pairs"], u["flow_steps"],
                      ", ".join(map(str, u["pairs_after_each_flow_step"])), u["flow_s"],
                      u["max_distance_to_input_rel"], u["mean_distance_to_input_rel"],
                      u["edge_length_error_mean"], u["edge_length_error_max"]))
    lines.append("")
if every:
    lines.append("The scaffold rebuilt every iteration (`--rebuild-quality 0`, the thesis) against "
                 "the default, which keeps the moved scaffold while its worst tet shape "
                 "(6√2 V / l_rms³) stays at least 0.5 × that of the last rebuild. Same inputs and "
                 "options; every run checked the same way.")
    lines.append("")
    lines.append("| input | it. (stop) every / default | rebuilds kept | E last every / default | "
                 "E_M last every / default | target error last every / default | valid every / "
                 "default | total s every / default | ratio |")
    lines.append("|---|---|---|---|---|---|---|---|---|")
    for b, a in zip(rows, every):
        ra, rb = a["report"], b["report"]
        if not ra or not rb:
            lines.append("| %s | failed (exit %d / %d) |" % (b["name"], a["exit"], b["exit"]))
            continue
        lines.append("| %s | %d (%s) / %d (%s) | %d of %d | %.6g / %.6g | %.6g / %.6g | %.3g / %.3g "
                     "| %s / %s | %.1f / %.1f | %.2f |" % (
                         b["name"], ra["iterations"], ra["stop_reason"], rb["iterations"],
                         rb["stop_reason"], rb["scaffold_kept"], max(0, rb["iterations"] - 1),
                         ra["objective"], rb["objective"], ra["energy"], rb["energy"],
                         ra["target_error_rel"], rb["target_error_rel"],
                         "yes" if ra["valid"] else "NO", "yes" if rb["valid"] else "NO",
                         ra["time_s"]["total"], rb["time_s"]["total"],
                         rb["time_s"]["total"] / ra["time_s"]["total"]))
    lines.append("")
lines.append("Commands (paths relative to the temporary work folder):")
lines.append("")
for row in rows + every:
    lines.append("    curvefem %s" % row["cmd"])
lines.append("")
with open(args.out, "w") as f:
    f.write("\n".join(lines) + "\n")
print("wrote", args.out)
