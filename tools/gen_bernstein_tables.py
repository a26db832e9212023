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

and, for k = 1..4, the constants of the affine path of the certificate:

  gradient bounds  Lambda[k][c] >= max over the reference tet of sum_{i >= 4} |dN_i/dxi_c(xi)|,
             the sum over the non-corner nodes of the order-k basis (the corners are the first
             four nodes). dN_i/dxi_c = dN_i/dlambda_c - dN_i/dlambda_0 has degree k-1. On each
             child T_s of one red refinement of the reference tet (a partition) its exact
             Bernstein coefficients g_{s,i,beta} (|beta| = k-1) give, since the B_beta are >= 0
             and sum to 1, sum_i |dN_i/dxi_c| <= max_beta sum_i |g_{s,i,beta}| on T_s; Lambda is
             the maximum over s (exact, rounded up). One refinement level halves the k = 4 bound
             (182.7 on the whole tet, 98 on the children; the sampled maximum is 74.7).
             k = 1 has no non-corner node: 0.

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
# Bernstein bounds of the order-k basis gradients (affine path of the certificate)


def lagrange_basis_poly(k, alpha):
    """N_alpha = prod_i prod_{t < alpha_i} (k lambda_i - t sum(lambda)) / (t + 1), homogeneous of
    degree k in lambda: dict exponent -> Fraction."""
    poly, denom = {(0, 0, 0, 0): 1}, 1
    for i in range(4):
        for t in range(alpha[i]):
            lin = [-t] * 4
            lin[i] = k - t
            poly = poly_mul_linear(poly, lin)
            denom *= t + 1
    return {e: Fraction(c, denom) for e, c in poly.items() if c != 0}


def poly_derivative(poly, i):
    out = {}
    for e, c in poly.items():
        if e[i] > 0:
            f = list(e)
            f[i] -= 1
            f = tuple(f)
            out[f] = out.get(f, Fraction(0)) + c * e[i]
    return out


def red_children():
    """The 8 children of the red refinement of the reference tet (4 corner tets, 4 around the
    diagonal between the midpoints of edges 02 and 13): a partition of the tet. Each child is 4
    points in barycentric coordinates of the parent."""
    def v(i):
        return tuple(Fraction(int(j == i)) for j in range(4))

    def m(a, b):
        return tuple(Fraction(int(j in (a, b)), 2) for j in range(4))

    children = [(v(0), m(0, 1), m(0, 2), m(0, 3)), (m(0, 1), v(1), m(1, 2), m(1, 3)),
                (m(0, 2), m(1, 2), v(2), m(2, 3)), (m(0, 3), m(1, 3), m(2, 3), v(3)),
                (m(0, 2), m(1, 3), m(0, 1), m(0, 3)), (m(0, 2), m(1, 3), m(0, 3), m(2, 3)),
                (m(0, 2), m(1, 3), m(2, 3), m(1, 2)), (m(0, 2), m(1, 3), m(1, 2), m(0, 1))]
    # The inner four share the diagonal m02-m13 and take consecutive pairs of the cycle
    # m01 m03 m23 m12 around it, so they tile the octahedron; every child has 1/8 of the volume.
    for child in children:
        e = [[child[j][i] - child[0][i] for i in range(1, 4)] for j in range(1, 4)]
        det = (e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
               e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
               e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]))
        assert abs(det) == Fraction(1, 8), child
    return children


def compose(poly, child):
    """poly(lambda) with lambda = sum_j mu_j child[j] (homogeneous in mu, same degree)."""
    out = {}
    for e, c in poly.items():
        term = {(0, 0, 0, 0): c}
        for i in range(4):
            lin = [child[j][i] for j in range(4)]
            for _ in range(e[i]):
                term = poly_mul_linear(term, lin)
        for f, q in term.items():
            out[f] = out.get(f, 0) + q
    return out


def gradient_bernstein_bounds(k):
    """[Lambda_c for c = 0, 1, 2] as Fractions (see the module docstring)."""
    nodes = canonical_lattice(k)
    assert nodes[:4] == [tuple(k if j == v else 0 for j in range(4)) for v in range(4)]
    if k == 1:
        return [Fraction(0)] * 3
    labels = canonical_lattice(k - 1)
    _, grad = gradients(k, k - 1, labels)
    children = red_children()
    bounds = []
    for c in range(3):
        sums = [{beta: Fraction(0) for beta in labels} for _ in children]
        for i, alpha in enumerate(nodes):
            poly = lagrange_basis_poly(k, alpha)
            # On the simplex d/dxi_c = d/dlambda_{c+1} - d/dlambda_0 of the homogeneous form.
            dc, d0 = poly_derivative(poly, c + 1), poly_derivative(poly, 0)
            deriv = {b: dc.get(b, Fraction(0)) - d0.get(b, Fraction(0)) for b in labels}
            # Cross-check against the independent point evaluation of `gradients` (exact).
            for j, beta in enumerate(labels):
                lam = barycentric(beta, k - 1)
                value = sum(q * math.prod(x**e for x, e in zip(lam, b)) for b, q in deriv.items())
                assert value == grad[j][i][c], (k, i, c, beta)
            if i < 4:
                continue
            for s, child in enumerate(children):
                sub = compose(deriv, child)
                for v in range(4):  # corner coefficients are the values at the child's vertices
                    corner = tuple(k - 1 if j == v else 0 for j in range(4))
                    value = sum(q * math.prod(x**e for x, e in zip(child[v], b))
                                for b, q in deriv.items())
                    assert sub.get(corner, 0) == value, (k, i, c, s, v)
                for b in labels:
                    sums[s][b] += abs(Fraction(sub.get(b, 0))) / multinomial(b)
        bounds.append(max(max(t.values()) for t in sums))
    return bounds


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
    emit("//   k_gradient_bernstein_bounds (k = 1..4): gradient sums of the order-k basis, for the")
    emit("//              affine path (nearly straight tets).")
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
    emit("// Affine path: k_gradient_bernstein_bounds[k-1][c] >= max over the reference tet of")
    emit("// sum_{i >= 4} |dN_i/dxi_c| (order-k basis, non-corner nodes): the maximum over the 8 red")
    emit("// children and over beta of sum_i |Bernstein coefficient beta of dN_i/dxi_c on the")
    emit("// child| (degree k-1), exact, rounded up.")
    rows = []
    for k in (1, 2, 3, 4):
        lam = gradient_bernstein_bounds(k)
        exact = ", ".join(str(q) for q in lam)
        rows.append(("{" + ", ".join(double_literal(round_up(q)) for q in lam) + "},", k, exact))
    emit("inline constexpr double k_gradient_bernstein_bounds[4][3] = {")
    for text, k, exact in rows:
        emit(f"    {text}  // k = {k}: {exact}")
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
