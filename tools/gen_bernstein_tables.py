#!/usr/bin/python3
"""Generate meshing/curved/generated/bernstein_tables.inc: exact tables for the certified
positivity of det J of curved Lagrange tetrahedra of order k = 2, 3, 4 (DESIGN.md §2).

det J of an order-k tet is a polynomial of degree d = 3(k-1) (d = 3, 6, 9). For each k the file
holds, computed exactly with fractions.Fraction:

  lattice    the uniform degree-d lattice: barycentric multi-indices beta (|beta| = d), point
             xi = (beta_1, beta_2, beta_3) / d, in the canonical order of
             meshing/core/lagrange_nodes.hpp applied at degree d (re-implemented here; the C++
             tests cross-check it against curvefem::lagrange_lattice(tetrahedron, d)):
               1. group points by entity, the set of vertices i with beta_i > 0;
               2. entities by dimension, equal dimension in lexicographic order of their vertices;
               3. inside an entity, descending lexicographic order of beta.
             The first four points are the vertices d*e_0 .. d*e_3. The same multi-indices label
             the Bernstein coefficients: coefficient alpha belongs to
               B_alpha(lambda) = d! / (alpha_0! .. alpha_3!) * lambda_0^alpha_0 .. lambda_3^alpha_3.
  gradients  D * dN_i/dxi_c (order-k Lagrange basis, nodes in canonical order) at every lattice
             point, as integers, with one common positive denominator D per order: every entry is
             an exact integer below 2^53, so the C++ side reads it without rounding.
  l2b        the Lagrange-to-Bernstein conversion M = V^{-1}, V[j][alpha] = B_alpha(point j):
             b_alpha = sum_j M[alpha][j] * p(point j) for every polynomial p of degree <= d.
             Each rational entry is emitted as an enclosing pair (l2b_lower <= M <= l2b_upper,
             adjacent doubles; equal when M is a double).
  bounds     l2b_abs_row_sum >= max_alpha sum_j max(|lower|, |upper|) and
             l2b_width_row_sum >= max_alpha sum_j (upper - lower), exact sums rounded up.

M is built without inverting V: row alpha of M holds the Bernstein coefficients of the degree-d
Lagrange polynomial of each lattice point, L_beta = prod_i prod_{t < beta_i} (d lambda_i - t)/(t+1),
expanded exactly as a homogeneous polynomial in lambda. M V = I is then verified exactly.

Usage:
  tools/gen_bernstein_tables.py            write the committed file
  tools/gen_bernstein_tables.py --check    regenerate in memory, compare, exit 1 on difference
  tools/gen_bernstein_tables.py --output F write to F instead
"""

import argparse
import math
import random
import sys
from fractions import Fraction
from pathlib import Path

ORDERS = (2, 3, 4)
REPO_ROOT = Path(__file__).resolve().parent.parent
OUTPUT = REPO_ROOT / "meshing" / "curved" / "generated" / "bernstein_tables.inc"
LINE_WIDTH = 100


def canonical_lattice(p):
    """Barycentric multi-indices (b0, b1, b2, b3), |b| = p, in the canonical order of core."""
    nodes = []
    for a1 in range(p + 1):
        for a2 in range(p + 1 - a1):
            for a3 in range(p + 1 - a1 - a2):
                nodes.append((p - a1 - a2 - a3, a1, a2, a3))

    def key(alpha):
        entity = tuple(i for i in range(4) if alpha[i] > 0)
        return (len(entity), entity, tuple(-a for a in alpha))

    return sorted(nodes, key=key)


def multinomial(alpha):
    r = math.factorial(sum(alpha))
    for a in alpha:
        r //= math.factorial(a)
    return r


def barycentric(beta, p):
    return [Fraction(b, p) for b in beta]


# ---------------------------------------------------------------------------------------------
# Lagrange-to-Bernstein conversion


def poly_mul_linear(poly, lin):
    """poly: dict exponent-tuple -> int (homogeneous); lin: 4 integer coefficients of lambda_i."""
    out = {}
    for e, c in poly.items():
        for i in range(4):
            if lin[i] == 0:
                continue
            f = list(e)
            f[i] += 1
            f = tuple(f)
            out[f] = out.get(f, 0) + c * lin[i]
    return out


def lagrange_to_bernstein(d, lattice):
    """M[alpha][j] as Fractions (row alpha = Bernstein coefficient, column j = lattice point)."""
    m = len(lattice)
    index = {beta: i for i, beta in enumerate(lattice)}
    mat = [[Fraction(0)] * m for _ in range(m)]
    for j, beta in enumerate(lattice):
        # L_beta = prod_i prod_{t < beta_i} (d lambda_i - t sum(lambda)) / (t + 1): homogeneous.
        poly = {(0, 0, 0, 0): 1}
        denom = 1
        for i in range(4):
            for t in range(beta[i]):
                lin = [-t] * 4
                lin[i] = d - t
                poly = poly_mul_linear(poly, lin)
                denom *= t + 1
        for e, c in poly.items():
            if c != 0:
                mat[index[e]][j] = Fraction(c, denom * multinomial(e))
    return mat


