#!/usr/bin/python3
"""The shell's distortion bound (SimplifyOptions::section_cos, `curvefem shell --pillar-cos`):
for each dev mesh of ../shared/data/dev and each bound, runs `curvefem shell IN --pillar-cos C
--threads 1` (one thread: the coarsening is then deterministic) and tabulates the coarse prism
count, verify_shell's smallest half-pillar/normal cosine over section-contact pairs
(`min_pillar_cos`), its P⁻¹-then-P roundtrip (largest error, failures) and the exit code.
Writes benchmarks/results/shell_pillar_cos.md.

Usage (from the repository root):
  /usr/bin/python3 benchmarks/run_pillar_cos.py [--exe build/tools/curvefem/curvefem]
      [--bounds 0 0.01 0.05] [--meshes NAME ...] [--timeout 900] [--work DIR] [--out FILE]
Standard library only.
"""
import argparse
import datetime
import json
import os
import subprocess

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"))
ap.add_argument("--data", default=os.path.join(root, "../shared/data/dev"))
ap.add_argument("--bounds", nargs="*", type=float, default=[0.0, 0.01, 0.05])
ap.add_argument("--meshes", nargs="*", default=None, help="dev mesh names (default: all)")
ap.add_argument("--timeout", type=int, default=900)
ap.add_argument("--work", default="/tmp/curvefem_pillar_cos")
ap.add_argument("--out", default=os.path.join(root, "benchmarks/results/shell_pillar_cos.md"))
a = ap.parse_args()

if not os.path.isdir(a.data):
    raise SystemExit(f"no dev meshes at {a.data} (../shared is absent): nothing to measure")


def read_report(path):
    """The run's report.json, or {} when the run wrote none."""
    if not os.path.isfile(path):
        return {}
    with open(path) as fh:
        return json.load(fh)


names = a.meshes or sorted(f[:-4] for f in os.listdir(a.data) if f.endswith(".obj"))
rows = []
for name in names:
    row = {"mesh": name, "runs": []}
    for c in a.bounds:
        out = os.path.join(a.work, f"{name}_{c:g}")
        cmd = [a.exe, "shell", "-q", os.path.join(a.data, name + ".obj"), "-o", out,
               "--pillar-cos", repr(c), "--threads", "1"]
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=a.timeout)
            code = p.returncode
        except subprocess.TimeoutExpired:
            code = "timeout"
        rep = read_report(os.path.join(out, "report.json"))
        row["runs"].append({"bound": c, "exit": code, "prisms": rep.get("prisms"),
                            "min_cos": rep.get("min_pillar_cos"),
                            "rt": rep.get("roundtrip_max_error_rel"),
                            "rt_fail": rep.get("roundtrip_failures"),
                            "s": (rep.get("time_s") or {}).get("total")})
        print(name, row["runs"][-1], flush=True)
    rows.append(row)


def fmt(v, f="{:.2g}"):
    return "—" if v is None else f.format(v) if isinstance(v, float) else str(v)


lines = ["# Shell distortion bound: coarse prisms and verified cosines per `--pillar-cos`", "",
         f"{datetime.date.today()}; `{' '.join(['/usr/bin/python3', 'benchmarks/run_pillar_cos.py'])}`"
         f" (bounds {' '.join(f'{c:g}' for c in a.bounds)}; `curvefem shell IN --pillar-cos C"
         " --threads 1`, zoom 0.1 default).", "",
         "Per bound: coarse prisms / verify_shell's `min_pillar_cos` / largest P⁻¹-then-P error"
         " (bbox-relative) / roundtrip failures / exit code.", ""]
hdr = "| mesh | " + " | ".join(f"bound {c:g}" for c in a.bounds) + " |"
lines += [hdr, "|---" * (1 + len(a.bounds)) + "|"]
tot = [0] * len(a.bounds)
for r in rows:
    cells = []
    for i, x in enumerate(r["runs"]):
        tot[i] += x["prisms"] or 0
        cells.append(f"{fmt(x['prisms'])} / {fmt(x['min_cos'])} / {fmt(x['rt'])} / "
                     f"{fmt(x['rt_fail'])} / {x['exit']}")
    lines.append(f"| {r['mesh']} | " + " | ".join(cells) + " |")
lines.append("| total prisms | " + " | ".join(
    f"{t:,} ({100.0 * (t / tot[0] - 1):+.1f}%)" if tot[0] else str(t) for t in tot) + " |")
os.makedirs(os.path.dirname(a.out), exist_ok=True)
with open(a.out, "w") as fh:
    fh.write("\n".join(lines) + "\n")
print("wrote", a.out)
