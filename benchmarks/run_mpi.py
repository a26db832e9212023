#!/usr/bin/python3
"""`curvefem run` on 1 and 2 MPI ranks (issue 24; fem/solvers/distributed.hpp), by hand only.

Runs each case with `mpirun -n 1` and `mpirun -n 2`, compares volume.vtu's solution (max relative
difference), and writes benchmarks/results/mpi.md: stage times (report.json time_s), solver
iterations, rows per rank, peak memory per rank (getrusage ru_maxrss, report.json
mpi.peak_rss_mb_per_rank; one rank: peak_rss_mb).

  /usr/bin/python3 benchmarks/run_mpi.py --build build [--cases poisson_p2,elasticity_p2]
      [--divisions-poisson 50] [--divisions-elasticity 35] [--threads 1]

Each case runs on 1 rank, on 2 ranks with the case's default `solver.parallel_ptap` ("auto"),
on 2 ranks with the other choice ("scalable" for elasticity, "allatonce" for Poisson), so the
table compares GAMG's two parallel Galerkin products side by side, and on 2 ranks with equal rows
per rank (`solver.rank_balance` "rows"; the others balance the ranks' memory, the default).
"""
import argparse
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def case_text(name, divisions):
    if name == "poisson_p2":
        return {
            "geometry": {"builtin": {"shape": "cube", "divisions": divisions, "order": 1}},
            "physics": {"type": "poisson"},
            "discretization": {"degree": 2},
            "rhs": "-2*exp(x)*sin(y)",
            "exact": "exp(x)*sin(y)*x + z",
            "boundary_conditions": [
                {"type": "dirichlet", "select": {"all": True}, "value": "exp(x)*sin(y)*x + z"}],
            "solver": {"type": "cg", "rtol": 1e-10},
        }
    return {
        "geometry": {"builtin": {"shape": "cube", "divisions": divisions, "order": 1}},
        "physics": {"type": "linear_elasticity", "E": 210e3, "nu": 0.3},
        "discretization": {"degree": 2},
        "boundary_conditions": [
            {"type": "dirichlet", "select": {"tag": 1}, "value": [0, 0, 0]},
            {"type": "neumann", "select": {"tag": 2}, "value": [0, 0, "-100"]}],
        "solver": {"type": "cg", "rtol": 1e-10},
    }


def read_vtu_field(path):
    """The first point field of a volume.vtu as written by meshing/io/vtu_io.cpp (appended raw
    binary, zlib blocks, UInt64 headers, Float64 values); no VTK Python module needed."""
    import re
    import struct
    import zlib
    import numpy as np
    data = open(path, "rb").read()
    start = data.index(b"<AppendedData")
    base = data.index(b"_", start) + 1
    xml = data[:start].decode()
    point = xml[xml.index("<PointData"):]
    array = re.search(r"<DataArray[^>]*>", point).group(0)
    assert 'type="Float64"' in array, array
    offset = base + int(re.search(r'offset="(\d+)"', array).group(1))
    nblocks, _, _ = struct.unpack_from("<3Q", data, offset)
    sizes = struct.unpack_from(f"<{nblocks}Q", data, offset + 24)
    pos = offset + 24 + 8 * nblocks
    raw = b""
    for size in sizes:
        raw += zlib.decompress(data[pos:pos + size])
        pos += size
    return np.frombuffer(raw, dtype="<f8")


