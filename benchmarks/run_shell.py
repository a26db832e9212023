#!/usr/bin/python3
"""Prismatic shell benchmark over the dev meshes (/work/shared/data/dev/MANIFEST.tsv, column
`file`). For every mesh it runs `curvefem shell INPUT -o DIR -q` in three modes:
  full       --no-simplify --threads 1   (the input stays the middle surface)
  simp_t1    default (simplified) shell, --threads 1
  simp_t2    default (simplified) shell, --threads 2
and collects DIR/report.json, the exit code (0 = positive and intersection-free, 3 = a
verification failed, 2 = bad input, other = crash), the wall time measured here and the peak RSS
from wait4(). Writes benchmarks/results/shell.md; raw JSON lines go to
BUILD_DIR/benchmarks/shell_runs.jsonl (outside the repository).

Usage (from the repository root):
  /usr/bin/python3 benchmarks/run_shell.py [--meshes knight_decimated.obj ...] [--timeout 600]
  /usr/bin/python3 benchmarks/run_shell.py --render-only   # rewrite shell.md from the .jsonl
It configures and builds the Release target curvefem in BUILD_DIR (default build-bench-shell,
-j2) unless --exe is given. Before each run it waits (sleep 20 s, at most --quiet-wait s) while
the 1-minute load average exceeds --max-load, and records the load at the start of the run.
Standard library only.
"""
import argparse
import datetime
import json
import os
import shlex
import signal
import statistics
import subprocess
import sys
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--data", default="/work/shared/data/dev")
ap.add_argument("--meshes", nargs="+", help="subset of MANIFEST `file` entries")
ap.add_argument("--modes", nargs="+", default=["full", "simp_t1", "simp_t2"])
ap.add_argument("--timeout", type=float, default=600, help="seconds per run before it is killed")
ap.add_argument("--max-load", type=float, default=1.5)
ap.add_argument("--quiet-wait", type=float, default=300)
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/shell.md"))
ap.add_argument("--build-jobs", type=int, default=2)
ap.add_argument("--exe", help="use this curvefem binary instead of building one")
ap.add_argument("--render-only", action="store_true",
                help="do not run anything; rewrite the report from the existing .jsonl")
args = ap.parse_args()
build = os.environ.get("BUILD_DIR", os.path.join(root, "build-bench-shell"))
if not os.path.isabs(build):
    build = os.path.join(root, build)
raw_path = os.path.join(build, "benchmarks/shell_runs.jsonl")
command_line = ("BUILD_DIR=%s " % os.path.relpath(build, root) if "BUILD_DIR" in os.environ
                else "") + "/usr/bin/python3 " + " ".join(
                    shlex.quote(a) for a in ["benchmarks/run_shell.py"] + sys.argv[1:])

MODES = {
    "full": (["--no-simplify", "--threads", "1"], "Full input as middle surface (`--no-simplify --threads 1`)"),
    "simp_t1": (["--threads", "1"], "Simplified shell, 1 thread (`--threads 1`)"),
    "simp_t2": (["--threads", "2"], "Simplified shell, 2 threads (`--threads 2`)"),
}
THESIS_RATIO = 0.07
THESIS_SECONDS = 360.0
GOAL_SECONDS = 10.0


def manifest():
    with open(os.path.join(args.data, "MANIFEST.tsv")) as f:
        lines = [l.rstrip("\n").split("\t") for l in f if l.strip()]
    head = lines[0]
    return [dict(zip(head, l)) for l in lines[1:]]


def git_info():
    commit = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", root, "status", "--porcelain"],
                           capture_output=True, text=True).stdout.strip()
    return commit + (" (with uncommitted changes)" if dirty else "")


def machine():
    model, cpus = "?", str(os.cpu_count())
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        for line in out.splitlines():
            k, _, v = line.partition(":")
            if k.strip() == "Model name":
                model = v.strip()
            elif k.strip() == "CPU(s)":
                cpus = v.strip()
    except OSError:
        pass
    return "%s, %s cores (lscpu CPU(s))" % (model, cpus)


