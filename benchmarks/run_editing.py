#!/usr/bin/python3
"""Side-by-side surface editing benchmark: curvefem's shortest-edge collapse, QSlim and isotropic
remeshing (meshing/editing/algorithms/surface_remeshing.hpp) vs CGAL 5.5 (SMS::edge_collapse with
Edge_length_cost + Midpoint_placement, SMS::GarlandHeckbert_plane_policies,
PMP::isotropic_remeshing with 5 iterations). CGAL runs serially; curvefem at 1 and 2 threads.
Targets: 10% of the input faces for the collapses; twice the input's mean edge length for isotropic
remeshing. Best of --repeat runs (by algorithm wall time), in rounds that interleave the engines.
Writes benchmarks/results/editing.md.

Usage (from the repository root):
  BUILD_DIR=build-release /usr/bin/python3 benchmarks/run_editing.py [--meshes armadillo igea]
It configures and builds the Release target curvefem_bench_editing itself. Before every run it
waits (at most --quiet-wait s) until other processes keep fewer than --max-busy cores busy and
flags the runs that started on a busy machine.
"""
import argparse
import datetime
import json
import os
import platform
import shlex
import subprocess
import sys
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--meshes", nargs="+", default=["armadillo", "igea"])
ap.add_argument("--data", default=os.path.join(os.path.dirname(root), "shared/data/dev"))
ap.add_argument("--algorithms", nargs="+",
                default=["shortest_collapse", "qslim", "isotropic"])
ap.add_argument("--repeat", type=int, default=2)
ap.add_argument("--face-ratio", type=float, default=0.1)
ap.add_argument("--edge-factor", type=float, default=2.0)
ap.add_argument("--timeout", type=float, default=600, help="seconds per run before it is killed")
ap.add_argument("--max-busy", type=float, default=0.3,
                help="before each run, wait until other processes use fewer than this many cores "
                     "(sampled over 1 s), for at most --quiet-wait seconds; flag the run otherwise")
ap.add_argument("--quiet-wait", type=float, default=300)
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/editing.md"))
ap.add_argument("--build-jobs", type=int, default=2)
ap.add_argument("--exe", help="use this curvefem_bench_editing binary instead of building one")
args = ap.parse_args()
build = os.environ.get("BUILD_DIR", os.path.join(root, "build-release"))
if not os.path.isabs(build):
    build = os.path.join(root, build)
command_line = ("BUILD_DIR=%s " % os.path.relpath(build, root) if "BUILD_DIR" in os.environ
                else "") + "/usr/bin/python3 " + " ".join(
                    shlex.quote(a) for a in [os.path.relpath(sys.argv[0], root)] + sys.argv[1:])

if args.exe:
    exe = os.path.abspath(args.exe)
else:
    subprocess.run(["cmake", "-S", root, "-B", build, "-G", "Ninja",
                    "-DCMAKE_BUILD_TYPE=Release"], check=True, stdout=subprocess.DEVNULL)
    subprocess.run(["cmake", "--build", build, "--target", "curvefem_bench_editing", "--parallel",
                    str(args.build_jobs)], check=True, stdout=subprocess.DEVNULL)
    exe = os.path.join(build, "benchmarks/curvefem_bench_editing")
raw_path = os.path.join(build, "benchmarks/editing_runs.jsonl")
os.makedirs(os.path.dirname(raw_path), exist_ok=True)
raw = open(raw_path, "w")

ALGO_TITLES = {
    "shortest_collapse": ("Shortest-edge collapse",
                          "CGAL: `SMS::edge_collapse` + `Edge_length_cost` + `Midpoint_placement`"),
    "qslim": ("QSlim (Garland–Heckbert)",
              "CGAL: `SMS::edge_collapse` + `GarlandHeckbert_plane_policies` (cost and placement)"),
    "isotropic": ("Isotropic remeshing",
                  "CGAL: `PMP::isotropic_remeshing(faces(mesh), target, mesh, "
                  "number_of_iterations(5))`"),
}


def load1():
    return os.getloadavg()[0]


def busy_cores(interval=1.0):
    """Cores kept busy by other processes over `interval` seconds (from /proc/stat)."""
    def sample():
        with open("/proc/stat") as f:
            v = [int(x) for x in f.readline().split()[1:]]
        return sum(v), v[3] + v[4]  # total, idle + iowait
    t0, i0 = sample()
    time.sleep(interval)
    t1, i1 = sample()
    return (os.cpu_count() or 1) * (1 - (i1 - i0) / max(1, t1 - t0))


