#!/usr/bin/python3
"""Dense-linear baseline: fill the inside of every dev mesh with its boundary unchanged
(meshing/tetfill, gmsh 4.8 3D Delaunay through the C++ API, verified exactly), and the gmsh 4.8
binary (`gmsh -3`) on the same surface for comparison.

For every mesh of /work/shared/data/dev/MANIFEST.tsv (column `file`):
  tetfill   BUILD_DIR/benchmarks/tetfill_tool INPUT  -> one JSON line (tets, boundary faces,
            seconds, exact verification, peak RSS); exit 0 valid, 2 bad input, 3 meshing failed
  gmsh -3   the surface written as MSH 2.2 (one discrete surface, same nodes), a .geo with
            `Merge; Surface Loop; Volume`, `gmsh -3 -nt 1`; tets counted in the output file, time
            and peak RSS of the process from wait4(). No verification of the gmsh binary output
            beyond the counts (its surface is not checked).
Waits (sleep 20 s, at most --quiet-wait s) while the 1-minute load exceeds --max-load before each
run. Writes benchmarks/results/tetfill.md; raw JSON lines go to
BUILD_DIR/benchmarks/tetfill_runs.jsonl (outside the repository).

Usage (from the repository root):
  /usr/bin/python3 benchmarks/run_tetfill.py [--meshes spot.obj ...] [--no-gmsh] [--timeout 900]
  /usr/bin/python3 benchmarks/run_tetfill.py --render-only
BUILD_DIR defaults to build-tetfill; the target tetfill_tool is built there (-j2) unless --exe is
given. Standard library only.
"""
import argparse
import datetime
import json
import os
import shlex
import signal
import subprocess
import sys
import tempfile
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--data", default="/work/shared/data/dev")
ap.add_argument("--meshes", nargs="+", help="subset of MANIFEST `file` entries")
ap.add_argument("--timeout", type=float, default=900, help="seconds per run before it is killed")
ap.add_argument("--max-load", type=float, default=1.5)
ap.add_argument("--quiet-wait", type=float, default=300)
ap.add_argument("--no-gmsh", action="store_true", help="skip the gmsh binary comparison")
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/tetfill.md"))
ap.add_argument("--exe", help="tetfill_tool binary (default: build it in BUILD_DIR)")
ap.add_argument("--render-only", action="store_true")
args = ap.parse_args()
build = os.environ.get("BUILD_DIR", os.path.join(root, "build-tetfill"))
if not os.path.isabs(build):
    build = os.path.join(root, build)
raw_path = os.path.join(build, "benchmarks/tetfill_runs.jsonl")
command_line = ("BUILD_DIR=%s " % os.path.relpath(build, root) if "BUILD_DIR" in os.environ
                else "") + "/usr/bin/python3 " + " ".join(
                    shlex.quote(a) for a in ["benchmarks/run_tetfill.py"] + sys.argv[1:])


def manifest():
    with open(os.path.join(args.data, "MANIFEST.tsv")) as f:
        lines = [l.rstrip("\n").split("\t") for l in f if l.strip()]
    return [dict(zip(lines[0], l)) for l in lines[1:]]


def load1():
    return os.getloadavg()[0]


def wait_quiet():
    waited = 0.0
    while load1() > args.max_load and waited < args.quiet_wait:
        time.sleep(20)
        waited += 20
    return load1()


def run(cmd, timeout):
    """Runs cmd; returns (exit code or None on timeout, stdout, wall seconds, peak RSS MB)."""
    start = time.monotonic()
    with tempfile.TemporaryFile() as out:
        p = subprocess.Popen(cmd, stdout=out, stderr=subprocess.DEVNULL, start_new_session=True)
        code, rss_kb = None, 0
        while True:
            pid, status, usage = os.wait4(p.pid, os.WNOHANG)
            if pid:
                code, rss_kb = os.waitstatus_to_exitcode(status), usage.ru_maxrss
                break
            if time.monotonic() - start > timeout:
                os.killpg(p.pid, signal.SIGKILL)
                _, _, usage = os.wait4(p.pid, 0)
                rss_kb = usage.ru_maxrss
                break
            time.sleep(0.05)
        p.returncode = code if code is not None else -9
        wall = time.monotonic() - start
        out.seek(0)
        return code, out.read().decode(errors="replace"), wall, rss_kb / 1024.0


