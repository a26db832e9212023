#!/usr/bin/python3
"""Gmsh 4.8's own high-order meshing of STEP solids beside curvefem on the same geometry.

For every solid of DATA/MANIFEST.tsv (column `file`, default /work/shared/data/step):
  gmsh      `gmsh SOLID.step -3 -order P [-optimize_ho] -format msh41 -o OUT.msh` for each order P,
            without and with the high-order optimizer, at Gmsh's default mesh size; one thread
            (Gmsh's default); wall time and peak RSS of the process from wait4(); killed at
            --timeout. Its log's last "Volume mesh: ... N elements with jac. < 0" line is kept.
  curvefem  `curvefem mesh DATA/derived_gmsh_surface/SOLID_surf.obj -o DIR --order K --eps EPS
            --threads T -q` for each order K, then `curvefem validate DIR --json -q`. The input is
            a dense Gmsh tessellation of the same STEP file (README there), not the CAD itself.

Every output mesh (Gmsh's .msh and curvefem's DIR/mesh.msh, both MSH 4.1) is then checked twice
in the same way:
  own       this script, standard library only: det J of each tet10/tet20 is a polynomial of
            degree 3(P-1) in the reference tet. Affine elements (every node where the map of the
            4 corners puts it, within 1e-10 of the element size) have a constant det J. For the
            others, det J is sampled on the degree-3(P-1) lattice and converted to Bernstein
            coefficients; the tet is "non-positive" when a sample is <= 0 (a witness), "positive"
            when every Bernstein coefficient is > 1e-12 x the largest (a bound: det J is a convex
            combination of them), and otherwise the reference tet is split 1:8 up to --depth
            times and the same tests are applied to each piece; what is still open is "undecided".
            The sign convention is the sign of the summed corner volumes of the whole mesh.
            `min J ratio` is the smallest (min sample / max sample) per tet: sampled, not a bound.
  plugin    Gmsh's Plugin(AnalyseMeshQuality) (JacobianDeterminant = 1, 3D elements) on the saved
            file; its per-element minJ/maxJ view is written as MSH and elements <= 0 are counted.
Node order inside a tet is read from the file itself (reference position of every node of the
straight-sided elements) and compared with Gmsh's documented order.

Usage (from the repository root):
  /usr/bin/python3 benchmarks/run_step_compare.py --exe /tmp/curvefem-bin/curvefem
      [--data /work/shared/data/step] [--timeout 300] [--orders 2 3] [--eps 0.01] [--threads 2]
      [--solids screw.step ...] [--work /tmp/step_compare] [--out FILE.md]
Prints the markdown tables; --out also writes them to a file. Raw records (one JSON line per run)
go to WORK/runs.jsonl. One failing run is recorded and the sweep goes on. Standard library only.
"""
import argparse
import datetime
import hashlib
import json
import math
import os
import re
import shlex
import signal
import subprocess
import sys
import tempfile
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--exe", default=os.path.join(root, "build/tools/curvefem/curvefem"),
                help="curvefem binary")
ap.add_argument("--gmsh", default="gmsh", help="gmsh binary (4.8.4 from Debian here)")
ap.add_argument("--data", default="/work/shared/data/step")
ap.add_argument("--solids", nargs="+", help="subset of MANIFEST `file` entries")
ap.add_argument("--orders", nargs="+", type=int, default=[2, 3],
                help="Gmsh -order P and curvefem --order K")
ap.add_argument("--timeout", type=float, default=300, help="seconds per run before it is killed")
ap.add_argument("--eps", type=float, default=0.01)
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--depth", type=int, default=4, help="1:8 subdivision levels of the det J check")
ap.add_argument("--max-load", type=float, default=0.0,
                help="before each run wait (15 s steps) while the 1-minute load exceeds this; "
                "0 = off")
ap.add_argument("--quiet-wait", type=float, default=120, help="longest wait per run, seconds")
ap.add_argument("--no-gmsh", action="store_true")
ap.add_argument("--no-curvefem", action="store_true")
ap.add_argument("--work", default="/tmp/step_compare")
ap.add_argument("--out", help="also write the markdown here")
args = ap.parse_args()
command_line = "/usr/bin/python3 " + " ".join(
    shlex.quote(a) for a in ["benchmarks/run_step_compare.py"] + sys.argv[1:])

