"""The manufactured Poisson solution the dev-mesh benchmarks share (run_pipeline_sweep.py,
run_accuracy.py): with the bounding box's centre c and longest edge L of an OBJ surface and
X = (x − c) / L, u = sin 3X₁ cos 2X₂ exp X₃ (−Δu = 12u / L²), as case-file expressions."""


def obj_bbox(path):
    """(lo, hi) of the `v` lines of an OBJ file."""
    lo, hi = [float("inf")] * 3, [float("-inf")] * 3
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                p = [float(t) for t in line.split()[1:4]]
                lo = [min(a, b) for a, b in zip(lo, p)]
                hi = [max(a, b) for a, b in zip(hi, p)]
    return lo, hi


def scaled_solution(lo, hi):
    """(u, grad u, f = −Δu, the centre c, L, the scaled coordinates X) as expressions."""
    c = [(a + b) / 2 for a, b in zip(lo, hi)]
    L = max(b - a for a, b in zip(lo, hi))
    X = ["((%s - (%.17g)) / %.17g)" % (v, c[i], L) for i, v in enumerate("xyz")]
    u = "sin(3*%s)*cos(2*%s)*exp(%s)" % tuple(X)
    grad = ["3/%.17g*cos(3*%s)*cos(2*%s)*exp(%s)" % (L, X[0], X[1], X[2]),
            "-2/%.17g*sin(3*%s)*sin(2*%s)*exp(%s)" % (L, X[0], X[1], X[2]),
            "1/%.17g*sin(3*%s)*cos(2*%s)*exp(%s)" % (L, X[0], X[1], X[2])]
    return u, grad, "12/%.17g*%s" % (L * L, u), c, L, X