def read_obj(path):
    V, F = [], []
    with open(path) as f:
        for line in f:
            w = line.split()
            if not w:
                continue
            if w[0] == "v":
                V.append(w[1:4])
            elif w[0] == "f":
                F.append([int(x.split("/")[0]) for x in w[1:4]])
    return V, F


def gmsh_binary(path, workdir):
    """gmsh -3 on the same surface (MSH 2.2, coordinates copied as text)."""
    V, F = read_obj(path)
    msh = os.path.join(workdir, "surface.msh")
    with open(msh, "w") as f:
        f.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n%d\n" % len(V))
        for i, v in enumerate(V):
            f.write("%d %s %s %s\n" % (i + 1, v[0], v[1], v[2]))
        f.write("$EndNodes\n$Elements\n%d\n" % len(F))
        for i, t in enumerate(F):
            f.write("%d 2 2 1 1 %d %d %d\n" % (i + 1, t[0], t[1], t[2]))
        f.write("$EndElements\n")
    geo = os.path.join(workdir, "fill.geo")
    with open(geo, "w") as f:
        f.write('Mesh.SaveAll = 1;\nMerge "surface.msh";\nSurface Loop(1) = {1};\nVolume(1) = {1};\n')
    out = os.path.join(workdir, "volume.msh")
    code, _, wall, rss = run(["gmsh", geo, "-3", "-nt", "1", "-format", "msh22", "-o", out,
                              "-v", "1"], args.timeout)
    tets, tris = None, None
    if code == 0 and os.path.exists(out):
        tets = tris = 0
        with open(out) as f:
            inside = False
            for line in f:
                if line.startswith("$Elements"):
                    inside = True
                    next(f)
                    continue
                if line.startswith("$EndElements"):
                    break
                if inside:
                    t = line.split(None, 2)[1]
                    tets += t == "4"
                    tris += t == "2"
    return {"gmsh_exit": code, "gmsh_tets": tets, "gmsh_triangles": tris,
            "gmsh_wall_s": round(wall, 3), "gmsh_rss_mb": round(rss, 1)}


def collect():
    exe = args.exe or os.path.join(build, "benchmarks/tetfill_tool")
    if not args.exe:
        subprocess.run(["cmake", "-S", root, "-B", build, "-G", "Ninja",
                        "-DCMAKE_BUILD_TYPE=RelWithDebInfo"], check=True,
                       stdout=subprocess.DEVNULL)
        subprocess.run(["ninja", "-C", build, "-j2", "tetfill_tool"], check=True,
                       stdout=subprocess.DEVNULL)
    os.makedirs(os.path.dirname(raw_path), exist_ok=True)
    rows = [m for m in manifest() if not args.meshes or m["file"] in args.meshes]
    with open(raw_path, "w") as raw:
        for m in rows:
            path = os.path.join(args.data, m["file"])
            rec = {"mesh": m["name"], "faces": int(m["F"]), "vertices": int(m["V"]),
                   "genus": m["genus"], "components": m["components"]}
            rec["load_at_start"] = round(wait_quiet(), 2)
            code, out, wall, rss = run([exe, path], args.timeout)
            rec["exit"] = code
            rec["wall_s"] = round(wall, 3)
            rec["rss_mb_wait4"] = round(rss, 1)
            try:
                rec["tool"] = json.loads(out.strip().splitlines()[-1])
            except (ValueError, IndexError):
                rec["tool"] = {"error": "no JSON output (exit %s)" % code}
            if not args.no_gmsh:
                wait_quiet()
                with tempfile.TemporaryDirectory() as d:
                    rec.update(gmsh_binary(path, d))
            raw.write(json.dumps(rec) + "\n")
            raw.flush()
            t = rec["tool"]
            print("%-20s exit %s tets %s valid %s %.2f s | gmsh -3: tets %s %.2f s" % (
                m["name"], code, t.get("tets"), t.get("valid"), wall, rec.get("gmsh_tets"),
                rec.get("gmsh_wall_s", 0.0)), file=sys.stderr)


def fmt(x, spec="%.2f"):
    return "–" if x is None else spec % x