def wait_quiet():
    """Waits (up to --quiet-wait s) for a quiet machine; returns the last busy-core sample."""
    deadline = time.time() + args.quiet_wait
    busy = busy_cores()
    while busy > args.max_busy and time.time() < deadline:
        busy = busy_cores(5.0)
    return busy


def run(cmd):
    """One run: the JSON record, or a record with `error` (crash, timeout, bad output)."""
    busy = wait_quiet()
    load = load1()
    t0 = time.time()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
    except subprocess.TimeoutExpired:
        r = {"error": "timeout after %.0f s" % args.timeout}
    else:
        if p.returncode != 0:
            r = {"error": "exit code %d: %s" % (p.returncode, p.stderr.strip()[-500:])}
        else:
            try:
                r = json.loads(p.stdout.strip().splitlines()[-1])
            except (ValueError, IndexError):
                r = {"error": "no JSON output: %s" % (p.stdout + p.stderr)[-500:]}
    r["command"] = " ".join(shlex.quote(c) for c in cmd)
    r["load_before"] = load
    r["busy_before"] = busy
    r["process_s"] = time.time() - t0
    raw.write(json.dumps(r) + "\n")
    raw.flush()
    status = r.get("error") or "%.3f s, %s faces" % (r["seconds"], r["output_faces"])
    print("  %-95s load %.2f busy %.2f  %s" % (
        r["command"].replace(os.path.dirname(exe) + "/", ""), load, busy, status), file=sys.stderr)
    return r


def best(runs):
    """The fastest of a configuration's runs; the first failure if any run failed."""
    failed = [r for r in runs if "error" in r]
    if failed:
        return failed[0]
    b = dict(min(runs, key=lambda x: x["seconds"]))
    b["all_seconds"] = [x["seconds"] for x in runs]
    b["max_load_before"] = max(x["load_before"] for x in runs)
    b["max_busy_before"] = max(x["busy_before"] for x in runs)
    return b


def fmt(x, f="%.3f"):
    return "—" if x is None else f % x


machine = platform.node()
try:
    with open("/proc/cpuinfo") as f:
        machine = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name"))
except (OSError, StopIteration):
    pass
try:
    commit = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", root, "status", "--porcelain", "--", "meshing",
                            "benchmarks"], capture_output=True, text=True).stdout.strip()
    commit += " (with uncommitted changes)" if dirty else ""
except OSError:
    commit = "?"

inputs = {}
for m in args.meshes:
    path = os.path.join(args.data, m + ".obj")
    info = json.loads(subprocess.run([exe, path, "info"], check=True, capture_output=True,
                                     text=True).stdout.strip().splitlines()[-1])
    info["path"] = path
    info["target_faces"] = int(info["input_faces"] * args.face_ratio)
    info["target_edge"] = args.edge_factor * info["input_mean_edge"]
    inputs[m] = info
    print("%s: %d faces, mean edge %.6g -> target faces %d, target edge %.6g" % (
        m, info["input_faces"], info["input_mean_edge"], info["target_faces"],
        info["target_edge"]), file=sys.stderr)

CONFIGS = [("cgal", 1), ("curvefem", 1), ("curvefem", 2)]
results = {}  # (algorithm, mesh, engine, threads) -> record
for algo in args.algorithms:
    for m in args.meshes:
        info = inputs[m]
        target = (["--target-edge", repr(info["target_edge"])] if algo == "isotropic"
                  else ["--target-faces", str(info["target_faces"])])
        runs = {c: [] for c in CONFIGS}
        # Rounds interleave the engines, so that a slow phase of the machine hits all of them.
        for _ in range(args.repeat):
            for engine, threads in CONFIGS:
                if any("error" in r for r in runs[(engine, threads)]):
                    continue  # a crash or timeout is not repeated
                cmd = [exe, info["path"], algo] + target + ["--threads", str(threads),
                                                            "--engine", engine]
                runs[(engine, threads)].append(run(cmd))
        for (engine, threads), rs in runs.items():
            results[(algo, m, engine, threads)] = best(rs)
raw.close()