# ---------------------------------------------------------------------------------------------
# Processes


def run(cmd, timeout, cwd=None, merge=False):
    """Runs cmd in its own process group. Returns dict(code: int or "timeout", wall, rss_mb,
    out, err); the group is killed after `timeout` seconds. merge: stderr goes into out, in
    order (Gmsh writes warnings and errors to stderr, the rest to stdout)."""
    start = time.monotonic()
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        try:
            p = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT if merge else err,
                                 cwd=cwd, start_new_session=True)
        except OSError as e:
            return dict(code="spawn failed", wall=0.0, rss_mb=None, out="", err=str(e))
        code, rss_kb = None, 0
        while True:
            pid, status, usage = os.wait4(p.pid, os.WNOHANG)
            if pid:
                code, rss_kb = os.waitstatus_to_exitcode(status), usage.ru_maxrss
                break
            if time.monotonic() - start > timeout:
                try:
                    os.killpg(p.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                _, _, usage = os.wait4(p.pid, 0)
                code, rss_kb = "timeout", usage.ru_maxrss
                break
            time.sleep(0.05)
        wall = time.monotonic() - start
        out.seek(0)
        err.seek(0)
        return dict(code=code, wall=wall, rss_mb=rss_kb / 1024.0,
                    out=out.read().decode(errors="replace"),
                    err=err.read().decode(errors="replace"))


# ---------------------------------------------------------------------------------------------
# Small dense linear algebra (pure Python; the matrices are at most 84 x 84)


def inverse(a):
    n = len(a)
    m = [list(map(float, row)) + [1.0 if i == j else 0.0 for j in range(n)]
         for i, row in enumerate(a)]
    for c in range(n):
        piv = max(range(c, n), key=lambda r: abs(m[r][c]))
        if abs(m[piv][c]) < 1e-14:
            raise ValueError("singular matrix")
        m[c], m[piv] = m[piv], m[c]
        inv_p = 1.0 / m[c][c]
        m[c] = [v * inv_p for v in m[c]]
        for r in range(n):
            if r != c and m[r][c] != 0.0:
                f = m[r][c]
                rc = m[c]
                m[r] = [v - f * w for v, w in zip(m[r], rc)]
    return [row[n:] for row in m]


def det3(a, b, c):
    """Determinant of the 3x3 matrix with columns a, b, c."""
    return (a[0] * (b[1] * c[2] - b[2] * c[1]) - b[0] * (a[1] * c[2] - a[2] * c[1]) +
            c[0] * (a[1] * b[2] - a[2] * b[1]))


def solve3(cols, rhs):
    d = det3(*cols)
    if d == 0.0:
        return None
    a, b, c = cols
    return (det3(rhs, b, c) / d, det3(a, rhs, c) / d, det3(a, b, rhs) / d)


# ---------------------------------------------------------------------------------------------
# Lagrange tets of order P (reference tet (0,0,0) (1,0,0) (0,1,0) (0,0,1)) and Bernstein bounds

GMSH_TYPE_ORDER = {4: 1, 11: 2, 29: 3, 30: 4}  # MSH element type -> order of the tet


def lattice(n):
    """Multi-indices (i, j, k) with i + j + k <= n."""
    return [(i, j, k) for k in range(n + 1) for j in range(n + 1 - k) for i in range(n + 1 - j - k)]


def gmsh_reference_nodes(p):
    """Gmsh's documented tet node order for p = 1..3: corners, edges (0,1) (1,2) (2,0) (3,0)
    (3,2) (3,1) with p-1 nodes each from the first corner on, then face nodes of the faces
    (0,2,1) (0,1,3) (0,3,2) (3,1,2)."""
    c = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
    if p == 1:
        return c
    nodes = list(c)
    for a, b in [(0, 1), (1, 2), (2, 0), (3, 0), (3, 2), (3, 1)]:
        for s in range(1, p):
            t = s / p
            nodes.append(tuple(c[a][d] + t * (c[b][d] - c[a][d]) for d in range(3)))
    if p == 3:
        for f in [(0, 2, 1), (0, 1, 3), (0, 3, 2), (3, 1, 2)]:
            nodes.append(tuple(sum(c[v][d] for v in f) / 3.0 for d in range(3)))
    return nodes


class TetType:
    """Lagrange basis of order p on given reference nodes and the Bernstein conversion of det J
    (degree n = 3(p-1))."""

    def __init__(self, p, ref_nodes):
        self.p = p
        self.ref = ref_nodes
        self.mono = lattice(p)
        vand = [[x ** a * y ** b * z ** c for (a, b, c) in self.mono] for (x, y, z) in ref_nodes]
        self.coef = inverse(vand)  # coef[m][node]: N_node = sum_m coef[m][node] * mono_m
        self.n = 3 * (p - 1)
        self.det_lattice = lattice(self.n)
        # Bernstein collocation on the degree-n lattice, in the same index order as det_lattice.
        n = self.n
        colloc = []
        for (i, j, k) in self.det_lattice:
            lam = ((n - i - j - k) / n, i / n, j / n, k / n)
            colloc.append([self.bernstein((n - a - b - c, a, b, c), lam)
                           for (a, b, c) in self.det_lattice])
        self.to_bernstein = inverse(colloc)
        self.grads0 = [self.grads(q) for q in self.sub_points(((0.0, 0.0, 0.0), (1.0, 0.0, 0.0),
                                                               (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)))]

    def bernstein(self, alpha, lam):
        n = sum(alpha)
        v = math.factorial(n)
        for a, l in zip(alpha, lam):
            v = v / math.factorial(a) * l ** a
        return v

    def grads(self, q):
        """Gradients of the basis functions at reference point q: list of (dx, dy, dz)."""
        x, y, z = q
        dm = []
        for (a, b, c) in self.mono:
            dm.append((a * x ** (a - 1) * y ** b * z ** c if a else 0.0,
                       b * x ** a * y ** (b - 1) * z ** c if b else 0.0,
                       c * x ** a * y ** b * z ** (c - 1) if c else 0.0))
        out = []
        for node in range(len(self.ref)):
            gx = gy = gz = 0.0
            for m, d in enumerate(dm):
                w = self.coef[m][node]
                if w:
                    gx += w * d[0]
                    gy += w * d[1]
                    gz += w * d[2]
            out.append((gx, gy, gz))
        return out

    def sub_points(self, verts):
        """The degree-n lattice of the sub-tet with reference corners verts."""
        n = self.n
        pts = []
        for (i, j, k) in self.det_lattice:
            w = ((n - i - j - k) / n, i / n, j / n, k / n)
            pts.append(tuple(sum(w[v] * verts[v][d] for v in range(4)) for d in range(3)))
        return pts

    @staticmethod
    def dets(xs, grads_list):
        out = []
        for g in grads_list:
            a0 = a1 = a2 = b0 = b1 = b2 = c0 = c1 = c2 = 0.0
            for (x, y, z), (gx, gy, gz) in zip(xs, g):
                a0 += x * gx
                a1 += y * gx
                a2 += z * gx
                b0 += x * gy
                b1 += y * gy
                b2 += z * gy
                c0 += x * gz
                c1 += y * gz
                c2 += z * gz
            out.append(a0 * (b1 * c2 - b2 * c1) - b0 * (a1 * c2 - a2 * c1) +
                       c0 * (a1 * b2 - a2 * b1))
        return out

    def coefficients(self, values):
        return [sum(w * v for w, v in zip(row, values)) for row in self.to_bernstein]


def split8(t):
    """1:8 subdivision of a tet given by 4 corner points (any octahedron diagonal: 0-2 / 1-3)."""
    v0, v1, v2, v3 = t
    m = lambda a, b: tuple((a[d] + b[d]) * 0.5 for d in range(3))
    m01, m02, m03, m12, m13, m23 = m(v0, v1), m(v0, v2), m(v0, v3), m(v1, v2), m(v1, v3), m(v2, v3)
    return [(v0, m01, m02, m03), (m01, v1, m12, m13), (m02, m12, v2, m23), (m03, m13, m23, v3),
            (m01, m02, m03, m13), (m01, m02, m12, m13), (m02, m03, m13, m23),
            (m02, m12, m13, m23)]


def classify(tt, xs, sign, depth):
    """-> ("pos" | "nonpos" | "undecided", sampled min/max ratio) for one curved tet."""
    vals = [sign * v for v in tt.dets(xs, tt.grads0)]
    ratio = min(vals) / max(vals) if max(vals) > 0 else -math.inf
    ref = ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    todo = [(ref, vals, 0)]
    open_leaf = False
    while todo:
        t, v, level = todo.pop()
        if min(v) <= 0.0:
            return "nonpos", ratio
        b = tt.coefficients(v)
        if min(b) > 1e-12 * max(abs(x) for x in b):
            continue
        if level >= depth:
            open_leaf = True
            continue
        for s in split8(t):
            sv = [sign * d for d in tt.dets(xs, [tt.grads(q) for q in tt.sub_points(s)])]
            todo.append((s, sv, level + 1))
    return ("undecided" if open_leaf else "pos"), ratio


def read_msh41_tets(path):
    """MSH 4.1 ASCII -> (coords by tag, list of (element type, node tags)) for tet types."""
    nodes, elems = {}, []
    with open(path) as f:
        lines = iter(f.read().split("\n"))
    for line in lines:
        s = line.strip()
        if s == "$MeshFormat":
            ver = next(lines).split()
            if not ver[0].startswith("4") or ver[1] != "0":
                raise ValueError("%s: MSH %s (binary=%s), need 4.x ASCII" % (path, ver[0], ver[1]))
        elif s == "$Nodes":
            nblocks = int(next(lines).split()[0])
            for _ in range(nblocks):
                _, _, parametric, count = map(int, next(lines).split())
                tags = [int(next(lines)) for _ in range(count)]
                for t in tags:
                    c = next(lines).split()
                    nodes[t] = (float(c[0]), float(c[1]), float(c[2]))
        elif s == "$Elements":
            nblocks = int(next(lines).split()[0])
            for _ in range(nblocks):
                _, _, etype, count = map(int, next(lines).split())
                for _ in range(count):
                    row = next(lines).split()
                    if etype in GMSH_TYPE_ORDER:
                        elems.append((etype, [int(x) for x in row[1:]]))
    return nodes, elems


def reference_position(xs, q):
    """Reference coordinates of point q in the straight tet of corners xs[0..3] (or None)."""
    x0 = xs[0]
    cols = [tuple(xs[i][d] - x0[d] for d in range(3)) for i in (1, 2, 3)]
    return solve3(cols, tuple(q[d] - x0[d] for d in range(3)))


def infer_order(p, conn_list, nodes):
    """Node order of order-p tets read from the straight-sided ones: the most common tuple of
    reference positions (each snapped to the 1/p lattice, within 1e-8), or None."""
    counts = {}
    for conn in conn_list[:5000]:
        xs = [nodes[t] for t in conn]
        snapped = []
        for q in xs:
            r = reference_position(xs, q)
            if r is None:
                break
            s = tuple(round(c * p) / p for c in r)
            if max(abs(a - b) for a, b in zip(r, s)) > 1e-8:
                break
            snapped.append(s)
        else:
            if len(set(snapped)) == len(snapped):
                key = tuple(snapped)
                counts[key] = counts.get(key, 0) + 1
    if not counts:
        return None
    return max(counts.items(), key=lambda kv: kv[1])[0]


def check_mesh(path, depth):
    """Independent det J check of every tet in an MSH 4.1 file (see the module doc)."""
    t0 = time.monotonic()
    nodes, elems = read_msh41_tets(path)
    if not elems:
        return dict(error="no tetrahedra in %s" % path)
    types = sorted({e[0] for e in elems})
    if len(types) != 1:
        return dict(error="mixed tet types %s" % types)
    p = GMSH_TYPE_ORDER[types[0]]
    conns = [c for _, c in elems]
    doc = gmsh_reference_nodes(p) if p <= 3 else None
    seen = infer_order(p, conns, nodes)
    if seen is not None:
        ref, order_source = list(seen), ("gmsh documented order" if doc and
                                         all(max(abs(a - b) for a, b in zip(u, v)) < 1e-12
                                             for u, v in zip(seen, doc))
                                         else "read from straight tets (differs from Gmsh's doc)")
    elif doc:
        ref, order_source = doc, "gmsh documented order (no straight tet to confirm it)"
    else:
        return dict(error="order %d: node order unknown" % p)
    # sign convention: summed corner volumes of the whole mesh
    vol = 0.0
    for c in conns:
        x0, x1, x2, x3 = (nodes[t] for t in c[:4])
        vol += det3(*[tuple(xi[d] - x0[d] for d in range(3)) for xi in (x1, x2, x3)])
    sign = 1.0 if vol >= 0 else -1.0
    tt = TetType(p, ref) if p > 1 else None
    res = dict(order=p, tets=len(conns), node_order=order_source, sign=int(sign), affine=0,
               pos=0, nonpos=0, undecided=0, min_ratio=1.0)
    for idx, c in enumerate(conns):
        xs = [nodes[t] for t in c]
        x0 = xs[0]
        cols = [tuple(xs[i][d] - x0[d] for d in range(3)) for i in (1, 2, 3)]
        d0 = sign * det3(*cols)
        h = max(math.sqrt(sum(v * v for v in col)) for col in cols)
        straight = True
        if p > 1:
            for q, r in zip(xs[4:], ref[4:]):
                pred = tuple(x0[d] + r[0] * cols[0][d] + r[1] * cols[1][d] + r[2] * cols[2][d]
                             for d in range(3))
                if max(abs(q[d] - pred[d]) for d in range(3)) > 1e-10 * h:
                    straight = False
                    break
        if straight:
            res["affine"] += 1
            verdict, ratio = ("pos" if d0 > 0 else "nonpos"), (1.0 if d0 > 0 else -math.inf)
        else:
            verdict, ratio = classify(tt, xs, sign, depth)
        res[verdict] += 1
        if ratio < res["min_ratio"]:
            res["min_ratio"] = ratio
    res["seconds"] = time.monotonic() - t0
    return res


# ---------------------------------------------------------------------------------------------
# Gmsh's own measures

PLUGIN_GEO = """Merge "{msh}";
Plugin(AnalyseMeshQuality).JacobianDeterminant = 1;
Plugin(AnalyseMeshQuality).IGEMeasure = 0;
Plugin(AnalyseMeshQuality).ICNMeasure = 0;
Plugin(AnalyseMeshQuality).DimensionOfElements = 3;
Plugin(AnalyseMeshQuality).CreateView = 1;
Plugin(AnalyseMeshQuality).Run;
Save View[PostProcessing.NbViews - 1] "{view}";
"""


def gmsh_plugin(msh):
    """Plugin(AnalyseMeshQuality) on a saved mesh: count of elements with minJ/maxJ <= 0."""
    base = os.path.splitext(msh)[0]
    geo, view = base + "_aq.geo", base + "_aq_view.msh"
    if os.path.exists(view):
        os.remove(view)
    with open(geo, "w") as f:
        f.write(PLUGIN_GEO.format(msh=os.path.abspath(msh), view=os.path.abspath(view)))
    r = run([args.gmsh, geo, "-0", "-nt", "1"], args.timeout, cwd=os.path.dirname(msh))
    res = dict(code=r["code"], wall=r["wall"])
    log = r["out"] + r["err"]
    m = re.search(r"minJ\s*=\s*(\S+),\s*(\S+),\s*(\S+) \(min, avg, max\)", log)
    if m:
        res["minJ_min"] = float(m.group(1))
    m = re.search(r"minJ/maxJ =\s*(\S+),\s*(\S+),\s*(\S+) \(worst, avg, best\)", log)
    if m:
        res["ratio_worst"] = float(m.group(1))
    try:
        vals = []
        with open(view) as f:
            lines = f.read().split("\n")
        i = lines.index("$ElementData")
        nstr = int(lines[i + 1])
        nreal = int(lines[i + 2 + nstr])
        nint = int(lines[i + 3 + nstr + nreal])
        ints = [int(x) for x in lines[i + 4 + nstr + nreal:i + 4 + nstr + nreal + nint]]
        start = i + 4 + nstr + nreal + nint
        for line in lines[start:start + ints[2]]:
            vals.append(float(line.split()[1]))
        res["elements"] = len(vals)
        res["nonpos"] = sum(1 for v in vals if v <= 0)
    except (OSError, ValueError, IndexError) as e:
        res["error"] = "view not read: %s; %s" % (e, tail(r["err"] or r["out"]))
    return res


VOLUME_LINE = re.compile(r"(Final volume mesh|Volume mesh): worst distortion = (\S+) "
                         r"\((?:avg = \S+, (\d+) elements with jac\. < 0|(\d+) elements in)")


def parse_gmsh_log(text):
    res = {}
    lines = VOLUME_LINE.findall(text)
    if lines:
        label, disto, neg, _ = lines[-1]
        res["log_line"] = label
        res["log_distortion"] = float(disto)
        res["log_negative"] = int(neg) if neg else 0
    msgs = [l.split(":", 1)[1].strip() for l in text.splitlines()
            if re.search(r"Optimization (partially failed|failed|succeeded|done)", l)]
    if msgs:
        res["optimizer"] = msgs[-1]
    errors = [l.split(":", 1)[1].strip() for l in text.splitlines() if l.startswith("Error")
              and not re.search(r"-{5}|error summary|warnings|errors$|full log", l)]
    if errors:
        res["errors"] = "%d logged errors, first: %s" % (len(errors), errors[0])
    return res


def tail(text, n=2):
    lines = [l for l in text.strip().splitlines() if l.strip()]
    return " | ".join(lines[-n:])


# ---------------------------------------------------------------------------------------------
# Runs


def wait_for_quiet():
    """Waits while the machine is busier than --max-load (other people's builds); returns the
    1-minute load average at the start of the run."""
    start = time.monotonic()
    while (args.max_load > 0 and os.getloadavg()[0] > args.max_load and
           time.monotonic() - start < args.quiet_wait):
        time.sleep(15)
    return os.getloadavg()[0]


def gmsh_case(step, name, p, optimize):
    out = os.path.join(args.work, "%s_gmsh_p%d%s.msh" % (name, p, "_ho" if optimize else ""))
    if os.path.exists(out):
        os.remove(out)
    cmd = [args.gmsh, step, "-3", "-order", str(p)] + (["-optimize_ho"] if optimize else []) + \
          ["-format", "msh41", "-o", out]
    load = wait_for_quiet()
    r = run(cmd, args.timeout, cwd=args.work, merge=True)
    with open(out[:-4] + ".log", "w") as f:
        f.write(r["out"])
    rec = dict(solid=name, tool="gmsh", order=p, optimize=optimize, cmd=" ".join(cmd),
               exit=r["code"], wall=r["wall"], rss_mb=r["rss_mb"], load=load)
    rec.update(parse_gmsh_log(r["out"]))
    # Gmsh exits 1 when it logged errors, yet may have written the mesh: check what is there.
    if r["code"] != "timeout" and os.path.exists(out):
        rec["check"] = guarded(check_mesh, out, args.depth)
        rec["plugin"] = guarded(gmsh_plugin, out)
    elif r["code"] != "timeout":
        rec["message"] = "no mesh written: " + tail(r["out"] or r["err"])
    return rec


def curvefem_case(surface, name, k):
    out_dir = os.path.join(args.work, "%s_curvefem_k%d" % (name, k))
    subprocess.run(["rm", "-rf", out_dir])
    cmd = [args.exe, "mesh", surface, "-o", out_dir, "--order", str(k), "--eps", str(args.eps),
           "--threads", str(args.threads), "-q"]
    load = wait_for_quiet()
    r = run(cmd, args.timeout)
    rec = dict(solid=name, tool="curvefem", order=k, cmd=" ".join(cmd), exit=r["code"],
               wall=r["wall"], rss_mb=r["rss_mb"], load=load)
    if r["code"] != 0:
        rec["message"] = tail(r["err"] or r["out"], 4)
    try:
        with open(os.path.join(out_dir, "report.json")) as f:
            rec["report"] = json.load(f)
    except (OSError, ValueError):
        rec["report"] = None
    if rec["report"] is not None:
        v = run([args.exe, "validate", out_dir, "--json", "-q", "--threads", str(args.threads)],
                args.timeout)
        try:
            rec["validate"] = json.loads(v["out"])
            rec["validate"]["exit"] = v["code"]
        except ValueError:
            rec["validate"] = dict(exit=v["code"], message=tail(v["err"] or v["out"]))
        msh = os.path.join(out_dir, "mesh.msh")
        if os.path.exists(msh):
            rec["check"] = guarded(check_mesh, msh, args.depth)
            rec["plugin"] = guarded(gmsh_plugin, msh)
    return rec


def guarded(fn, *a):
    try:
        return fn(*a)
    except Exception as e:  # one bad file must not stop the sweep
        return dict(error="%s: %s" % (type(e).__name__, e))


def manifest():
    with open(os.path.join(args.data, "MANIFEST.tsv")) as f:
        rows = [l.rstrip("\n").split("\t") for l in f if l.strip()]
    return [dict(zip(rows[0], r)) for r in rows[1:]]


# ---------------------------------------------------------------------------------------------
# Markdown


def fmt(x, f="%.3g"):
    return "–" if x is None else (f % x)


def row(rec):
    chk = rec.get("check") or {}
    plg = rec.get("plugin") or {}
    if rec["tool"] == "gmsh":
        label = "Gmsh P%d %s" % (rec["order"], "-optimize_ho" if rec["optimize"] else "default")
        log_neg = rec.get("log_negative")
        own_report = "–"
        dist = "–"
        status = "exit %s" % rec["exit"]
        if rec.get("optimizer"):
            status += "; " + rec["optimizer"]
        if rec.get("errors"):
            status += "; " + rec["errors"]
    else:
        label = "curvefem K=%d" % rec["order"]
        rep = rec.get("report") or {}
        val = rep.get("validation", {})
        log_neg = None
        own_report = "%s / %s" % (val.get("non_positive_tets", "–"),
                                  val.get("undecided_tets", "–"))
        dist = fmt(rep.get("max_distance_rel"))
        vv = rec.get("validate") or {}
        yes_no = {True: "yes", False: "NO"}
        status = "exit %s, valid %s; validate: exit %s, valid %s%s" % (
            rec["exit"], yes_no.get(rep.get("valid"), "–"), vv.get("exit", "–"),
            yes_no.get(vv.get("valid"), "–"), agreement(val, vv))
    if rec["exit"] == "timeout":
        status = "timeout after %.0f s" % args.timeout
    if rec.get("message"):
        status += "; " + rec["message"].replace("|", "/")
    tets = chk.get("tets")
    if tets is None and rec["tool"] == "curvefem":
        tets = (rec.get("report") or {}).get("output_tets")
    if "error" in chk:
        own = "check failed: " + chk["error"]
    elif chk:
        own = "%d / %d" % (chk["nonpos"], chk["undecided"])
    else:
        own = "–"
    plugin = ("%d" % plg["nonpos"]) if "nonpos" in plg else ("–" if not plg else "err")
    sj = None
    if rec["tool"] == "curvefem":
        sj = ((rec.get("report") or {}).get("validation") or {}).get("min_scaled_jacobian")
    return "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
        label, tets if tets is not None else "–", own,
        fmt(log_neg, "%d"), plugin, own_report,
        fmt(chk.get("min_ratio")) if chk.get("min_ratio") not in (None, -math.inf) else
        ("≤ 0" if chk else "–"), fmt(sj), dist, fmt(rec["wall"], "%.1f"),
        fmt(rec.get("rss_mb"), "%.0f"), fmt(rec.get("load"), "%.1f"), status)