def wait_quiet():
    waited = 0.0
    while os.getloadavg()[0] > args.max_load and waited < args.quiet_wait:
        time.sleep(20)
        waited += 20
    return os.getloadavg()[0], waited


def run_one(mesh, mode, exe):
    outdir = os.path.join(build, "benchmarks/shell_out", os.path.splitext(mesh)[0] + "_" + mode)
    os.makedirs(outdir, exist_ok=True)
    report_path = os.path.join(outdir, "report.json")
    if os.path.exists(report_path):
        os.remove(report_path)
    cmd = [exe, "shell", os.path.join(args.data, mesh), "-o", outdir] + MODES[mode][0] + ["-q"]
    load, waited = wait_quiet()
    err_path = os.path.join(outdir, "stderr.txt")
    rec = {"mesh": mesh, "mode": mode, "command": " ".join(shlex.quote(c) for c in cmd),
           "load1_at_start": round(load, 2), "waited_for_quiet_s": waited,
           "busy_at_start": load > args.max_load,
           "date": datetime.datetime.now().isoformat(timespec="seconds")}
    with open(err_path, "w") as err, open(os.path.join(outdir, "stdout.txt"), "w") as out:
        t0 = time.perf_counter()
        p = subprocess.Popen(cmd, stdout=out, stderr=err, start_new_session=True)
        timed_out = False
        while True:
            pid, status, ru = os.wait4(p.pid, os.WNOHANG)
            if pid:
                break
            if time.perf_counter() - t0 > args.timeout:
                timed_out = True
                os.killpg(p.pid, signal.SIGKILL)
                pid, status, ru = os.wait4(p.pid, 0)
                break
            time.sleep(0.02)
        wall = time.perf_counter() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    rec.update({"exit": "timeout" if timed_out else p.returncode, "wall_s": round(wall, 3),
                "rusage_maxrss_mb": round(ru.ru_maxrss / 1024.0, 1)})
    with open(err_path) as f:
        rec["stderr_tail"] = f.read().splitlines()[-15:]
    if not timed_out and os.path.exists(report_path):
        with open(report_path) as f:
            try:
                rec["report"] = json.load(f)
            except ValueError as e:
                rec["report_error"] = str(e)
    return rec


# ---------------------------------------------------------------- rendering

def failure_paragraph(records, meshes):
    """Data-driven summary of what did not verify, across all modes."""
    reps = [r for r in records if r.get("report")]
    sec_meshes = sorted({r["mesh"] for r in reps if not r["report"]["is_section_verified"]})
    sec_ok = sorted({r["mesh"] for r in reps} - set(sec_meshes))
    hard = sorted({r["mesh"] for r in reps if not (r["report"]["positive_verified"] and
                                                   r["report"]["intersection_free_verified"])})
    nobuild = sorted({r["mesh"] for r in records if not r.get("report")})
    short = lambda ms: ", ".join(os.path.splitext(m)[0] for m in ms) or "none"
    txt = []
    txt.append("Shell not built or not reported (crash, timeout or bad input) in at least one "
               "mode: %d of %d meshes (%s)." % (len(nobuild), len(meshes), short(nobuild)))
    txt.append("Positivity or intersection-freeness (the exit-0 guarantees) failed in at least "
               "one mode on %d meshes (%s)." % (len(hard), short(hard)))
    txt.append("The section condition (every prism projects bijectively onto its base along its "
               "pillars) is violated in at least one mode on %d of %d meshes; it holds "
               "everywhere only on %s. Topological beveling runs only where the exact section "
               "check fails (`beveling` in report.json); a shell still failing it exits 0 when "
               "positivity and intersection-freeness hold, because the section check is "
               "reported, not enforced." % (len(sec_meshes), len(meshes), short(sec_ok)))
    return " ".join(txt)


def fmt(v, spec="%.3g"):
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else "**no**"
    return spec % v


def median(xs):
    return statistics.median(xs) if xs else None


def mean(xs):
    return statistics.fmean(xs) if xs else None


def crashed(r):
    return r["exit"] == "timeout" or r["exit"] not in (0, 2, 3)


