#!/usr/bin/python3
"""Shell applications benchmark (issue 25, thesis §4.4-4.5): runs `curvefem shell` with
--displacement-map L, --cages K and --texture TILE (three separate runs per input, so that one
failing application does not hide the others' numbers) on the dev meshes of ../shared/data/dev
and on generated adversarial surfaces, then --boolean union|intersection|difference of a few dev
meshes with a shifted copy of themselves, and writes benchmarks/results/shell_applications.md.

Every number comes from the run's report.json: the checks there are made by code independent of
the construction (meshing/check: CGAL distances, exact self-intersection tests).

Usage (from the repository root):
  /usr/bin/python3 benchmarks/run_shell_applications.py [--exe build/tools/curvefem/curvefem]
      [--level 4] [--cages 3] [--tile knob] [--timeout 900] [--skip igea ...]
Standard library only.
"""
import argparse
import datetime
import json
import os
import subprocess
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--data", default=os.path.join(root, "../shared/data/dev"))
ap.add_argument("--corpus", nargs="*", default=["noise_sphere_5", "noise_sphere_20",
                                                 "needle_sphere_8", "split_ring_01",
                                                 "kissing_spheres_01", "thin_tube_2",
                                                 "torus_coarse", "box_sharp"])
ap.add_argument("--level", type=int, default=4)
ap.add_argument("--cages", type=int, default=3)
ap.add_argument("--tile", default="knob")
ap.add_argument("--timeout", type=int, default=900)
ap.add_argument("--boolean", nargs="*", default=["bunny", "spot", "fertility", "fandisk",
                                                  "rocker_arm"],
                help="dev meshes combined with a copy shifted by (0.31, 0.17, 0.11) x bbox")
ap.add_argument("--skip", nargs="*", default=[])
ap.add_argument("--work", default="/tmp/curvefem_shell_applications")
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/shell_applications.md"))
args = ap.parse_args()
os.makedirs(args.work, exist_ok=True)

inputs = []
if os.path.isdir(args.data):
    for name in sorted(os.listdir(args.data)):
        if name.endswith(".obj") and name[:-4] not in args.skip:
            inputs.append((name[:-4], "dev", os.path.join(args.data, name)))
for name in args.corpus:
    if name in args.skip:
        continue
    path = os.path.join(args.work, name + ".obj")
    subprocess.run([args.exe, "generate", name, "-q", "-o", path], check=True,
                   stdout=subprocess.DEVNULL)
    inputs.append((name, "corpus", path))


def run(name, path, what, extra):
    out = os.path.join(args.work, name + "_" + what)
    cmd = [args.exe, "shell", path, "-o", out, "-q"] + extra
    t = time.time()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
        code, err = p.returncode, (p.stderr.strip().splitlines() or [""])[-1]
    except subprocess.TimeoutExpired:
        code, err = 124, "timeout"
    wall = time.time() - t
    report = None
    rp = os.path.join(out, "report.json")
    if code in (0, 3) and os.path.exists(rp):
        with open(rp) as f:
            report = json.load(f)
    return {"exit": code, "error": err if code not in (0,) else "", "wall": wall,
            "report": report, "command": " ".join(cmd)}


rows = []
for name, kind, path in inputs:
    r = {"name": name, "kind": kind}
    r["disp"] = run(name, path, "disp", ["--displacement-map", str(args.level)])
    r["cages"] = run(name, path, "cages", ["--cages", str(args.cages)])
    r["texture"] = run(name, path, "texture", ["--texture", args.tile])
    rows.append(r)
    print(name, r["disp"]["exit"], r["cages"]["exit"], r["texture"]["exit"], flush=True)


def shifted_copy(src, dst):
    V, rest = [], []
    with open(src) as f:
        for line in f:
            if line.startswith("v "):
                V.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                rest.append(line)
    lo = [min(v[i] for v in V) for i in range(3)]
    hi = [max(v[i] for v in V) for i in range(3)]
    e = max(hi[i] - lo[i] for i in range(3))
    d = [0.31 * e, 0.17 * e, 0.11 * e]
    with open(dst, "w") as f:
        for v in V:
            f.write("v %.17g %.17g %.17g\n" % (v[0] + d[0], v[1] + d[1], v[2] + d[2]))
        f.writelines(rest)