def agreement(report_validation, validate):
    """', agrees' when `curvefem validate` repeats the report's verdict and figures."""
    keys = ["valid", "tets", "non_positive_tets", "undecided_tets", "min_scaled_jacobian",
            "max_distance_rel", "boundary_self_intersections"]
    if not report_validation or not validate or "valid" not in validate:
        return ""
    diff = []
    for k in keys:
        a, b = report_validation.get(k), validate.get(k)
        same = (a == b if not isinstance(a, float) or not isinstance(b, float)
                else abs(a - b) <= 1e-9 * max(abs(a), abs(b), 1e-300))
        if not same:
            diff.append("%s %s vs %s" % (k, a, b))
    return ", agrees" if not diff else ", DIFFERS: " + "; ".join(diff)


def render(records, uptime):
    w = []
    w.append("Generated %s by `%s`; gmsh %s; curvefem binary %s (sha256 %s…); %d cores; "
             "`uptime` before the run: `%s`.\n" % (
                 datetime.datetime.now().strftime("%Y-%m-%d %H:%M"), command_line, gmsh_version(),
                 args.exe, exe_digest(), os.cpu_count(), uptime))
    w.append("Columns: tets = tetrahedra in the saved file. Own check = `non-positive / "
             "undecided` tets by this script's det J test (non-positive: a sampled det J <= 0, "
             "a witness; positive: all Bernstein coefficients > 0, a bound; undecided: neither "
             "after %d 1:8 splits). Gmsh log = the last `(Final) volume mesh: ... elements with "
             "jac. < 0` count Gmsh printed; Gmsh 4.8 computes it with distoShapeMeasure(), the "
             "smallest Bezier coefficient of the scaled Jacobian without subdivision, so it "
             "counts tets not proven positive, and with -optimize_ho it is printed after the "
             "elastic step, before the last (HighOrder) optimization, which prints no count. "
             "Plugin = elements "
             "with minJ/maxJ <= 0 from "
             "Plugin(AnalyseMeshQuality). curvefem report = `non_positive_tets / undecided_tets` "
             "of its own validator. min J ratio = smallest min/max of sampled det J in a tet "
             "(sampled, not a bound). min sJ = curvefem's certified min scaled Jacobian. max dist "
             "= curvefem's distance to its input tessellation / longest bbox edge. time = wall "
             "seconds of the meshing process (Gmsh: STEP import + mesh + high order + write). "
             "load = 1-minute load average just before the run.\n"
             % args.depth)
    solids = []
    for r in records:
        if r["solid"] not in solids:
            solids.append(r["solid"])
    for s in solids:
        w.append("### %s\n" % s)
        w.append("| run | tets | own check: non-pos / undecided | Gmsh log jac<0 | "
                 "plugin minJ<=0 | curvefem report non-pos / undecided | min J ratio | min sJ | "
                 "max dist | time s | RSS MB | load | status |")
        w.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        for r in records:
            if r["solid"] == s:
                w.append(row(r))
        w.append("")
    return "\n".join(w)