def run(build, work, name, divisions, ranks, threads, ptap=None, balance=None):
    os.makedirs(work, exist_ok=True)
    text = case_text(name, divisions)
    tag = ""
    if ptap:
        text["solver"]["parallel_ptap"] = ptap
        tag = "_" + ptap
    if balance:
        text["solver"]["rank_balance"] = balance
        tag += "_" + balance
    case = os.path.join(work, f"{name}{tag}.json")
    with open(case, "w") as f:
        json.dump(text, f, indent=1)
    out = os.path.join(work, f"{name}_n{ranks}{tag}")
    cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-n", str(ranks),
           os.path.join(build, "tools/curvefem/curvefem"), "run", "-q", case, "-o", out,
           "--threads", str(threads)]
    t = time.time()
    subprocess.run(cmd, check=True)
    wall = time.time() - t
    with open(os.path.join(out, "report.json")) as f:
        report = json.load(f)
    return {"cmd": " ".join(cmd), "wall": wall, "report": report, "out": out}


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--build", default=os.path.join(HERE, "..", "build"))
    p.add_argument("--work", default="/tmp/curvefem_mpi_bench")
    p.add_argument("--cases", default="poisson_p2,elasticity_p2")
    p.add_argument("--divisions-poisson", type=int, default=50)
    p.add_argument("--divisions-elasticity", type=int, default=35)
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--results", default=os.path.join(HERE, "results", "mpi.md"))
    a = p.parse_args()
    import numpy as np
    lines = ["# `curvefem run` on 1 and 2 MPI ranks (issue 24)", "",
             "Written by `benchmarks/run_mpi.py` (" + " ".join(sys.argv[1:]) + "), "
             + time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()) + ", 2-core machine "
             "(shared with other builds: times indicative). The linear solve is distributed, and "
             "the matrix is assembled by rows, one rank's rows at a time on rank 0, where the "
             "matrix row says \"by rows\" (fem/solvers/distributed.hpp); the element matrices "
             "and every other stage are computed on rank 0.", ""]
    for name in a.cases.split(","):
        d = a.divisions_poisson if name == "poisson_p2" else a.divisions_elasticity
        other = "allatonce" if name == "poisson_p2" else "scalable"
        runs = [run(a.build, a.work, name, d, 1, a.threads),
                run(a.build, a.work, name, d, 2, a.threads),
                run(a.build, a.work, name, d, 2, a.threads, other),
                run(a.build, a.work, name, d, 2, a.threads, balance="rows")]
        u = [read_vtu_field(os.path.join(r["out"], "volume.vtu")) for r in runs]
        diffs = [float(np.max(np.abs(u[0] - v)) / np.max(np.abs(u[0]))) for v in u[1:]]
        reps = [r["report"] for r in runs]
        r1 = reps[0]
        lines += [f"## {name}: builtin cube, {d} divisions, {r1['tets']} tets, {r1['dofs']} DOFs",
                  "", "```"] + [r["cmd"] for r in runs] + ["```", "",
                  "max |u1 - u2| / max |u1| = " + ", ".join(f"{x:.3e}" for x in diffs)
                  + " (2 ranks, then 2 ranks with " + other + ", then 2 ranks with equal rows)", ""]
        stages = sorted(set().union(*(set(r["time_s"]) for r in reps)))
        lines += [f"| | 1 rank | 2 ranks (auto) | 2 ranks ({other}) | 2 ranks (auto, equal rows) |",
                  "|---|---|---|---|---|"]
        for s in stages:
            lines.append(f"| time `{s}` (s) | "
                         + " | ".join(f"{r['time_s'].get(s, 0):.2f}" for r in reps) + " |")
        sv = [r["solver"] for r in reps]

        def setup(x):
            extra = ""
            if "partition_s" in x:
                extra = (f" (partition {x['partition_s']:.2f}, distribute "
                         f"{x['distribute_s']:.2f})")
            return f"{x['setup_s']:.2f} / {x['solve_s']:.2f}{extra}"

        def matrix(x):
            if "ranks" not in x:
                return "whole"
            return (f"by rows (their assembly {x.get('rows_assembly_s', 0):.2f} s)"
                    if x.get("assembled_by_rows") else "whole on rank 0")

        def rss(r):
            return ", ".join(f"{m:.0f}" for m in r.get("mpi", {}).get(
                "peak_rss_mb_per_rank", [r["peak_rss_mb"]]))

        def ratio(r):
            return max(r.get("mpi", {}).get("peak_rss_mb_per_rank", [r["peak_rss_mb"]])) \
                / r1["peak_rss_mb"]

        lines += ["| wall (mpirun, s) | " + " | ".join(f"{r['wall']:.1f}" for r in runs) + " |",
                  "| solver | " + " | ".join(f"{x['method']}, {x['iterations']} it" for x in sv)
                  + " |",
                  "| parallel Galerkin product (`-matptap_via`) | – | "
                  + " | ".join(x.get("parallel_ptap", "–") for x in sv[1:]) + " |",
                  "| solver setup / solve (s) | " + " | ".join(setup(x) for x in sv) + " |",
                  "| matrix | " + " | ".join(matrix(x) for x in sv) + " |",
                  "| rows per rank | " + " | ".join(
                      f"{x.get('rows_per_rank')} ({x.get('partitioner')})" if "ranks" in x
                      else "all" for x in sv) + " |",
                  "| row shares asked (`solver.rank_balance`) | – | " + " | ".join(
                      ("memory: " + ", ".join(f"{v:.3f}" for v in x["rank_shares"])
                       + " (heap " + ", ".join(f"{v:.0f}" for v in x["rank_heap_mb"]) + " MiB)")
                      if x.get("rank_shares") else "rows: equal" for x in sv[1:]) + " |",
                  "| peak RSS per rank (MiB) | " + " | ".join(rss(r) for r in reps) + " |",
                  "| max rank / 1 rank | " + " | ".join(f"{ratio(r):.2f}" for r in reps) + " |",
                  ""]
        print("\n".join(lines[-24:]), flush=True)
    # A hand-written "## Reading" section of an existing file is kept after the new tables.
    kept = ""
    if os.path.exists(a.results):
        old = open(a.results).read()
        if "\n## Reading" in old:
            kept = old[old.index("\n## Reading"):]
    with open(a.results, "w") as f:
        f.write("\n".join(lines) + "\n" + kept)


if __name__ == "__main__":
    main()
