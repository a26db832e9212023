#!/usr/bin/python3
"""SCAF parameterization benchmark (issue 25, part 1): runs `curvefem param` on generated inputs
and, when /work/shared/data/dev exists, on its genus-0 dev meshes cut to a disk, and writes
benchmarks/results/param.md.

Generated inputs (written here as OBJ, same shapes as tests/meshing/param/param_inputs.hpp):
  bump_N      deep Gaussian bump disk (height 1.6, width 0.28) at several resolutions
  spiral      flat strip, 3 turns (minimum energy exactly 4)
  torus_cut   torus cut into a disk by a meridian and a longitude seam (seam file)
  charts5     4 bump disks + a spiral strip: 5 charts packed by the same optimisation
Dev meshes (genus 0 in MANIFEST.tsv): cut along the edge path between two far-apart vertices
(Dijkstra from vertex 0 to the farthest vertex, then from there to its farthest): a sphere cut
along a simple path is a disk.

Each input runs once with the default settings (--iterations 50, --tolerance 1e-6) and, for the
reference energy, once with --iterations REF --tolerance 1e-9 (skipped above --ref-max-faces).
Flips and overlaps are counted by the exact checker after every iteration (report.json); the
time per iteration excludes those checks.

Usage (from the repository root):
  /usr/bin/python3 benchmarks/run_param.py [--exe build/tools/curvefem/curvefem] [--no-dev]
Standard library only.
"""
import argparse
import heapq
import json
import math
import os
import subprocess
import sys
import tempfile
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--data", default=os.path.join(root, "../shared/data/dev"))
ap.add_argument("--dev", nargs="*", default=["knight_decimated", "spot", "bunny", "homer",
                                              "armadillo"],
                help="dev mesh names (genus 0) to run")
ap.add_argument("--no-dev", action="store_true")
ap.add_argument("--iterations", type=int, default=50)
ap.add_argument("--ref-iterations", type=int, default=300)
ap.add_argument("--ref-max-faces", type=int, default=20000)
ap.add_argument("--bump-sizes", nargs="*", type=int, default=[16, 32, 64, 128])
ap.add_argument("--newton", type=int, default=50,
                help="also run every input with this many projected Newton iterations after "
                     "SLIM (`curvefem param --newton N`); 0: not")
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/param.md"))
args = ap.parse_args()


def write_obj(path, V, F, groups=None):
    with open(path, "w") as f:
        for v in V:
            f.write("v %.17g %.17g %.17g\n" % tuple(v))
        last = None
        for i, t in enumerate(F):
            if groups is not None and groups[i] != last:
                last = groups[i]
                f.write("g %s\n" % last)
            f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))


def bump_disk(rings, sectors, height, width, offset=(0, 0, 0)):
    V = [(offset[0], offset[1], offset[2] + height)]
    for r in range(1, rings + 1):
        for s in range(sectors):
            rho = r / rings
            a = 2 * math.pi * (s + 0.5 * (r % 2)) / sectors
            V.append((offset[0] + rho * math.cos(a), offset[1] + rho * math.sin(a),
                      offset[2] + height * math.exp(-rho * rho / (2 * width * width))))

    def vid(r, s):
        return 0 if r == 0 else 1 + (r - 1) * sectors + (s % sectors)
    F = [(0, vid(1, s), vid(1, s + 1)) for s in range(sectors)]
    for r in range(1, rings):
        for s in range(sectors):
            if r % 2:
                F += [(vid(r, s), vid(r + 1, s + 1), vid(r, s + 1)),
                      (vid(r, s), vid(r + 1, s), vid(r + 1, s + 1))]
            else:
                F += [(vid(r, s), vid(r + 1, s), vid(r, s + 1)),
                      (vid(r, s + 1), vid(r + 1, s), vid(r + 1, s + 1))]
    return V, F


def spiral_strip(turns, segments, across, width, pitch):
    cols = across + 1
    V = []
    for i in range(segments + 1):
        t = 2 * math.pi * turns * i / segments
        for j in range(cols):
            rho = 1 + pitch * t / (2 * math.pi) + width * (j / across - 0.5)
            V.append((rho * math.cos(t), rho * math.sin(t), 0.0))
    F = []
    for i in range(segments):
        for j in range(across):
            a = i * cols + j
            b, c = a + 1, a + cols
            d = c + 1
            F += [(a, b, d), (a, d, c)]
    return V, F