def render(records, meta):
    by = {(r["mesh"], r["mode"]): r for r in records}
    meshes = meta["meshes"]
    modes = [m for m in MODES if any((x, m) in by for x in meshes)]
    L = []
    w = L.append
    w("# Prismatic shell benchmark (`curvefem shell`)")
    w("")
    w("- Command: `%s` (from the repository root)" % meta["command"])
    w("- Per run: `curvefem shell INPUT -o DIR [--no-simplify] --threads N -q`, timeout %d s"
      % meta["timeout"])
    w("- Date: %s" % meta["date"])
    w("- Machine: %s; shared with other jobs, each run waits (≤ %d s) until the 1-min load "
      "average is ≤ %.1f; the load at start is in the raw data" %
      (meta["machine"], meta["quiet_wait"], meta["max_load"]))
    w("- Git commit: %s" % meta["git"])
    w("- Build: Release (`-DCMAKE_BUILD_TYPE=Release`, Ninja), %s" % meta["exe"])
    w("- Data: %d meshes of `%s/MANIFEST.tsv`; raw JSON lines: `%s`" %
      (len(meshes), meta["data"], meta["raw"]))
    busy = [r for r in records if r.get("busy_at_start")]
    loads = [r["load1_at_start"] for r in records]
    w("- 1-min load at run start: median %.2f, max %.2f; %d of %d runs started above %.1f "
      "(after waiting the maximum)" % (median(loads), max(loads), len(busy), len(records),
                                       meta["max_load"]))
    w("")
    w("Columns: *faces* = input faces; *prisms/in* = prisms per input face; *sing.* = singular "
      "vertices (pinch splits); thickness = half-pillar length relative to the longest bbox edge; "
      "*pos.* = all prisms positive (non-positive count); *int.-free* = shell free of "
      "intersections with the input (input faces intersecting); *section* = every prism is a "
      "section (non-section prisms); *roundtrip* = max relative error of the input → shell → "
      "input map (failures); *total s* = `time_s.total` from the report (simplify stage in "
      "parentheses); *wall s* = measured by the script (includes I/O); *RSS* = `peak_rss_mb`.")
    w("")
    for mode in modes:
        w("## %s" % MODES[mode][1])
        w("")
        w("| mesh | faces | prisms | prisms/in | sing. | min thick. | med. thick. | pos. | "
          "int.-free | section | roundtrip | total s (simplify) | wall s | RSS MB | exit |")
        w("|---|--:|--:|--:|--:|--:|--:|:-:|:-:|:-:|--:|--:|--:|--:|:-:|")
        for m in meshes:
            r = by.get((m, mode))
            if r is None:
                continue
            rep = r.get("report")
            name = os.path.splitext(m)[0]
            ex = r["exit"]
            exs = ("**%s**" % ex) if crashed(r) else str(ex)
            if rep is None:
                w("| %s | %s | – | – | – | – | – | – | – | – | – | – | %s | %s | %s |" %
                  (name, meta["faces"].get(m, "?"),
                   ">%d" % meta["timeout"] if ex == "timeout" else "%.2f" % r["wall_s"],
                   fmt(r.get("rusage_maxrss_mb"), "%.0f"), exs))
                continue
            ts = rep.get("time_s", {})
            simp = ts.get("simplify")
            tot = "%.2f" % ts["total"] if ts.get("total") is not None else "–"
            if rep.get("simplified") and simp is not None:
                tot += " (%.2f)" % simp
            w("| %s | %d | %d | %.1f%% | %d (%d) | %s | %s | %s | %s | %s | %s | %s | %.2f | %s "
              "| %s |" % (
                  name, rep["input_faces"], rep["prisms"], 100 * rep["prisms_per_input_face"],
                  rep["singular_vertices"], rep["pinch_splits"],
                  fmt(rep["min_thickness_rel"], "%.2g"), fmt(rep["median_thickness_rel"], "%.2g"),
                  fmt(rep["positive_verified"]) + ("" if rep["positive_verified"] else
                                                   " (%d)" % rep["non_positive_prisms"]),
                  fmt(rep["intersection_free_verified"]) +
                  ("" if rep["intersection_free_verified"] else
                   " (%d)" % rep["input_faces_intersecting_shell"]),
                  fmt(rep["is_section_verified"]) + ("" if rep["is_section_verified"] else
                                                     " (%d)" % rep["non_section_prisms"]),
                  fmt(rep["roundtrip_max_error_rel"], "%.1e") +
                  (" (%d fail)" % rep["roundtrip_failures"] if rep["roundtrip_failures"] else ""),
                  tot, r["wall_s"], fmt(rep.get("peak_rss_mb"), "%.0f"), exs))
        w("")

    # ---------------- summary
    w("## Summary")
    w("")
    w("Times are `time_s.total` of the runs that produced a report (exit 0 or 3); timeouts and "
      "crashes are listed separately and are not in the medians.")
    w("")
    w("| mode | runs | reports | median s | mean s | max s | median prisms/in | mean prisms/in | "
      "positive | intersection-free | section | roundtrip ok | exit 0 | exit 3 | crash/timeout |")
    w("|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|")
    stats = {}
    for mode in modes:
        rs = [by[(m, mode)] for m in meshes if (m, mode) in by]
        reps = [r["report"] for r in rs if r.get("report")]
        times = [p["time_s"]["total"] for p in reps]
        ratios = [p["prisms_per_input_face"] for p in reps]
        n = len(reps)
        st = dict(runs=len(rs), n=n, med=median(times), mean=mean(times),
                  max=max(times) if times else None, rmed=median(ratios), rmean=mean(ratios),
                  pos=sum(p["positive_verified"] for p in reps),
                  inter=sum(p["intersection_free_verified"] for p in reps),
                  sec=sum(p["is_section_verified"] for p in reps),
                  rt=sum(p["roundtrip_failures"] == 0 for p in reps),
                  e0=sum(r["exit"] == 0 for r in rs), e3=sum(r["exit"] == 3 for r in rs),
                  bad=sum(crashed(r) for r in rs))
        stats[mode] = st
        w("| %s | %d | %d | %s | %s | %s | %s | %s | %d/%d | %d/%d | %d/%d | %d/%d | %d | %d | %d |"
          % (mode, st["runs"], n, fmt(st["med"], "%.2f"), fmt(st["mean"], "%.2f"),
             fmt(st["max"], "%.2f"),
             fmt(st["rmed"] and 100 * st["rmed"], "%.1f%%"),
             fmt(st["rmean"] and 100 * st["rmean"], "%.1f%%"),
             st["pos"], n, st["inter"], n, st["sec"], n, st["rt"], n, st["e0"], st["e3"],
             st["bad"]))
    w("")
    # speedup of the simplify stage
    sp = []
    for m in meshes:
        a, b = by.get((m, "simp_t1")), by.get((m, "simp_t2"))
        if a and b and a.get("report") and b.get("report"):
            s1 = a["report"]["time_s"].get("simplify")
            s2 = b["report"]["time_s"].get("simplify")
            if s1 and s2:
                sp.append((s1 / s2, m, s1, s2))
    if sp:
        w("- 2-thread speedup of the simplify stage (`time_s.simplify`, 1 thread / 2 threads): "
          "median **%.2f×** over %d meshes (min %.2f× on %s, max %.2f× on %s)." %
          (median([x[0] for x in sp]), len(sp), min(sp)[0], os.path.splitext(min(sp)[1])[0],
           max(sp)[0], os.path.splitext(max(sp)[1])[0]))
        tot = []
        for m in meshes:
            a, b = by.get((m, "simp_t1")), by.get((m, "simp_t2"))
            if a and b and a.get("report") and b.get("report"):
                tot.append(a["report"]["time_s"]["total"] / b["report"]["time_s"]["total"])
        if tot:
            w("- 2-thread speedup of the whole run (`time_s.total`): median %.2f×." % median(tot))
    for mode in ("simp_t1", "simp_t2"):
        if mode in stats and stats[mode]["med"] is not None:
            st = stats[mode]
            ok = st["med"] < GOAL_SECONDS and st["bad"] == 0
            w("- Goal \"median under %g s per model\", %s: median %.2f s over %d reports%s → "
              "**%s**." % (GOAL_SECONDS, mode, st["med"], st["n"],
                           (", %d run(s) without report" % (st["runs"] - st["n"]))
                           if st["runs"] > st["n"] else "",
                           "met" if ok else "not met"))
    for mode in modes:
        reps = [by[(m, mode)]["report"] for m in meshes
                if (m, mode) in by and by[(m, mode)].get("report")]
        rss = [(p.get("peak_rss_mb") or 0, os.path.splitext(os.path.basename(p["input"]))[0])
               for p in reps if p.get("peak_rss_mb") is not None]
        if rss:
            w("- Peak RSS, %s: median %.0f MB, max %.0f MB (%s)." %
              (mode, median([x[0] for x in rss]), max(rss)[0], max(rss)[1]))
    for mode in ("simp_t1", "simp_t2"):
        stalled = [os.path.splitext(m)[0] + " (%.0f%%)" % (100 * by[(m, mode)]["report"]
                                                          ["prisms_per_input_face"])
                   for m in meshes if (m, mode) in by and by[(m, mode)].get("report") and
                   by[(m, mode)]["report"]["prisms_per_input_face"] > 0.9]
        if stalled:
            w("- Simplification removed less than 10%% of the faces (%s): %s." %
              (mode, ", ".join(stalled)))
    w("- The 2-thread runs started at the 1-min load given at the top (on a quiet machine, a "
      "load near 1 is mostly the previous run's own load decaying). On 2 cores the second "
      "thread competes with anything else running, so the speedups are lower bounds for an "
      "idle machine.")
    # stage breakdown for the simplified single-thread mode
    for mode in ("simp_t1",):
        reps = [by[(m, mode)]["report"] for m in meshes
                if (m, mode) in by and by[(m, mode)].get("report")]
        if reps:
            keys = []
            for p in reps:
                for k in p["time_s"]:
                    if k not in keys and k != "total":
                        keys.append(k)
            tot = sum(p["time_s"]["total"] for p in reps)
            parts = ", ".join("%s %.0f%%" % (k, 100 * sum(p["time_s"].get(k, 0) for p in reps)
                                             / tot) for k in keys)
            w("- Share of the summed `time_s.total` of %s per stage: %s." % (mode, parts))
    w("")

    # ---------------- failures
    w("## Failures")
    w("")
    bad = [r for r in records if crashed(r)]
    if bad:
        w("Runs that crashed or timed out (exit code not in {0, 2, 3}):")
        w("")
        for r in bad:
            tail = [l for l in r.get("stderr_tail", []) if l.strip()][-3:]
            w("- %s, %s: exit %s after %.1f s; `%s`%s" % (
                os.path.splitext(r["mesh"])[0], r["mode"], r["exit"], r["wall_s"], r["command"],
                ("; stderr tail: `%s`" % " / ".join(tail)) if tail else "; no stderr"))
        w("")
    else:
        w("No run crashed or timed out.")
        w("")
    bad_input = [r for r in records if r["exit"] == 2]
    if bad_input:
        w("Rejected as bad input (exit 2): %s." % ", ".join(
            "%s (%s)" % (os.path.splitext(r["mesh"])[0], r["mode"]) for r in bad_input))
        w("")
    for mode in modes:
        rs = [by[(m, mode)] for m in meshes if (m, mode) in by and by[(m, mode)].get("report")]
        names = lambda pred: [os.path.splitext(r["mesh"])[0] for r in rs if pred(r["report"])]
        nonpos = names(lambda p: not p["positive_verified"])
        inter = names(lambda p: not p["intersection_free_verified"])
        sec = names(lambda p: not p["is_section_verified"])
        rt = names(lambda p: p["roundtrip_failures"] > 0)
        nosec = [r["report"]["non_section_prisms"] / max(1, r["report"]["prisms"]) for r in rs
                 if not r["report"]["is_section_verified"]]
        w("- **%s**: not positive: %s; not intersection-free: %s; roundtrip failures: %s; "
          "section violated on %d of %d meshes%s." % (
              mode, ", ".join(nonpos) or "none", ", ".join(inter) or "none",
              ", ".join(rt) or "none", len(sec), len(rs),
              (" (median %.0f%% of the prisms non-section; section holds on: %s)" %
               (100 * median(nosec), ", ".join(names(lambda p: p["is_section_verified"])) or
                "none")) if sec else ""))
    w("")
    w(failure_paragraph(records, meshes))
    w("")

    # ---------------- thesis comparison
    w("## Comparison with the thesis")
    w("")
    parts = []
    for mode in ("simp_t1", "simp_t2"):
        if mode in stats and stats[mode]["rmean"] is not None:
            st = stats[mode]
            parts.append("%s: mean %.1f%% prisms/input (median %.1f%%), mean %.1f s, median "
                         "%.2f s per model" % (mode, 100 * st["rmean"], 100 * st["rmed"],
                                               st["mean"], st["med"]))
    fc = [int(meta["faces"][m]) for m in meshes if str(meta["faces"].get(m, "")).isdigit()] or [0]
    w("The thesis reports on Thingi10k an average of %.0f%% prisms per input face and an average "
      "of %.0f minutes per model. Here: %s. These are not like-for-like: a different dataset "
      "(%d dev meshes, %s–%s input faces, several CAD parts with slivers, instead of the ~10 000 "
      "Thingi10k models), a different machine (%s, shared) and a different implementation "
      "(the section condition is reported, not enforced, and no dev mesh needs beveling)." %
      (100 * THESIS_RATIO, THESIS_SECONDS / 60, "; ".join(parts) or "no report",
       len(meshes), min(fc), max(fc), meta["machine"]))
    w("")
    return "\n".join(L)