booleans = []
for name in args.boolean:
    src = os.path.join(args.data, name + ".obj")
    if not os.path.exists(src):
        continue
    dst = os.path.join(args.work, name + "_shifted.obj")
    shifted_copy(src, dst)
    for op in ["union", "intersection", "difference"]:
        b = run(name, src, "bool_" + op, ["--boolean", op, "--with", dst])
        b["name"], b["op"] = name, op
        booleans.append(b)
        print(name, op, b["exit"], flush=True)

head = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"], capture_output=True,
                      text=True).stdout.strip()
L = []
L.append("# Shell applications: displacement maps, nested cages, geometric textures (issue 25)\n")
L.append("Generated %s by `/usr/bin/python3 benchmarks/run_shell_applications.py --level %d "
         "--cages %d --tile %s` (HEAD %s, %d cores). Default shell options; each application in "
         "its own `curvefem shell` run.\n" % (
             datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M UTC"), args.level, args.cages,
             args.tile, head, os.cpu_count()))


def g(x, fmt="%.3g"):
    return "" if x is None else (fmt % x)


L.append("## Displacement maps (`--displacement-map %d`)\n" % args.level)
L.append("Rebuilt = the level-%d subdivision of the coarse middle surface, each vertex at the height "
         "P gives it (cage.obj + displacement_map.txt are all it needs). Normals = the same "
         "subdivision moved along the middle surface's interpolated normals to the nearest input "
         "crossing (the usual displacement-map baking). Pairs = exactly self-intersecting face "
         "pairs; Hausdorff = sampled, two-sided, relative to the longest bbox edge; on fibers = "
         "every rebuilt vertex on the input and located back on its own fiber.\n" % args.level)
L.append("| input | kind | coarse faces | samples | missed | on fibers | rebuilt pairs | rebuilt "
         "Hausdorff | normals pairs | normals missed | normals Hausdorff | s | exit |")
L.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for r in rows:
    d = r["disp"]
    if d["report"] is None:
        L.append("| %s | %s | | | | | | | | | | %.1f | %d %s |" % (
            r["name"], r["kind"], d["wall"], d["exit"], d["error"][:80]))
        continue
    m = d["report"]["displacement_map"]
    ok = (m["failures"] == 0 and m["rebuilt"]["vertices_not_located"] == 0 and
          m["rebuilt"]["fiber_offset_max_rel"] <= 1e-9 and
          m["rebuilt"]["max_vertex_distance_rel"] <= 1e-12)
    L.append("| %s | %s | %d | %d | %d | %s | %d | %s | %d | %d | %s | %.1f | %d |" % (
        r["name"], r["kind"], m["coarse_faces"], m["samples"], m["failures"],
        "yes" if ok else "NO", m["rebuilt"]["self_intersecting_pairs"],
        g(m["rebuilt"]["hausdorff_rel"]), m["along_normals"]["self_intersecting_pairs"],
        m["along_normals"]["missed"], g(m["along_normals"]["hausdorff_rel"]), d["wall"],
        d["exit"]))
ok_rows = [r for r in rows if r["disp"]["report"] is not None]
fewer = sum(1 for r in ok_rows if r["disp"]["report"]["displacement_map"]["rebuilt"]
            ["self_intersecting_pairs"] < r["disp"]["report"]["displacement_map"]["along_normals"]
            ["self_intersecting_pairs"])
zero = sum(1 for r in ok_rows if r["disp"]["report"]["displacement_map"]["rebuilt"]
           ["self_intersecting_pairs"] == 0)
L.append("\nRebuilt through P: no self-intersecting pair on %d of %d inputs; fewer pairs than along "
         "the normals on %d of %d.\n" % (zero, len(ok_rows), fewer, len(ok_rows)))

L.append("## Nested cages (`--cages %d`)\n" % args.cages)
L.append("Per layer: faces, the shell kept (s = simplified, s0 = simplified without thickness "
         "growth, st = the same on a shell a quarter as thick, n = not simplified), singular "
         "vertices of its shell / of them filled (pinched: the cage is the top surface's union "
         "with a small tetrahedron there, or touches the layer inside when not filled), the cage's "
         "pinch points before -> after unpinching (top vertices the next layer's shell would "
         "pinch; not computed for the last layer), top-surface pairs before shrinking / shrink "
         "rounds, min gap to the layer inside (relative). Between = exactly intersecting pairs over every two "
         "layers (input included); ok = every layer embedded, nested (winding number 1), and the "
         "maps cage -> input -> cage return every sample whose way down meets no fill.\n")
