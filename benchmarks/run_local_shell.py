#!/usr/bin/python3
"""Locally injective shells of self-intersecting inputs (issue 25, thesis §4.5): runs `curvefem
shell IN --allow-self-intersections` on surfaces that pass through themselves, checks that the
default (embedded) run refuses them, and measures what the local sheets cost on surfaces that do
not self-intersect (the same input in both modes). Writes benchmarks/results/shell_local_sheets.md.

Inputs that pass through themselves:
  - ../shared/data/bad/selfintersect_*.{obj,off} (real meshes: the CGAL camel, an ABC part made
    of three overlapping closed components), when present;
  - dev meshes of ../shared/data/dev written together with a copy of themselves shifted by
    (0.31, 0.17, 0.11) x the longest bbox edge, as one surface (two components crossing);
  - a closed tube of radius 0.12 around the figure eight x = cos t, y = sin 2t / 2 (one component
    of genus 1 crossing itself), at two resolutions.
Every figure comes from the run's report.json (verification by meshing/shell/verify.cpp: exact
positivity, separation and section per prism against its sheet, and P⁻¹ then P of every input
vertex; self-intersecting pairs by meshing/check).

Usage (from the repository root):
  /usr/bin/python3 benchmarks/run_local_shell.py [--exe build/tools/curvefem/curvefem]
      [--threads 2] [--timeout 900] [--work DIR] [--out FILE]
Standard library only.
"""
import argparse
import datetime
import json
import math
import os
import subprocess
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--data", default=os.path.join(root, "../shared/data"))
ap.add_argument("--shifted", nargs="*", default=["bunny", "fertility", "fandisk", "armadillo"],
                help="dev meshes written with a shifted copy of themselves as one surface")
ap.add_argument("--embedded", nargs="*", default=["bunny", "homer", "fertility", "armadillo"],
                help="dev meshes run in both modes (the cost of the local sheets)")
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--timeout", type=int, default=900)
ap.add_argument("--work", default="/tmp/curvefem_local_shell")
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/shell_local_sheets.md"))
args = ap.parse_args()
os.makedirs(args.work, exist_ok=True)


def read_obj(path):
    V, F = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                V.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                F.append([int(t.split("/")[0]) for t in line.split()[1:4]])
    return V, F


def write_obj(path, V, F):
    with open(path, "w") as f:
        for v in V:
            f.write("v %.17g %.17g %.17g\n" % tuple(v))
        for t in F:
            f.write("f %d %d %d\n" % tuple(t))


def with_shifted_copy(src, dst):
    V, F = read_obj(src)
    e = max(max(v[i] for v in V) - min(v[i] for v in V) for i in range(3))
    d = [0.31 * e, 0.17 * e, 0.11 * e]
    W = V + [[v[0] + d[0], v[1] + d[1], v[2] + d[2]] for v in V]
    write_obj(dst, W, F + [[i + len(V) for i in t] for t in F])


def figure_eight(dst, n, m, r):
    V, F = [], []
    for i in range(n):
        t = 2 * math.pi * i / n
        c = [math.cos(t), math.sin(2 * t) / 2, 0.0]
        d = [-math.sin(t), math.cos(2 * t), 0.0]
        ld = math.hypot(d[0], d[1])
        d = [d[0] / ld, d[1] / ld, 0.0]
        side = [-d[1], d[0], 0.0]  # z x d
        for j in range(m):
            w = 2 * math.pi * j / m
            V.append([c[k] + r * (math.cos(w) * side[k] + (math.sin(w) if k == 2 else 0.0))
                      for k in range(3)])
    for i in range(n):
        for j in range(m):
            a, b = i * m + j, ((i + 1) % n) * m + j
            c2, d2 = ((i + 1) % n) * m + (j + 1) % m, i * m + (j + 1) % m
            F += [[a + 1, c2 + 1, b + 1], [a + 1, d2 + 1, c2 + 1]]
    write_obj(dst, V, F)


def run(name, path, extra):
    out = os.path.join(args.work, name)
    cmd = [args.exe, "shell", path, "-o", out, "-q", "--threads", str(args.threads)] + extra
    t = time.time()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
        code, err = p.returncode, (p.stderr.strip().splitlines() or [""])[-1]
    except subprocess.TimeoutExpired:
        code, err = 124, "timeout"
    wall = time.time() - t
    rp = os.path.join(out, "report.json")
    report = None
    if code in (0, 3) and os.path.exists(rp):
        with open(rp) as f:
            report = json.load(f)
    return {"exit": code, "error": err, "wall": wall, "report": report}


crossing = []
bad = os.path.join(args.data, "bad")
if os.path.isdir(bad):
    for name in sorted(os.listdir(bad)):
        if name.startswith("selfintersect_"):
            crossing.append((os.path.splitext(name)[0], "real (data/bad)", os.path.join(bad, name),
                             None))