def torus(R, r, nu, nv):
    V = []
    for i in range(nu):
        for j in range(nv):
            u, w = 2 * math.pi * i / nu, 2 * math.pi * j / nv
            V.append(((R + r * math.cos(w)) * math.cos(u), (R + r * math.cos(w)) * math.sin(u),
                      r * math.sin(w)))
    F = []
    for i in range(nu):
        for j in range(nv):
            a, b = i * nv + j, ((i + 1) % nu) * nv + j
            c, d = ((i + 1) % nu) * nv + (j + 1) % nv, i * nv + (j + 1) % nv
            F += [(a, b, c), (a, c, d)]
    seams = [(j, (j + 1) % nv) for j in range(nv)] + [(i * nv, ((i + 1) % nu) * nv)
                                                      for i in range(nu)]
    return V, F, seams


def read_obj(path):
    V, F = [], []
    with open(path) as f:
        for line in f:
            p = line.split()
            if not p:
                continue
            if p[0] == "v":
                V.append(tuple(float(x) for x in p[1:4]))
            elif p[0] == "f":
                F.append(tuple(int(x.split("/")[0]) - 1 for x in p[1:4]))
    return V, F


def path_seams(V, F):
    adj = {}
    for t in F:
        for k in range(3):
            a, b = t[k], t[(k + 1) % 3]
            w = math.dist(V[a], V[b])
            adj.setdefault(a, {})[b] = w
            adj.setdefault(b, {})[a] = w

    def dijkstra(src):
        dist, prev = {src: 0.0}, {}
        heap = [(0.0, src)]
        while heap:
            d, u = heapq.heappop(heap)
            if d > dist[u]:
                continue
            for v, w in adj[u].items():
                if d + w < dist.get(v, math.inf):
                    dist[v], prev[v] = d + w, u
                    heapq.heappush(heap, (d + w, v))
        far = max(dist, key=dist.get)
        return far, prev
    a, _ = dijkstra(F[0][0])
    b, prev = dijkstra(a)
    seams, v = [], b
    while v != a:
        seams.append((prev[v], v))
        v = prev[v]
    return seams


def run(name, obj, seams_file, iterations, tolerance, work, newton=0):
    report = os.path.join(work, name + "_%d_%d.json" % (iterations, newton))
    cmd = [args.exe, "param", "-q", obj, "-o", os.path.join(work, name + "_uv.obj"),
           "--iterations", str(iterations), "--tolerance", str(tolerance), "--report", report]
    cmd += ["--newton", str(newton)]  # 0: SLIM alone (the CLI's default adds 10 Newton iterations)
    if seams_file:
        cmd += ["--seams", seams_file]
    t0 = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.time() - t0
    if p.returncode != 0:
        print("FAILED (%d): %s\n%s%s" % (p.returncode, " ".join(cmd), p.stdout, p.stderr))
        return None
    with open(report) as f:
        r = json.load(f)
    r["wall_s"] = wall
    return r


if not os.path.exists(args.exe):
    sys.exit("no curvefem executable at %s (build the target curvefem, or pass --exe)" % args.exe)
work = tempfile.mkdtemp(prefix="param_bench_")
cases = []  # (name, kind, obj, seams file)
for n in args.bump_sizes:
    V, F = bump_disk(n, 4 * n, 1.6, 0.28)
    path = os.path.join(work, "bump_%d.obj" % len(F))
    write_obj(path, V, F)
    cases.append(("bump_%d" % len(F), "generated", path, None))
V, F = spiral_strip(3.0, 150, 2, 0.5, 1.0)
write_obj(os.path.join(work, "spiral.obj"), V, F)
cases.append(("spiral", "generated", os.path.join(work, "spiral.obj"), None))
V, F, seams = torus(2, 0.8, 80, 32)
write_obj(os.path.join(work, "torus_cut.obj"), V, F)
with open(os.path.join(work, "torus_cut.seams"), "w") as f:
    f.writelines("%d %d\n" % s for s in seams)
cases.append(("torus_cut", "generated", os.path.join(work, "torus_cut.obj"),
              os.path.join(work, "torus_cut.seams")))
V, F, G = [], [], []
for i in range(4):
    v, f = bump_disk(8, 32, 0.6 + 0.4 * i, 0.3, (3.0 * i, 0, 0))
    F += [tuple(x + len(V) for x in t) for t in f]
    G += ["bump%d" % i] * len(f)
    V += v