def bernstein_vandermonde_scaled(d, lattice):
    """W[j][alpha] = d^d B_alpha(point j): exact integers."""
    return [[multinomial(a) * math.prod(b**e for b, e in zip(beta, a)) for a in lattice]
            for beta in lattice]


def verify_inverse(d, lattice, mat):
    """Exact check M W = d^d I. Full product for d <= 6; for d = 9 (10^7 big-integer products)
    the exact identity M (W x) = d^d x for 8 fixed pseudo-random integer vectors x (Freivalds),
    a deterministic check that a wrong M passes with negligible probability."""
    w = bernstein_vandermonde_scaled(d, lattice)
    m = len(lattice)
    scale = d**d
    if d <= 6:
        for a in range(m):
            row = mat[a]
            den = math.lcm(*(q.denominator for q in row))
            num = [q.numerator * (den // q.denominator) for q in row]
            for col in range(m):
                s = sum(num[j] * w[j][col] for j in range(m) if num[j] != 0)
                assert s == (scale * den if col == a else 0), (d, a, col)
        return
    rng = random.Random(20240601)
    for _ in range(8):
        x = [rng.randrange(-10**6, 10**6) for _ in range(m)]
        wx = [sum(w[j][c] * x[c] for c in range(m)) for j in range(m)]
        for a in range(m):
            assert sum(q * v for q, v in zip(mat[a], wx) if q) == scale * x[a], (d, a)


# ---------------------------------------------------------------------------------------------
# Order-k Lagrange gradients at the degree-d lattice


def factor(a, k, lam, cache={}):
    """Value and derivative of prod_{t < a} (k lam - t) / (t + 1) (memoized: few distinct)."""
    key = (a, k, lam)
    if key not in cache:
        value, deriv = Fraction(1), Fraction(0)
        for t in range(a):
            f = (k * lam - t) / (t + 1)
            df = Fraction(k, t + 1)
            deriv = deriv * f + value * df
            value *= f
        cache[key] = (value, deriv)
    return cache[key]


def gradients(k, d, lattice):
    """G[j][i][c] = dN_i/dxi_c at lattice point j (Fractions)."""
    nodes = canonical_lattice(k)
    table = []
    for beta in lattice:
        lam = barycentric(beta, d)
        rows = []
        for alpha in nodes:
            fd = [factor(alpha[i], k, lam[i]) for i in range(4)]
            dlam = []
            for i in range(4):
                p = fd[i][1]
                for j in range(4):
                    if j != i:
                        p *= fd[j][0]
                dlam.append(p)
            rows.append([dlam[c + 1] - dlam[0] for c in range(3)])
        table.append(rows)
    return nodes, table


# ---------------------------------------------------------------------------------------------
# Emission


def enclose(q):
    """(lower, upper) adjacent doubles with lower <= q <= upper (equal when q is a double)."""
    f = float(q)  # int / int true division: correctly rounded
    if Fraction(f) == q:
        return f, f
    if Fraction(f) < q:
        lo, hi = f, math.nextafter(f, math.inf)
    else:
        lo, hi = math.nextafter(f, -math.inf), f
    assert Fraction(lo) <= q <= Fraction(hi)
    return lo, hi


def round_up(q):
    f = float(q)
    if Fraction(f) < q:
        f = math.nextafter(f, math.inf)
    assert Fraction(f) >= q
    return f


def double_literal(x):
    s = repr(x)
    if "e" not in s and "." not in s and "inf" not in s and "nan" not in s:
        s += ".0"
    assert float(s) == x
    return s


def wrap(items, indent):
    lines, line = [], indent
    for item in items:
        piece = item + ","
        if line != indent and len(line) + 1 + len(piece) > LINE_WIDTH:
            lines.append(line)
            line = indent
        line += ("" if line == indent else " ") + piece
    if line != indent:
        lines.append(line)
    return lines


def generate():
    out = []
    emit = out.append
    emit("// generated by tools/gen_bernstein_tables.py — do not edit")
    emit("//")
    emit("// Exact tables for the certified positivity of det J of Lagrange tets of order k = 2..4")
    emit("// (degree d = 3(k-1) = 3, 6, 9). See the generator's docstring for the definitions:")
    emit("//   lattice:   m x 4 barycentric multi-indices of the degree-d lattice, canonical order of")
    emit("//              meshing/core/lagrange_nodes.hpp at degree d; also the Bernstein labels.")
    emit("//   gradients: m x n x 3 integers, gradient_denominator * dN_i/dxi_c at lattice point j.")
    emit("//   l2b_lower / l2b_upper: m x m, row alpha, enclosing the exact Lagrange-to-Bernstein")
    emit("//              matrix: b_alpha = sum_j M[alpha][j] p(lattice point j).")
    emit("//   l2b_abs_row_sum >= max_alpha sum_j max(|lower|, |upper|);")
    emit("//   l2b_width_row_sum >= max_alpha sum_j (upper - lower).")
    emit("// Included by meshing/curved/jacobian_certificate.cpp inside namespace")
    emit("// curvefem::meshing::curved::generated.")
    emit("")
    emit("// clang-format off")
    emit("")
    emit("struct BernsteinTable {")
    emit("  int order;                     // k")
    emit("  int degree;                    // d = 3(k-1)")
    emit("  int num_nodes;                 // n = (k+1)(k+2)(k+3)/6")
    emit("  int num_lattice;               // m = (d+1)(d+2)(d+3)/6")
    emit("  const int* lattice;            // m x 4")
    emit("  double gradient_denominator;   // D > 0")
    emit("  const int* gradients;          // m x n x 3, D * dN_i/dxi_c at point j")
    emit("  const double* l2b_lower;       // m x m")
    emit("  const double* l2b_upper;       // m x m")
    emit("  double l2b_abs_row_sum;")
    emit("  double l2b_width_row_sum;")
    emit("};")
    entries = []
    for k in ORDERS:
        d = 3 * (k - 1)
        lattice = canonical_lattice(d)
        m = len(lattice)
        mat = lagrange_to_bernstein(d, lattice)
        verify_inverse(d, lattice, mat)
        nodes, grad = gradients(k, d, lattice)
        n = len(nodes)
        den = math.lcm(*(g.denominator for pt in grad for row in pt for g in row))
        gint = [[[g * den for g in row] for row in pt] for pt in grad]
        for pt in gint:
            for row in pt:
                for g in row:
                    assert g.denominator == 1 and abs(g.numerator) < 2**31
        # Partition of unity: gradients sum to zero at every point.
        for pt in gint:
            for c in range(3):
                assert sum(row[c] for row in pt) == 0
        lower, upper, abs_sums, width_sums = [], [], [], []
        for row in mat:
            pairs = [enclose(q) for q in row]
            lower.append([p[0] for p in pairs])
            upper.append([p[1] for p in pairs])
            abs_sums.append(sum(max(abs(Fraction(a)), abs(Fraction(b))) for a, b in pairs))
            width_sums.append(sum(Fraction(b) - Fraction(a) for a, b in pairs))
        name = f"p{k}"
        entries.append((k, d, n, m, name, den, round_up(max(abs_sums)), round_up(max(width_sums))))
        emit("")
        emit(f"// order k = {k}, Jacobian degree d = {d}: {n} nodes, {m} lattice points")
        emit(f"inline constexpr int k_{name}_lattice[{m * 4}] = {{")
        out.extend(wrap(["{}, {}, {}, {}".format(*b) for b in lattice], "    "))
        emit("};")
        emit(f"inline constexpr int k_{name}_gradients[{m * n * 3}] = {{")
        for j, pt in enumerate(gint):
            emit("    // point {} beta = ({})".format(j, ", ".join(map(str, lattice[j]))))
            out.extend(wrap(["{}, {}, {}".format(*(g.numerator for g in row)) for row in pt],
                            "    "))
        emit("};")
        for label, rows in (("lower", lower), ("upper", upper)):
            emit(f"inline constexpr double k_{name}_l2b_{label}[{m * m}] = {{")
            for a, row in enumerate(rows):
                emit("    // alpha {} = ({})".format(a, ", ".join(map(str, lattice[a]))))
                out.extend(wrap([double_literal(x) for x in row], "    "))
            emit("};")
    emit("")
    emit(f"inline constexpr BernsteinTable k_bernstein_tables[{len(entries)}] = {{")
    for k, d, n, m, name, den, abs_sum, width_sum in entries:
        emit(f"    {{{k}, {d}, {n}, {m}, k_{name}_lattice, {den}.0, k_{name}_gradients,")
        emit(f"     k_{name}_l2b_lower, k_{name}_l2b_upper, {double_literal(abs_sum)},"
             f" {double_literal(width_sum)}}},")
    emit("};")
    emit("")
    emit("// clang-format on")
    return "\n".join(out) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true",
                        help="compare the committed file with a fresh generation; exit 1 if stale")
    parser.add_argument("--output", type=Path, default=OUTPUT, help="output file")
    args = parser.parse_args()
    text = generate()
    if args.check:
        try:
            current = args.output.read_text(encoding="utf-8")
        except OSError as e:
            print(f"gen_bernstein_tables: cannot read {args.output}: {e}", file=sys.stderr)
            return 1
        if current != text:
            print(f"gen_bernstein_tables: {args.output} is stale; rerun "
                  "tools/gen_bernstein_tables.py", file=sys.stderr)
            return 1
        print(f"gen_bernstein_tables: {args.output} is up to date")
        return 0
    args.output.parent.mkdir(parents=True, exist_ok=True)
    with open(args.output, "w", encoding="utf-8", newline="\n") as f:
        f.write(text)
    print(f"gen_bernstein_tables: wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
