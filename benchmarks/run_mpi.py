#!/usr/bin/python3
"""`curvefem run` on 1 and 2 MPI ranks (issue 24; fem/solvers/distributed.hpp), by hand only.

Runs each case with `mpirun -n 1` and `mpirun -n 2`, compares volume.vtu's solution (max relative
difference), and writes benchmarks/results/mpi.md: stage times (report.json time_s), solver
iterations, rows per rank, peak memory per rank (getrusage ru_maxrss, report.json
mpi.peak_rss_mb_per_rank; one rank: peak_rss_mb).

  /usr/bin/python3 benchmarks/run_mpi.py --build build [--cases poisson_p2,elasticity_p2]
      [--divisions-poisson 50] [--divisions-elasticity 35] [--threads 1]
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


def run(build, work, name, divisions, ranks, threads):
    os.makedirs(work, exist_ok=True)
    case = os.path.join(work, f"{name}.json")
    with open(case, "w") as f:
        json.dump(case_text(name, divisions), f, indent=1)
    out = os.path.join(work, f"{name}_n{ranks}")
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
             "solver row says \"by rows\" (fem/solvers/distributed.hpp); the element matrices "
             "and every other stage are computed on rank 0.", ""]
    for name in a.cases.split(","):
        d = a.divisions_poisson if name == "poisson_p2" else a.divisions_elasticity
        runs = {n: run(a.build, a.work, name, d, n, a.threads) for n in (1, 2)}
        u1 = read_vtu_field(os.path.join(runs[1]["out"], "volume.vtu"))
        u2 = read_vtu_field(os.path.join(runs[2]["out"], "volume.vtu"))
        diff = float(np.max(np.abs(u1 - u2)) / np.max(np.abs(u1)))
        r1, r2 = runs[1]["report"], runs[2]["report"]
        lines += [f"## {name}: builtin cube, {d} divisions, {r1['tets']} tets, {r1['dofs']} DOFs",
                  "", "```"] + [runs[n]["cmd"] for n in (1, 2)] + ["```", "",
                  f"max |u1 - u2| / max |u1| = {diff:.3e}", ""]
        stages = sorted(set(r1["time_s"]) | set(r2["time_s"]))
        lines += ["| | 1 rank | 2 ranks |", "|---|---|---|"]
        for s in stages:
            lines.append(f"| time `{s}` (s) | {r1['time_s'].get(s, 0):.2f} | "
                         f"{r2['time_s'].get(s, 0):.2f} |")
        s1, s2 = r1["solver"], r2["solver"]
        lines += [f"| wall (mpirun, s) | {runs[1]['wall']:.1f} | {runs[2]['wall']:.1f} |",
                  f"| solver | {s1['method']}, {s1['iterations']} it | "
                  f"{s2['method']}, {s2['iterations']} it |",
                  f"| solver setup / solve (s) | {s1['setup_s']:.2f} / {s1['solve_s']:.2f} | "
                  f"{s2['setup_s']:.2f} / {s2['solve_s']:.2f} (partition "
                  f"{s2.get('partition_s', 0):.2f}, distribute {s2.get('distribute_s', 0):.2f}) |",
                  f"| matrix | whole | "
                  + (f"by rows (their assembly {s2.get('rows_assembly_s', 0):.2f} s)"
                     if s2.get("assembled_by_rows") else "whole on rank 0") + " |",
                  f"| rows per rank | {sum(s2.get('rows_per_rank', [0]))} (all) | "
                  f"{s2.get('rows_per_rank')} ({s2.get('partitioner')}) |",
                  f"| peak RSS per rank (MiB) | {r1['peak_rss_mb']:.0f} | "
                  + ", ".join(f"{m:.0f}" for m in r2["mpi"]["peak_rss_mb_per_rank"]) + " |",
                  f"| max rank / 1 rank | 1 | "
                  f"{max(r2['mpi']['peak_rss_mb_per_rank']) / r1['peak_rss_mb']:.2f} |", ""]
        print("\n".join(lines[-20:]), flush=True)
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
