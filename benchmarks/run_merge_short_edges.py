#!/usr/bin/python3
"""Input floors removed by merging short edges (issue 21): for every surface, `curvefem check IN
--merge-short-edges L -o MERGED` (meshing/check/merge_short_edges.hpp), then `curvefem mesh` of the
input and of the merged surface at each order, side by side in one run, and the quality numbers
of both report.json files (the independent validator's): max curved MIPS, min scaled Jacobian,
tets below 0.01, the input needles and folds the boundary kept (input_floors), and whether issue
21's quality goal holds (min SJ >= 1e-3, <= 1% of tets below 0.01, max MIPS <= 1e4).

Usage (from the repository root):
  /usr/bin/python3 benchmarks/run_merge_short_edges.py --inputs FILE:L [FILE:L ...]
      [--orders 3 4] [--threads 1] [--exe build/tools/curvefem/curvefem] [--work DIR] [--out MD]
L is the merge length relative to the bounding box's longest edge (ε is 0.01 of it by default).
Standard library only.
"""
import argparse
import datetime
import json
import os
import shlex
import subprocess
import sys
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--inputs", nargs="+", required=True, metavar="FILE:L")
ap.add_argument("--orders", nargs="+", type=int, default=[3, 4])
ap.add_argument("--threads", type=int, default=1)
ap.add_argument("--timeout", type=float, default=900)
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--work", default="/tmp/merge_short_edges")
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/merge_short_edges.md"))
args = ap.parse_args()
command = "/usr/bin/python3 " + " ".join(
    shlex.quote(a) for a in ["benchmarks/run_merge_short_edges.py"] + sys.argv[1:])
os.makedirs(args.work, exist_ok=True)


def run(cmd):
    t0 = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
    return p.returncode, time.time() - t0, p.stdout, p.stderr


def goal(v):
    tets = v["tets"]
    return (v["min_scaled_jacobian"] >= 1e-3 and v["max_mips"] <= 1e4 and
            v["tets_scaled_jacobian_below_0.01"] <= 0.01 * tets)


rows, merges = [], []
for spec in args.inputs:
    path, length = spec.rsplit(":", 1)
    name = os.path.splitext(os.path.basename(path))[0]
    merged = os.path.join(args.work, f"{name}_L{length}_merged.obj")
    code, _, out, err = run([args.exe, "check", "-q", "--json", path, "--merge-short-edges",
                             length, "-o", merged])
    report = json.loads(out[out.find("{"):]) if "{" in out else {}
    m = report.get("merge_short_edges", {})
    merges.append((name, length, code, m, report.get("warnings", [])))
    for k in args.orders:
        for kind, surface in (("input", path), ("merged", merged)):
            if kind == "merged" and code != 0:
                continue
            d = os.path.join(args.work, f"{name}_{kind if kind == 'input' else 'L' + length}_{k}")
            if kind == "input" and any(r["name"] == name and r["kind"] == "input" and r["K"] == k
                                       for r in rows):
                continue  # the same input with another L
            rc, secs, _, err = run([args.exe, "mesh", surface, "-o", d, "--order", str(k), "-q",
                                    "--threads", str(args.threads)])
            row = {"name": name, "kind": kind if kind == "input" else f"merged, L = {length}",
                   "K": k, "exit": rc, "s": secs}
            if rc == 0 or os.path.exists(os.path.join(d, "report.json")):
                with open(os.path.join(d, "report.json")) as f:
                    j = json.load(f)
                v = j["validation"]
                fl = j.get("input_floors", {})
                row.update(valid=j["valid"], tets=v["tets"], max_mips=v["max_mips"],
                           min_sj=v["min_scaled_jacobian"],
                           below=v["tets_scaled_jacobian_below_0.01"], goal=goal(v),
                           kept=f"{fl.get('needle_faces_kept', '?')} / "
                                f"{fl.get('near_fold_edges_kept', '?')}",
                           worst_on_kept=fl.get("worst_mips_tet_at_kept") or
                           fl.get("worst_scaled_jacobian_tet_at_kept"))
            else:
                row["error"] = err.strip().splitlines()[-1] if err.strip() else ""
            rows.append(row)
            print(json.dumps(row), flush=True)

now = datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M UTC")
head = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"], capture_output=True,
                      text=True).stdout.strip()
lines = [
    "# Input floors removed by merging short edges (issue 21)", "",
    f"Generated {now} by `{command}`; HEAD {head}; {os.cpu_count()} cores; ε = 0.01, "
    f"`curvefem mesh IN -o DIR --order K -q --threads {args.threads}` on the input and on "
    "`curvefem check IN --merge-short-edges L -o MERGED` (meshing/check/merge_short_edges.hpp), "
    "one run each, side by side.", "",
    "## The merges", "",
    "| surface | L (bbox) | short edges | merged | left | longest merged | check of the result |",
    "|---|---|---|---|---|---|---|"]
for name, length, code, m, warnings in merges:
    warn = ", ".join(f"{w['count']} {w['kind']}" for w in warnings) or "no warning"
    lines.append(f"| {name} | {length} | {m.get('candidates', '')} | {m.get('merged', '')} | "
                 f"{m.get('left', '')} | {m.get('max_moved', 0):.3g} | "
                 f"{'acceptable' if code == 0 else 'not acceptable (exit %d)' % code}; "
                 f"{warn} |")
lines += ["", "## Meshes of the input and of the merged surface", "",
          "kept = input needles / near folds the curved boundary kept as they are "
          "(report.json input_floors); on kept = the mesh's worst tet (by MIPS or by SJ) is on "
          "one; goal = issue 21's quality goal.", "",
          "| surface | K | surface meshed | exit | valid | tets | max MIPS | min SJ | < 0.01 | "
          "kept | on kept | goal | s |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
for r in rows:
    if "tets" in r:
        lines.append(f"| {r['name']} | {r['K']} | {r['kind']} | {r['exit']} | "
                     f"{'yes' if r['valid'] else 'no'} | {r['tets']} | {r['max_mips']:.3g} | "
                     f"{r['min_sj']:.3g} | {r['below']} | {r['kept']} | "
                     f"{'yes' if r['worst_on_kept'] else 'no'} | "
                     f"{'met' if r['goal'] else 'missed'} | {r['s']:.1f} |")
    else:
        lines.append(f"| {r['name']} | {r['K']} | {r['kind']} | {r['exit']} | | | | | | | | | "
                     f"{r['s']:.1f} |")
for kind in sorted({r["kind"] for r in rows}):
    done = [r for r in rows if r["kind"] == kind and "tets" in r]
    lines.append("")
    lines.append(f"- {kind}: quality goal met on {sum(r['goal'] for r in done)} of {len(done)} "
                 f"runs; valid {sum(bool(r['valid']) for r in done)} of {len(done)}.")
with open(args.out, "w") as f:
    f.write("\n".join(lines) + "\n")
print("wrote", args.out)
