#!/usr/bin/python3
"""Robustness benchmark (issue 21): the curved mesher on the procedural adversarial corpus
(`curvefem generate --list`, meshing/core/adversarial.hpp) and on the dev meshes.

For every surface and order K: `curvefem check` (a refusal there makes exit 2 acceptable), then
`curvefem mesh IN -o DIR --order K --eps EPS -q --threads T` (timeout per run) and the numbers of
DIR/report.json, whose guarantees come from the independent validator: exit code, valid, min
scaled Jacobian, tets with scaled Jacobian below 0.01, max / mean curved MIPS, each for the slab
layer and the interior too, boundary self-intersections, max distance, wall time. The first
line of the error output is kept for failed runs.

Usage (from the repository root):
  /usr/bin/python3 benchmarks/run_robustness.py [--corpus all|none|NAME ...] [--dev] [--files F ...]
      [--orders 3 4]
      [--eps 0.01] [--threads 2] [--timeout 600] [--exe build/tools/curvefem/curvefem]
      [--extra 'MORE MESH OPTIONS']
Writes benchmarks/results/robustness.md; raw JSON lines go to WORK/runs.jsonl.
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
ap.add_argument("--corpus", nargs="+", default=["all"])
ap.add_argument("--skip", nargs="*", default=[], help="corpus or dev names to leave out")
ap.add_argument("--dev", action="store_true", help="also the dev meshes of --data")
ap.add_argument("--data", default="/work/shared/data/dev")
ap.add_argument("--files", nargs="*", default=[], metavar="SURFACE",
                help="more surfaces (any format `curvefem mesh` reads), named by their file stem, "
                     "kind 'unseen' (e.g. meshes of Debian packages nobody here tuned for)")
ap.add_argument("--orders", nargs="+", type=int, default=[3, 4])
ap.add_argument("--eps", type=float, default=0.01)
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--timeout", type=float, default=600)
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--work", default="/tmp/robustness")
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/robustness.md"))
ap.add_argument("--extra", default="", metavar="ARGS",
                help="more `curvefem mesh` options for every run, e.g. --extra='--shape-slack 0'")
ap.add_argument("--note", default="", help="a hand-written paragraph for the report")
ap.add_argument("--render-from", metavar="JSONL",
                help="run nothing: write --out from these raw records (e.g. of a run cut short)")
args = ap.parse_args()
command = "/usr/bin/python3 " + " ".join(
    shlex.quote(a) for a in ["benchmarks/run_robustness.py"] + sys.argv[1:])
os.makedirs(args.work, exist_ok=True)


def run(cmd, timeout):
    t0 = time.time()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        return p.returncode, time.time() - t0, p.stderr
    except subprocess.TimeoutExpired:
        return "timeout", time.time() - t0, ""


inputs = []  # (name, path, kind)
if args.render_from:
    args.corpus = ["none"]
    args.dev = False
if args.corpus != ["none"]:
    listed = subprocess.run([args.exe, "generate", "--list"], capture_output=True, text=True,
                            check=True).stdout.splitlines()
    names = [l.split()[0] for l in listed if l.strip()]
    if args.corpus != ["all"]:
        names = [n for n in names if n in args.corpus]
    for n in names:
        if n in args.skip:
            continue
        path = os.path.join(args.work, n + ".obj")
        if not os.path.exists(path):
            subprocess.run([args.exe, "generate", n, "-o", path], check=True)
        inputs.append((n, path, "corpus"))
if args.dev:
    with open(os.path.join(args.data, "MANIFEST.tsv")) as f:
        for line in f:
            cols = line.rstrip("\n").split("\t")
            if len(cols) < 2 or not cols[1].endswith(".obj") or cols[0] in args.skip:
                continue
            inputs.append((cols[0], os.path.join(args.data, cols[1]), "dev"))

for path in args.files:
    name = os.path.splitext(os.path.basename(path))[0]
    if name not in args.skip:
        inputs.append((name, os.path.abspath(path), "unseen"))

records = []
if args.render_from:
    with open(args.render_from) as f:
        records = [json.loads(l) for l in f if l.strip()]
jsonl = open(os.path.join(args.work, "runs.jsonl"), "a")
for name, path, kind in inputs:
    code, _, _ = run([args.exe, "check", path, "-q"], args.timeout)
    for k in args.orders:
        out = os.path.join(args.work, f"{name}_k{k}")
        cmd = [args.exe, "mesh", path, "-o", out, "--order", str(k), "--eps", str(args.eps), "-q",
               "--threads", str(args.threads)] + shlex.split(args.extra)
        rc, wall, err = run(cmd, args.timeout)
        rec = dict(name=name, kind=kind, order=k, check=code, exit=rc, wall=wall,
                   error=next((l for l in err.splitlines() if "error" in l), ""))
        try:
            with open(os.path.join(out, "report.json")) as f:
                r = json.load(f)
            if rc == 0 or os.path.getmtime(os.path.join(out, "report.json")) > time.time() - wall - 1:
                v = r["validation"]
                rec.update(valid=v["valid"], tets=v["tets"], faces=r["input_faces"],
                           sj=v["min_scaled_jacobian"],
                           below=v.get("tets_scaled_jacobian_below_0.01"),
                           max_mips=v["max_mips"], mean_mips=v["mean_mips"],
                           si=v["boundary_self_intersections"], dist=v["max_distance_rel"],
                           singular=r.get("singular_vertices"), coarse=r.get("coarse_faces"),
                           by_tag=v.get("quality_by_tag", {}),
                           bnd_mips_floor=v.get("boundary_limits", {}).get("mips_floor"),
                           bnd_sj_ceiling=v.get("boundary_limits", {}).get("sj_ceiling"))
                fl = r.get("input_floors")
                if fl is not None:  # since 4249525 (pipeline/input_floors.hpp)
                    rec.update(floor_kept=fl["needle_faces_kept"] + fl["near_fold_edges_kept"],
                               floor_worst=fl["worst_mips_tet_at_kept"]
                               or fl["worst_scaled_jacobian_tet_at_kept"])
        except (OSError, ValueError, KeyError):
            pass
        records.append(rec)
        jsonl.write(json.dumps(rec) + "\n")
        jsonl.flush()
        print(f"{name:22s} K={k} exit {rc} valid {rec.get('valid')} sj {rec.get('sj')} "
              f"{wall:.1f} s {rec['error'][:80]}", flush=True)


def g(x, fmt="{:.3g}"):
    if x is None:
        return "—"
    if isinstance(x, float) and x != x:
        return "nan"
    return fmt.format(x) if isinstance(x, float) else str(x)


kinds = [k for k in ("corpus", "dev", "unseen") if any(r["kind"] == k for r in records)]
what = {"corpus": "the adversarial corpus", "dev": "the dev meshes", "unseen": "unseen surfaces"}
lines = [f"# Robustness: the curved mesher on {' and '.join(what[k] for k in kinds) or 'nothing'}",
         "",
         f"Generated {datetime.datetime.now():%Y-%m-%d %H:%M} by `{command}`; HEAD "
         + subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"], capture_output=True,
                          text=True).stdout.strip()
         + f"; {os.cpu_count()} cores; ε = {args.eps}, default options, one run each, sequential.",
         "",
         "exit: 0 valid, 3 a guarantee failed (or a stage could not meet it), 2 input refused; "
         "check: `curvefem check` exit (0 accepted). SJ = sampled min scaled Jacobian; < 0.01 = tets "
         "below 0.01 (share of all); MIPS = curved MIPS; slab / interior: the same per layer; "
         "boundary bounds: the largest MIPS floor and the smallest SJ ceiling its straight corner "
         "triangles set for straight tets on them (report.json validation.boundary_limits).",
         "",
         "| surface | kind | K | faces | check | exit | valid | tets | min SJ | < 0.01 | max MIPS | mean MIPS | slab min SJ | interior min SJ | boundary bounds (MIPS ≥, SJ ≤) | singular | s | error |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
for r in records:
    bt = r.get("by_tag", {})
    share = (f"{r['below']} ({100.0 * r['below'] / r['tets']:.1f}%)"
             if r.get("below") is not None and r.get("tets") else "—")
    lines.append("| " + " | ".join([
        r["name"], r["kind"], str(r["order"]), g(r.get("faces")), str(r["check"]), str(r["exit"]),
        {True: "yes", False: "no"}.get(r.get("valid"), "—"), g(r.get("tets")), g(r.get("sj")),
        share, g(r.get("max_mips")), g(r.get("mean_mips")),
        g(bt.get("slab", {}).get("min_scaled_jacobian")),
        g(bt.get("interior", {}).get("min_scaled_jacobian")),
        (f"{g(r.get('bnd_mips_floor'))}, {g(r.get('bnd_sj_ceiling'))}"
         if "bnd_sj_ceiling" in r else "—"), g(r.get("singular")),
        f"{r['wall']:.1f}", r["error"].replace("|", "/")[:120]]) + " |")
ok = [r for r in records if r.get("valid")]
accepted = [r for r in records if r["check"] == 0]
lines += ["", f"Valid: {len(ok)} of {len(records)} runs; of the {len(accepted)} runs on inputs "
          f"`curvefem check` accepts, {len([r for r in accepted if r.get('valid')])} valid."]
qual = [r for r in ok if r.get("sj") is not None]
if qual:
    good = [r for r in qual if r["sj"] >= 1e-3 and (r.get("below") or 0) <= 0.01 * r["tets"]
            and r["max_mips"] <= 1e4]
    lines.append(f"Quality goal (min SJ >= 1e-3, <= 1% of tets below 0.01, max MIPS <= 1e4) met "
                 f"on {len(good)} of {len(qual)} valid runs.")
    missed = [r for r in qual if r not in good and r.get("bnd_sj_ceiling") is not None]
    forced = [r for r in missed if (r.get("bnd_mips_floor") or float("inf")) > 1e4
              or r["bnd_sj_ceiling"] < 1e-3]
    if missed:
        lines.append(f"Of the {len(missed)} misses with boundary bounds, {len(forced)} have a "
                     "boundary whose straight corner triangles exclude the goal for straight tets "
                     "(MIPS floor > 1e4 or SJ ceiling < 1e-3)"
                     + (": " + ", ".join(f"{r['name']} K = {r['order']}" for r in forced)
                        if forced else "") + ".")
    at_input = [r for r in qual if r not in good and r.get("floor_worst")]
    if any("floor_worst" in r for r in qual):
        lines.append(f"Misses whose worst tet (largest MIPS or smallest SJ) sits on an input needle "
                     f"face or near-fold edge the boundary kept as it is (report.json "
                     f"input_floors): {len(at_input)}"
                     + (": " + ", ".join(f"{r['name']} K = {r['order']}" for r in at_input)
                        if at_input else "") + ".")
# bichon (reference-notes/bichon-measured.md, P4, eps 1e-2): mean curved MIPS on four dev meshes.
BICHON_MEAN_MIPS = {"knight_decimated": 47.9, "spot": 56.0, "bunny": 52.4, "fandisk": 40.5}
rows = [r for r in records if r["name"] in BICHON_MEAN_MIPS and r["order"] == 4 and r.get("valid")]
if rows:
    lines += ["", "Mean curved MIPS at K = 4 against bichon's (P4): " + "; ".join(
        f"{r['name']} {r['mean_mips']:.1f} vs {BICHON_MEAN_MIPS[r['name']]}" for r in rows) + "."]
if args.note:
    lines += ["", "## Notes", "", args.note]
os.makedirs(os.path.dirname(args.out), exist_ok=True)
with open(args.out, "w") as f:
    f.write("\n".join(lines) + "\n")
print("wrote", args.out)