def checks(algo, info, r):
    """Plausibility flags for one output (empty when it looks sane)."""
    if "error" in r:
        return ["**%s**" % r["error"]]
    flags = []
    q = r["quality"]
    if algo != "isotropic":
        t = info["target_faces"]
        if r["output_faces"] > t * 1.02 or r["output_faces"] < t * 0.9:
            flags.append("face count %d far from target %d" % (r["output_faces"], t))
    else:
        ratio = q["mean_edge"] / info["target_edge"]
        if not 0.7 <= ratio <= 1.3:
            flags.append("mean edge %.2f× target" % ratio)
    if max(q["max_deviation_rel"], q["max_deviation_from_reference_rel"]) > 0.05:
        flags.append("deviation > 5% of bbox")
    if q["min_angle_deg"] < 0.01:
        flags.append("near-degenerate faces (min angle %.2g°)" % q["min_angle_deg"])
    if r.get("max_busy_before", 0) > args.max_busy:
        flags.append("machine busy (%.1f cores) before a run" % r["max_busy_before"])
    return flags


out = []
out.append("# Surface editing: curvefem vs CGAL %s\n" % "5.5")
out.append("Generated by `benchmarks/run_editing.py`; do not edit by hand.\n")
out.append("- Command: `%s`" % command_line)
out.append("- Date: %s" % datetime.datetime.now().strftime("%Y-%m-%d %H:%M"))
out.append("- Machine: %s, %d hardware threads, %s %s, Python %s" % (
    machine, os.cpu_count(), platform.system(), platform.release(), platform.python_version()))
out.append("- curvefem: %s, Release (`-O3 -DNDEBUG`), build dir `%s`" % (
    commit, os.path.relpath(build, root)))
out.append("- CGAL 5.5 (Debian libcgal-dev), `Surface_mesh<Epick::Point_3>`, serial (CGAL's "
           "SMS and isotropic remeshing have no parallel mode); curvefem at 1 and 2 threads "
           "(`RemeshOptions::threads` + `tbb::global_control`).")
out.append("- Each figure is the best of %d runs, in rounds that interleave CGAL, curvefem 1 "
           "thread and curvefem 2 threads (algorithm wall time; loading, conversions and quality "
           "measurement excluded; for curvefem the whole `remesh()` call, including its own mesh "
           "construction and export). Raw records: `%s`." % (
               args.repeat, os.path.relpath(raw_path, root)))
out.append("- Targets: %g%% of the input faces (collapses, stop at or below); %g × the input's "
           "mean edge length (isotropic, 5 iterations, no envelope)." % (
               100 * args.face_ratio, args.edge_factor))
out.append("- Quality: curvefem's `measure_quality(output, input)` for both engines. Deviation "
           "columns are one-sided Hausdorff estimates divided by the input's longest bounding-box "
           "edge: output→input / input→output. Valence-6 = share of output vertices of valence "
           "6.\n")
out.append("| input | faces | vertices | mean edge | bbox edge | target faces | target edge |")
out.append("|---|---:|---:|---:|---:|---:|---:|")
for m in args.meshes:
    i = inputs[m]
    out.append("| %s | %d | %d | %.4g | %.4g | %d | %.4g |" % (
        m, i["input_faces"], i["input_vertices"], i["input_mean_edge"], i["bbox_longest_edge"],
        i["target_faces"], i["target_edge"]))
out.append("")