for name in args.shifted:
    src = os.path.join(args.data, "dev", name + ".obj")
    if os.path.exists(src):
        dst = os.path.join(args.work, name + "_and_shifted.obj")
        with_shifted_copy(src, dst)
        crossing.append((name + " + shifted copy", "dev, two copies", dst, name))
for n, m in [(96, 10), (480, 48)]:
    dst = os.path.join(args.work, "figure_eight_%d.obj" % (2 * n * m))
    figure_eight(dst, n, m, 0.12)
    crossing.append(("figure-eight tube %d" % (2 * n * m), "generated", dst, None))

rows = []
for name, kind, path, copy_of in crossing:
    tag = name.replace(" ", "_").replace("+", "and")
    plain = run(tag + "_plain", path, [])
    local = run(tag + "_local", path, ["--allow-self-intersections"])
    rows.append((name, kind, plain, local, copy_of))
    print(name, plain["exit"], local["exit"], "%.1f s" % local["wall"], flush=True)

costs = []
embedded_prisms = {}
for name in args.embedded + [c for *_, c in crossing if c and c not in args.embedded]:
    src = os.path.join(args.data, "dev", name + ".obj")
    if not os.path.exists(src):
        continue
    a = run(name + "_embedded", src, [])
    b = run(name + "_embedded_local", src, ["--allow-self-intersections"])
    if a["report"]:
        embedded_prisms[name] = a["report"]["prisms"]
    if name in args.embedded:
        costs.append((name, a, b))
    print(name, a["exit"], b["exit"], flush=True)

head = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"], capture_output=True,
                      text=True).stdout.strip()
L = ["# Locally injective shells of self-intersecting inputs (issue 25, thesis §4.5)\n",
     "Generated %s by `/usr/bin/python3 benchmarks/run_local_shell.py --threads %d` (HEAD %s, %d "
     "cores). Default shell options otherwise (thickness 0.02, zoom 0.1, simplified).\n" % (
         datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M UTC"), args.threads, head,
         os.cpu_count()),
     "## Inputs that pass through themselves\n",
     "default = `curvefem shell IN` (embedded shell): its exit (2 = refused, naming the "
     "self-intersecting pairs). local = `--allow-self-intersections`: prisms after "
     "simplification; verified = positive, separated and a section against each prism's sheet "
     "(independent checks of verify.cpp); roundtrip = max |P(P⁻¹(x)) − x| over the input "
     "vertices / bbox edge, with the failures; field = the smooth test field carried input → "
     "middle surface → input (max error / the field's range); pairs = exactly "
     "self-intersecting face pairs of the input and of the coarse middle surface; alone = for "
     "two copies, twice the prisms of one copy's embedded shell (same options, its own run).\n",
     "| input | kind | faces | input pairs | default exit | local exit | prisms | alone | "
     "verified | roundtrip (failures) | field error / range | middle pairs | s |",
     "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
for name, kind, plain, local, copy_of in rows:
    r = local["report"]
    if r is None:
        L.append("| %s | %s | | | %d | %d | | | | | | | %.1f |" % (
            name, kind, plain["exit"], local["exit"], local["wall"]))
        continue
    s = r["local_sheets"]
    ft = s["field_roundtrip"]
    alone = "%d" % (2 * embedded_prisms[copy_of]) if copy_of in embedded_prisms else ""
    L.append("| %s | %s | %d | %d | %d | %d | %d | %s | %s | %.2g (%d) | %.3g / %.3g | %d | "
             "%.1f |" % (
        name, kind, r["input_faces"], s["input_self_intersecting_pairs"], plain["exit"],
        local["exit"], r["prisms"], alone,
        "yes" if r["positive_verified"] and r["intersection_free_verified"]
        and r["is_section_verified"] else "NO",
        r["roundtrip_max_error_rel"], r["roundtrip_failures"], ft["max_error"], ft["field_range"],
        s["middle_self_intersecting_pairs"], r["time_s"]["total"]))
L.append("")
L.append("## What the local sheets cost (inputs free of self-intersections, both modes)\n")
L.append("The same dev mesh with the embedded shell and with `--allow-self-intersections`, one "
         "run each, one after the other (seconds: report.json `time_s.total`).\n")
L.append("| input | faces | embedded prisms | local prisms | embedded s | local s | ratio |")
L.append("|---|---|---|---|---|---|---|")
for name, a, b in costs:
    ra, rb = a["report"], b["report"]
    if ra is None or rb is None:
        L.append("| %s | | | | | | exit %d / %d |" % (name, a["exit"], b["exit"]))
        continue
    L.append("| %s | %d | %d | %d | %.2f | %.2f | %.2f |" % (
        name, ra["input_faces"], ra["prisms"], rb["prisms"], ra["time_s"]["total"],
        rb["time_s"]["total"], rb["time_s"]["total"] / ra["time_s"]["total"]))
L.append("")
with open(args.out, "w") as f:
    f.write("\n".join(L) + "\n")
print("wrote", args.out)