v, f = spiral_strip(1.0, 40, 2, 0.4, 1.0)
F += [tuple(x + len(V) for x in t) for t in f]
G += ["strip"] * len(f)
V += v
write_obj(os.path.join(work, "charts5.obj"), V, F, G)
cases.append(("charts5", "generated", os.path.join(work, "charts5.obj"), None))

dev_note = ""
if args.no_dev:
    dev_note = "dev meshes not run (--no-dev)"
elif not os.path.isdir(args.data):
    dev_note = "dev meshes skipped: %s does not exist" % args.data
    print(dev_note)
else:
    manifest = {}
    with open(os.path.join(args.data, "MANIFEST.tsv")) as f:
        header = f.readline().rstrip("\n").split("\t")
        for line in f:
            row = dict(zip(header, line.rstrip("\n").split("\t")))
            manifest[row["name"]] = row
    for name in args.dev:
        row = manifest.get(name)
        if row is None or row["genus"] != "0" or row["components"] != "1":
            print("skipping %s: not a single genus-0 component" % name)
            continue
        V, F = read_obj(os.path.join(args.data, row["file"]))
        seams = path_seams(V, F)
        sp = os.path.join(work, name + ".seams")
        with open(sp, "w") as f:
            f.writelines("%d %d\n" % s for s in seams)
        cases.append((name, "dev, path cut (%d edges)" % len(seams),
                      os.path.join(args.data, row["file"]), sp))

load_start = os.getloadavg()[0]
rows = []
for name, kind, obj, seams in cases:
    r = run(name, obj, seams, args.iterations, 1e-6, work)
    if r is None:
        rows.append((name, kind, None, None))
        continue
    ref = None
    if r["faces"] <= args.ref_max_faces:
        ref = run(name + "_ref", obj, seams, args.ref_iterations, 1e-9, work)
    if args.newton > 0:
        r["newton_run"] = run(name + "_newton", obj, seams, args.iterations, 1e-6, work,
                              args.newton)
    print("%-14s F=%7d charts=%d it=%3d E %.6g -> %.6g (ref %s) flips %d overlaps %d %.4f s/it" % (
        name, r["faces"], r["charts"], r["iterations"], r["initial_energy"], r["energy"],
        "%.6g" % ref["energy"] if ref else "-", r["max_flips_over_iterations"],
        r["max_overlaps_over_iterations"], r["time_s"]["per_iteration"]))
    rows.append((name, kind, r, ref))

with open(os.path.join(root, "build", "param_bench_runs.json") if os.path.isdir(
        os.path.join(root, "build")) else os.devnull, "w") as f:
    json.dump([{"name": n, "kind": k, "report": r, "reference": ref} for n, k, r, ref in rows], f)

cpu = ""
try:
    with open("/proc/cpuinfo") as f:
        cpu = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
except (OSError, StopIteration):
    pass
out = []
load_end = os.getloadavg()[0]
out.append("# SCAF bijective parameterization — `curvefem param` (issue 25, part 1)\n")
out.append("Written by `benchmarks/run_param.py` on %s (%s, 2 cores shared; CHOLMOD may use "
           "both through OpenBLAS), %s. Every run: %d iterations at most, tolerance 1e-6 on the "
           "relative energy decrease. Flips and overlaps are the maxima over *all* iterations "
           "counted by the independent exact checker (`meshing/param/uv_check.hpp`, CGAL "
           "predicates). Energy = area-weighted mean symmetric Dirichlet (≥ 4). Reference = the "
           "same input run to %d iterations / tolerance 1e-9 (omitted above %d faces). "
           "s/it = mean wall time of one iteration (scaffold rebuild + assembly + CHOLMOD + "
           "line search), without the checks. 1-minute load average %.1f at the start, %.1f at the "
           "end (other work shares the machine: timings are upper bounds).\n" % (
               time.strftime("%Y-%m-%d"), cpu or "unknown CPU", dev_note or "dev meshes from "
               "../shared/data/dev", args.iterations, args.ref_iterations, args.ref_max_faces, load_start, load_end))
out.append("| input | kind | #F | charts | #F scaffold first/last | it. (stop) | E initial | "
           "E final | E reference | final / ref | max flips | max overlaps | s/it | "
           "scaf total s | solve s/it |")