summary = []
goals = []  # (serial goal met, speedup goal met) per measured algorithm and input
for algo in args.algorithms:
    title, peer = ALGO_TITLES[algo]
    out.append("## %s\n" % title)
    out.append(peer + "; curvefem: `remesh(input, {algorithm = %s})`.\n" % algo)
    out.append("| input | engine | threads | output faces | seconds | ratio to CGAL | speedup 1→2 "
               "| min angle (°) | max dev. out→in / in→out (rel.) | mean edge | valence-6 | "
               "notes |")
    out.append("|---|---|---:|---:|---:|---:|---:|---:|---|---:|---:|---|")
    for m in args.meshes:
        info = inputs[m]
        cg = results[(algo, m, "cgal", 1)]
        c1 = results[(algo, m, "curvefem", 1)]
        c2 = results[(algo, m, "curvefem", 2)]
        for engine, threads in CONFIGS:
            r = results[(algo, m, engine, threads)]
            if "error" in r:
                out.append("| %s | %s | %d | — | — | — | — | — | — | — | — | %s |" % (
                    m, engine, threads, "; ".join(checks(algo, info, r))))
                continue
            q = r["quality"]
            ratio = (r["seconds"] / cg["seconds"] if engine == "curvefem" and "error" not in cg
                     else None)
            speedup = (c1["seconds"] / c2["seconds"]
                       if (engine, threads) == ("curvefem", 2) and "error" not in c1 else None)
            out.append("| %s | %s | %d | %d | %.3f | %s | %s | %.2f | %.2e / %.2e | %.4g | "
                       "%.1f%% | %s |" % (
                           m, "CGAL" if engine == "cgal" else "curvefem", threads,
                           r["output_faces"], r["seconds"], fmt(ratio, "%.2f×"),
                           fmt(speedup, "%.2f×"), q["min_angle_deg"], q["max_deviation_rel"],
                           q["max_deviation_from_reference_rel"], q["mean_edge"],
                           100 * q["valence6_share"], "; ".join(checks(algo, info, r))))
        # goals, per algorithm and input
        if any("error" in x for x in (cg, c1, c2)):
            summary.append("- %s on %s: **not measured** (%s)." % (
                title, m, "; ".join(x["error"] for x in (cg, c1, c2) if "error" in x)))
            continue
        ratio = c1["seconds"] / cg["seconds"]
        speedup = c1["seconds"] / c2["seconds"]
        bad = [f for x in (c1, c2) for f in checks(algo, info, x)]
        q, qc = c1["quality"], cg["quality"]
        goals.append((ratio <= 1.5, speedup >= 1.6))
        summary.append("- %s on %s: serial %.2f× CGAL (goal ≤ 1.5×: %s), 2-thread speedup "
                       "%.2f× (goal ≥ 1.6×: %s)%s. Serial output vs CGAL's: %d vs %d faces, "
                       "min angle %.2f° vs %.2f°, valence-6 %.0f%% vs %.0f%%, max deviation "
                       "out→in %.2e vs %.2e." % (
                           title, m, ratio, "**met**" if ratio <= 1.5 else "**not met**",
                           speedup, "**met**" if speedup >= 1.6 else "**not met**",
                           "; output flagged: " + "; ".join(bad) if bad else "",
                           c1["output_faces"], cg["output_faces"], q["min_angle_deg"],
                           qc["min_angle_deg"], 100 * q["valence6_share"],
                           100 * qc["valence6_share"], q["max_deviation_rel"],
                           qc["max_deviation_rel"]))
    out.append("")
    # where curvefem's time goes (per scheduler pass, best serial and 2-thread runs)
    rows = []
    for m in args.meshes:
        for threads in (1, 2):
            r = results[(algo, m, "curvefem", threads)]
            if "error" in r or not r.get("passes"):
                continue
            agg = {}
            for p in r["passes"]:
                a = agg.setdefault(p["name"], [0, 0.0, 0, 0])
                a[0] += 1
                a[1] += p["seconds"]
                a[2] += p["succeeded"]
                a[3] += p["attempted"]
            rows.append("| %s | %d | %.3f | %s |" % (
                m, threads, r["seconds"] - sum(p["seconds"] for p in r["passes"]),
                "; ".join("%s ×%d: %.3f s, %d/%d ok" % (n, a[0], a[1], a[2], a[3])
                          for n, a in agg.items())))
    if rows:
        out.append("curvefem time per pass (summed over repeated passes; 'other' = remesh() wall "
                   "time outside the passes):\n")
        out.append("| input | threads | other (s) | passes |")
        out.append("|---|---:|---:|---|")
        out += rows
        out.append("")

out.append("## Summary\n")
out.append("Goals: serial curvefem within 1.5× of CGAL's time, 2-thread speedup ≥ 1.6×. Of the "
           "%d measured algorithm × input cases, the serial goal is met in %d and the speedup "
           "goal in %d.\n" % (len(goals), sum(a for a, _ in goals), sum(b for _, b in goals)))
out += summary
busy = [r["max_busy_before"] for r in results.values() if "max_busy_before" in r]
loads = [r["max_load_before"] for r in results.values() if "max_load_before" in r]
if busy and max(busy) > args.max_busy:
    out.append("\nNote: some runs started while other processes kept %.1f cores busy: their "
               "timings may be noisy." % max(busy))
elif busy:
    out.append("\nEvery run started on a quiet machine (other processes < %.1f cores, sampled "
               "over 1 s before each run; 1-minute load average, which includes the previous "
               "benchmark run, at most %.1f)." % (args.max_busy, max(loads)))
out.append("")

os.makedirs(os.path.dirname(args.out), exist_ok=True)
with open(args.out, "w") as f:
    f.write("\n".join(out) + "\n")
print("wrote %s" % args.out, file=sys.stderr)