def exe_digest():
    try:
        with open(args.exe, "rb") as f:
            return hashlib.sha256(f.read()).hexdigest()[:12]
    except OSError:
        return "?"


def gmsh_version():
    r = run([args.gmsh, "--version"], 30)
    return (r["out"] + r["err"]).strip() or "?"


def main():
    os.makedirs(args.work, exist_ok=True)
    uptime = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    solids = [m["file"] for m in manifest()]
    if args.solids:
        solids = [s for s in solids if s in args.solids]
    records = []
    raw = open(os.path.join(args.work, "runs.jsonl"), "a")

    def keep(rec):
        records.append(rec)
        raw.write(json.dumps(rec, default=str) + "\n")
        raw.flush()
        chk = rec.get("check") or {}
        print("%-18s %-8s P%d%s exit=%s %.1fs tets=%s own=%s/%s %s" % (
            rec["solid"], rec["tool"], rec["order"], " ho" if rec.get("optimize") else "",
            rec["exit"], rec["wall"], chk.get("tets"), chk.get("nonpos"), chk.get("undecided"),
            chk.get("error", "")), file=sys.stderr, flush=True)

    for step in solids:
        name = os.path.splitext(step)[0]
        if not args.no_gmsh:
            for p in args.orders:
                for optimize in (False, True):
                    keep(guarded_case(gmsh_case, name, os.path.join(args.data, step), name, p,
                                      optimize, tool="gmsh", order=p, optimize=optimize))
        surface = os.path.join(args.data, "derived_gmsh_surface", name + "_surf.obj")
        if args.no_curvefem:
            continue
        if not os.path.exists(surface):
            print("%-18s no derived surface (%s): curvefem not run" % (name, surface),
                  file=sys.stderr)
            continue
        for k in args.orders:
            keep(guarded_case(curvefem_case, name, surface, name, k, tool="curvefem", order=k))
    md = render(records, uptime)
    print(md)
    if args.out:
        with open(args.out, "w") as f:
            f.write(md + "\n")


def guarded_case(fn, name, *a, **meta):
    try:
        return fn(*a)
    except Exception as e:  # record and go on with the sweep
        return dict(solid=name, exit="script error", wall=0.0,
                    message="%s: %s" % (type(e).__name__, e), **meta)


if __name__ == "__main__":
    main()