out.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for name, kind, r, ref in rows:
    if r is None:
        out.append("| %s | %s | failed (see the script's output) |||||||||||||" % (name, kind))
        continue
    h = r["history"]
    it = r["iterations"]
    solve = sum(x["time_s"]["solve"] for x in h[1:]) / max(1, it)
    out.append("| %s | %s | %d | %d | %d/%d | %d (%s) | %.6g | %.6g | %s | %s | %d | %d | %.4f | "
               "%.2f | %.4f |" % (
                   name, kind, r["faces"], r["charts"], h[0]["scaffold_faces"],
                   h[-1]["scaffold_faces"], it, r["stop_reason"], r["initial_energy"],
                   r["energy"], "%.6g" % ref["energy"] if ref else "–",
                   "%.4f" % (r["energy"] / ref["energy"]) if ref else "–",
                   r["max_flips_over_iterations"], r["max_overlaps_over_iterations"],
                   r["time_s"]["per_iteration"], r["time_s"]["scaf"], solve))
if args.newton > 0:
    out.append("""
## SLIM, then projected Newton (`--newton %d`)

The same inputs and SLIM settings, then at most %d projected Newton iterations
(meshing/param/scaf.hpp: exact gradient, per-triangle Hessians projected onto the PSD cone, the
same scaffold, CHOLMOD solve and flip-free line search), until the relative decrease of E is
below 1e-12. Checked after every iteration like the runs above. "SLIM s" and "SLIM + Newton s"
are the optimisation times (`time_s.scaf`); "ref. s" is the SLIM reference run's (the table
above: %d iterations at most, tolerance 1e-9). final / ref < 1: below the reference.
""" % (args.newton, args.newton, args.ref_iterations))
    out.append("| input | #F | SLIM it. | Newton it. (stop) | E SLIM | E SLIM + Newton | E reference | "
               "final / ref | max flips | max overlaps | last gradient | SLIM s | SLIM + Newton s | "
               "ref. it. | ref. s |")
    out.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, kind, r, ref in rows:
        if r is None:
            continue
        n = r.get("newton_run")
        if n is None:
            out.append("| %s | %d | failed (see the script's output) |||||||||||||" % (
                name, r["faces"]))
            continue
        last = n["history"][-1]
        out.append("| %s | %d | %d | %d (%s) | %.10g | %.10g | %s | %s | %d | %d | %s | %.2f | %.2f | "
                   "%s | %s |" % (
                       name, r["faces"], r["iterations"], n["newton_iterations"],
                       n["newton_stop_reason"], r["energy"], n["energy"],
                       "%.10g" % ref["energy"] if ref else "–",
                       "%.8f" % (n["energy"] / ref["energy"]) if ref else "–",
                       n["max_flips_over_iterations"], n["max_overlaps_over_iterations"],
                       "%.2g" % last["gradient_norm"] if "gradient_norm" in last else "–",
                       r["time_s"]["scaf"], n["time_s"]["scaf"],
                       "%d" % ref["iterations"] if ref else "–",
                       "%.2f" % ref["time_s"]["scaf"] if ref else "–"))
out.append("""
## Thesis Table 3.1 (for comparison, not measured here)

The thesis' timings (Table 3.1, single thread on a 4 GHz i7, libigl reference implementation),
rows quoted as "#F, it., total s, s/it" (Nefertiti and Maneki-Neko are its atlas rows): Nefertiti 2,823 F, 50 it., 0.71 s, 0.01 s/it;
Hand 4,046 F, 7 it., 0.14 s, 0.02; Camel 3,576 F, 30 it., 0.52 s, 0.02; Cow 5,804 F, 30 it.,
0.81 s, 0.03; Horse 39,698 F, 30 it., 8.26 s, 0.28; Animal 39,040 F, 50 it., 15.36 s, 0.31;
Maneki-Neko 43,648 F, 50 it., 16.81 s, 0.34; Thai Statue 79,970 F, 50 it., 28.28 s, 0.56;
Filigree 100,000 F, 100 it., 75.99 s, 0.76; Lucy 1,000,000 F, 100 it., 2,524 s, 25.24.
libigl (the thesis' implementation) is not a Debian package here (`apt-cache search libigl`
finds only the unrelated libigloo), so it was not run side by side: the comparison is with the
table's figures only, on different inputs and hardware.
""")
os.makedirs(os.path.dirname(args.out), exist_ok=True)
with open(args.out, "w") as f:
    f.write("\n".join(out) + "\n")
print("wrote", args.out)
