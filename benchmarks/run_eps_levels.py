#!/usr/bin/python3
"""ε levels from one coarsening against one `curvefem mesh` per ε (issue 22, "one coarsening,
many meshes"), on dev meshes.

For every mesh it runs, in one run:
  levels    `curvefem mesh INPUT -o DIR --order K --eps-levels E1,E2,... -q --threads T`
            (the shell is built once, the finest level coarsens it, every coarser level resumes
            from the finer level's coarse shell)
  separate  `curvefem mesh INPUT -o DIR --order K --eps Ei -q --threads T` for every level
The two alternate which goes first from mesh to mesh. Times are whole-process wall times; the
per-level figures of the levels run come from its levels.json, every validity figure from the
reports' independent validation.

Usage (from the repository root):
  /usr/bin/python3 benchmarks/run_eps_levels.py [--meshes spot.obj ...] [--levels 0.04 0.02 0.01
      0.005] [--order 3] [--threads 2] [--timeout 900] [--exe build/tools/curvefem/curvefem]
      [--note TEXT]
Writes benchmarks/results/eps_levels.md. Standard library only.
"""
import argparse
import datetime
import json
import os
import shlex
import shutil
import subprocess
import sys
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--data", default="/work/shared/data/dev")
ap.add_argument("--meshes", nargs="+",
                default=["spot.obj", "fandisk.obj", "bunny.obj", "rocker_arm.obj",
                         "fertility.obj", "armadillo.obj"])
ap.add_argument("--levels", nargs="+", type=float, default=[0.04, 0.02, 0.01, 0.005])
ap.add_argument("--order", type=int, default=3)
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--timeout", type=float, default=900)
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/eps_levels.md"))
ap.add_argument("--work", default="/tmp/eps_levels_bench")
ap.add_argument("--note", default="")
args = ap.parse_args()
command = "/usr/bin/python3 " + " ".join(
    shlex.quote(a) for a in ["benchmarks/run_eps_levels.py"] + sys.argv[1:])


def run(cmd):
    start = time.time()
    try:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           timeout=args.timeout)
        code = p.returncode
    except subprocess.TimeoutExpired:
        code = "timeout"
    return code, time.time() - start


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def fmt(x, spec=".3g"):
    return "-" if x is None else format(x, spec)


os.makedirs(args.work, exist_ok=True)
name_of = {e: "eps_%g" % e for e in args.levels}
rows = []
for i, mesh in enumerate(args.meshes):
    src = os.path.join(args.data, mesh)
    base = os.path.join(args.work, os.path.splitext(mesh)[0])
    shutil.rmtree(base, ignore_errors=True)
    common = ["-q", "--order", str(args.order), "--threads", str(args.threads)]

    def levels_run():
        cmd = [args.exe, "mesh", src, "-o", base + "/levels",
               "--eps-levels", ",".join("%g" % e for e in args.levels)] + common
        return run(cmd)

    def separate_runs():
        out = {}
        for e in args.levels:
            out[e] = run([args.exe, "mesh", src, "-o", base + "/" + name_of[e], "--eps",
                          "%g" % e] + common)
        return out

    if i % 2 == 0:
        lv = levels_run()
        sep = separate_runs()
    else:
        sep = separate_runs()
        lv = levels_run()
    summary = load(base + "/levels/levels.json") or {}
    per = {l["eps_rel"]: l for l in summary.get("levels", [])}
    input_faces = None
    for e in args.levels:
        rep = load(base + "/" + name_of[e] + "/report.json") or {}
        lrep = load(base + "/levels/" + name_of[e] + "/report.json") or {}
        input_faces = input_faces or rep.get("input_faces") or lrep.get("input_faces")
        l = per.get(e, {})
        rows.append({
            "mesh": os.path.splitext(mesh)[0], "eps": e,
            "levels_code": lv[0], "levels_total_s": lv[1],
            "levels_faces": l.get("coarse_faces"), "levels_valid": l.get("valid"),
            "levels_start": l.get("coarsen_start_faces"),
            "levels_s": l.get("seconds"), "levels_coarsen_s": l.get("coarsen_seconds"),
            "levels_min_sj": l.get("min_scaled_jacobian"),
            "sep_code": sep[e][0], "sep_s": sep[e][1],
            "sep_faces": rep.get("coarse_faces"), "sep_valid": rep.get("valid"),
            "sep_min_sj": rep.get("min_scaled_jacobian"),
            "input_faces": input_faces,
        })
    print(mesh, "levels", lv, "separate", {e: sep[e] for e in args.levels}, flush=True)

lines = [
    "# ε levels from one coarsening against one run per ε (issue 22)", "",
    "Generated %s by `%s` on %d cores; order %d, %d threads. %s" % (
        datetime.datetime.now().strftime("%Y-%m-%d %H:%M"), command, os.cpu_count(), args.order,
        args.threads, args.note), "",
    "levels = one `curvefem mesh --eps-levels %s` (shell built once, finest level coarsened "
    "from it, each coarser level resumed from the finer one's coarse shell); separate = one "
    "`curvefem mesh --eps E` per level. level s = that level's meshing + validation + output "
    "(levels.json); separate s = whole process. start = coarse faces the level resumed from "
    "(0: the input's shell). valid, faces, min SJ: report.json (independent validator)." % (
        ",".join("%g" % e for e in args.levels)), "",
    "| mesh | input faces | eps | faces levels / separate | start | valid | min SJ levels / "
    "separate | level s | separate s |",
    "|---|---|---|---|---|---|---|---|---|"]
totals = {}
for r in rows:
    valid = "%s / %s" % ("yes" if r["levels_valid"] else "NO (%s)" % r["levels_code"],
                         "yes" if r["sep_valid"] else "NO (%s)" % r["sep_code"])
    lines.append("| %s | %s | %g | %s / %s | %s | %s | %s / %s | %s | %.1f |" % (
        r["mesh"], r["input_faces"], r["eps"], r["levels_faces"], r["sep_faces"],
        r["levels_start"], valid, fmt(r["levels_min_sj"]), fmt(r["sep_min_sj"]),
        fmt(r["levels_s"], ".1f"), r["sep_s"]))
    t = totals.setdefault(r["mesh"], {"levels": r["levels_total_s"], "separate": 0.0,
                                      "finest": None})
    t["separate"] += r["sep_s"]
lines += ["", "| mesh | levels run s (all %d levels) | separate runs s (sum) | ratio |" %
          len(args.levels), "|---|---|---|---|"]
for mesh, t in totals.items():
    lines.append("| %s | %.1f | %.1f | %.2f |" % (mesh, t["levels"], t["separate"],
                                                  t["separate"] / t["levels"]))
ok_levels = sum(1 for r in rows if r["levels_valid"])
ok_sep = sum(1 for r in rows if r["sep_valid"])
lines += ["", "- Valid: levels %d of %d, separate %d of %d." % (ok_levels, len(rows), ok_sep,
                                                                 len(rows))]
with open(args.out, "w") as f:
    f.write("\n".join(lines) + "\n")
print("wrote", args.out)