def main():
    rows = manifest()
    files = [r["file"] for r in rows]
    faces = {r["file"]: r.get("F", "?") for r in rows}
    if args.meshes:
        unknown = [m for m in args.meshes if m not in files]
        if unknown:
            sys.exit("not in MANIFEST.tsv: %s" % ", ".join(unknown))
        files = [f for f in files if f in args.meshes]
    meta_path = os.path.join(build, "benchmarks/shell_meta.json")
    if args.render_only:
        with open(raw_path) as f:
            records = [json.loads(l) for l in f if l.strip()]
        with open(meta_path) as f:
            meta = json.load(f)
    else:
        if args.exe:
            exe = os.path.abspath(args.exe)
        else:
            subprocess.run(["cmake", "-S", root, "-B", build, "-G", "Ninja",
                            "-DCMAKE_BUILD_TYPE=Release"], check=True, stdout=subprocess.DEVNULL)
            subprocess.run(["ninja", "-C", build, "-j%d" % args.build_jobs, "curvefem"],
                           check=True, stdout=subprocess.DEVNULL)
            exe = os.path.join(build, "tools/curvefem/curvefem")
        os.makedirs(os.path.dirname(raw_path), exist_ok=True)
        meta = {"command": command_line, "timeout": args.timeout, "max_load": args.max_load,
                "quiet_wait": args.quiet_wait,
                "date": datetime.datetime.now().strftime("%Y-%m-%d %H:%M %Z").strip(),
                "machine": machine(), "git": git_info(), "exe": os.path.relpath(exe, root),
                "data": args.data, "raw": os.path.relpath(raw_path, root),
                "meshes": files, "faces": faces}
        records = []
        with open(raw_path, "w") as raw:
            for m in files:
                for mode in args.modes:
                    rec = run_one(m, mode, exe)
                    records.append(rec)
                    raw.write(json.dumps(rec) + "\n")
                    raw.flush()
                    rep = rec.get("report") or {}
                    print("%-26s %-8s exit %-7s %7.2f s  load %.2f  prisms %s" % (
                        m, mode, rec["exit"], rec["wall_s"], rec["load1_at_start"],
                        rep.get("prisms", "-")), flush=True)
        meta["date_end"] = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
        with open(meta_path, "w") as f:
            json.dump(meta, f, indent=1)
    with open(args.out, "w") as f:
        f.write(render(records, meta))
    print("wrote", args.out)


if __name__ == "__main__":
    main()