def render():
    recs = [json.loads(l) for l in open(raw_path) if l.strip()]
    commit = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    L = []
    L.append("# Dense-linear baseline: boundary-preserving tet fill (`meshing/tetfill`)\n")
    L.append("- Command: `%s` (from the repository root)" % command_line)
    L.append("- Per mesh: `BUILD/benchmarks/tetfill_tool INPUT` = `fill_interior` (gmsh 4.8.4 "
             "C++ API, 3D Delaunay `Mesh.Algorithm3D=1`, default sizes extended from the boundary, "
             "`Mesh.Optimize=1`, 1 thread) + `verify_tetfill` (exact orient3d, oriented boundary "
             "faces vs input, volume); timeout %d s" % args.timeout)
    L.append("- Comparison: gmsh 4.8.4 binary, `gmsh fill.geo -3 -nt 1` on the same surface "
             "(MSH 2.2 discrete surface, `Surface Loop`/`Volume`); its output is not verified")
    L.append("- Date: %s; git commit %s; build RelWithDebInfo (`%s`)" % (
        datetime.datetime.now().strftime("%Y-%m-%d %H:%M"), commit, os.path.relpath(build, root)))
    L.append("- Machine: %d cores shared with other jobs; each run waits (≤ %d s) for 1-min load ≤ "
             "%.1f; load at start: max %.2f" % (os.cpu_count(), args.quiet_wait, args.max_load,
                                               max(r["load_at_start"] for r in recs)))
    L.append("- Raw JSON lines: `%s`\n" % os.path.relpath(raw_path, root))
    L.append("Columns: *tets* = output tets (the **dense-linear baseline** of the curved-meshing "
             "comparison); *int. V* = interior (Steiner) vertices, none on the boundary; *bnd faces* "
             "= boundary faces of the tet mesh (= input faces when valid); *valid* = "
             "`verify_tetfill` (all tets exactly positive, boundary faces = input faces as oriented "
             "triangles, input vertices bit-identical, volume error ≤ 1e-9); *vol. err* = |Σ tet "
             "volumes − enclosed volume| / enclosed; *fill s* = `fill_interior` (gmsh part in "
             "parentheses); *wall s* = process wall time incl. OBJ reading and a second "
             "verification; *RSS* = peak resident set of the process.\n")
    L.append("| mesh | faces | genus | tets | tets/face | int. V | bnd faces | valid | vol. err | "
             "fill s (gmsh) | wall s | RSS MB | gmsh -3 tets | gmsh -3 s | gmsh -3 RSS MB |")
    L.append("|---|--:|--:|--:|--:|--:|--:|:-:|--:|--:|--:|--:|--:|--:|--:|")
    ok = 0
    for r in recs:
        t = r["tool"]
        valid = t.get("valid")
        ok += bool(valid)
        if t.get("error"):
            cells = ["–"] * 4 + ["**no**: %s" % t["error"].replace("|", "/")[:160], "–", "–"]
        else:
            cells = [str(t["tets"]), "%.2f" % (t["tets"] / r["faces"]), str(t["interior_vertices"]),
                     str(t["boundary_faces"]), "yes" if valid else "**no**",
                     "%.1e" % t["volume_error_rel"],
                     "%.2f (%.2f)" % (t["seconds"], t["gmsh_seconds"])]
        g_tets = "–" if r.get("gmsh_tets") is None else str(r["gmsh_tets"])
        if r.get("gmsh_exit") not in (0, None):
            g_tets = "fail (exit %s)" % r["gmsh_exit"]
        L.append("| %s | %d | %s | %s | %s | %.1f | %s | %s | %s |" % (
            r["mesh"], r["faces"], r["genus"], " | ".join(cells), fmt(r["wall_s"]),
            t.get("peak_rss_mb", r["rss_mb_wait4"]), g_tets, fmt(r.get("gmsh_wall_s")),
            fmt(r.get("gmsh_rss_mb"), "%.0f")))
    L.append("\n%d of %d meshes filled and verified.\n" % (ok, len(recs)))
    with open(args.out, "w") as f:
        f.write("\n".join(L) + "\n")
    print("wrote", args.out, file=sys.stderr)


if not args.render_only:
    collect()
render()