L.append("| input | kind | layers (faces, shell, singular/filled, pinch points, pairs/rounds, "
         "min gap) "
         "| between | ok | s | exit |")
L.append("|---|---|---|---|---|---|---|")
short = {"simplified": "s", "simplified without growth": "s0", "simplified, thinner": "st",
         "not simplified": "n"}
for r in rows:
    c = r["cages"]
    if c["report"] is None:
        L.append("| %s | %s | | | | %.1f | %d %s |" % (r["name"], r["kind"], c["wall"], c["exit"],
                                                        c["error"][:120]))
        continue
    n = c["report"]["nested_cages"]
    layers = "; ".join("%d %s %d/%d %d->%d %d/%d %.1e" % (
        l["faces"], short.get(l["shell"], l["shell"]), l["singular_vertices"],
        l.get("filled_points", 0),
        l["top_pinch_points_before_unpinching"], l["top_pinch_points"],
        l["self_intersecting_pairs_before_shrinking"], l["shrink_rounds"],
        l["min_gap_to_layer_inside_rel"]) for l in n["per_layer"])
    ok = n["intersecting_pairs_between_layers"] == 0 and all(
        l["shell_verified"] and l["self_intersecting_pairs"] == 0 and
        abs(l["winding_number_of_layer_inside"] - 1) < 1e-6 and l["map_failures"] == 0 and
        l["map_roundtrip_max_rel"] < 1e-9 for l in n["per_layer"])
    L.append("| %s | %s | %s | %d | %s | %.1f | %d |" % (
        r["name"], r["kind"], layers, n["intersecting_pairs_between_layers"],
        "yes" if ok else "NO", c["wall"], c["exit"]))

L.append("\n## Geometric textures (`--texture %s`)\n" % args.tile)
L.append("One copy of the tile per prism of the simplified shell but the pinched ones (a "
         "singular vertex: flat tets; skipped = their number), split at the reference prism's "
         "tets (exact image). Pairs = exactly self-intersecting pairs of all copies; input pairs = "
         "pairs with the input (not a constraint: the input crosses the fibers at its own "
         "heights).\n")
L.append("| input | kind | copies | skipped | faces | pairs | input pairs | s | exit |")
L.append("|---|---|---|---|---|---|---|---|---|")
for r in rows:
    t = r["texture"]
    if t["report"] is None:
        L.append("| %s | %s | | | | | | %.1f | %d %s |" % (r["name"], r["kind"], t["wall"],
                                                           t["exit"], t["error"][:80]))
        continue
    x = t["report"]["geometric_texture"]
    L.append("| %s | %s | %d | %d | %d | %d | %d | %.1f | %d |" % (
        r["name"], r["kind"], x["copies"], x.get("prisms_pinched_skipped", 0), x["faces"],
        x["self_intersecting_pairs"],
        x["pairs_with_input"], t["wall"], t["exit"]))
L.append("\n## Boolean remeshing with correspondence (`--boolean OP --with B`)\n")
L.append("A = the dev mesh, B = the same mesh shifted by (0.31, 0.17, 0.11) x its longest bbox "
         "edge. CGAL corefinement (exact constructions), rounded; the shell is built and simplified "
         "on the result. On operand = largest distance from a coarse vertex's image (through P, "
         "then the result face's origin) to the operand it is attributed to (CGAL, relative). "
         "Field error = the carried value against the operand's analytic test field at that "
         "point (the operand's own linear interpolation error).\n")
L.append("| input | op | result faces (A / B) | coarse faces | section | on operand | field error "
         "| s | exit |")
L.append("|---|---|---|---|---|---|---|---|---|")
for b in booleans:
    if b["report"] is None:
        L.append("| %s | %s | | | | | | %.1f | %d %s |" % (b["name"], b["op"], b["wall"],
                                                          b["exit"], b["error"][:120]))
        continue
    x = b["report"]["boolean"]
    L.append("| %s | %s | %d (%d / %d) | %d | %s | %.1e | %.2g | %.1f | %d |" % (
        b["name"], b["op"], x["result_faces"], x["result_faces_from_a"], x["result_faces_from_b"],
        x["remeshed_faces"], "yes" if b["report"]["is_section_verified"] else "NO",
        x["map_to_operand_max_distance_rel"], x["field_max_error"], b["wall"], b["exit"]))
with open(args.out, "w") as f:
    f.write("\n".join(L) + "\n")
with open(os.path.join(args.work, "rows.json"), "w") as f:
    json.dump(rows, f)
print("wrote", args.out)
