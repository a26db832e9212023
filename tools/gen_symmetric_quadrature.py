#!/usr/bin/python3
"""Generate fem/quadrature/generated/symmetric_rules.inc: fully symmetric quadrature rules with
positive weights and interior points on the reference triangle and tetrahedron, found by search.

Reference simplices (as fem/quadrature/simplex_quadrature.hpp): triangle {x, y >= 0, x + y <= 1},
tetrahedron {x, y, z >= 0, x + y + z <= 1}; barycentric l0 = 1 - x - y (- z), l1 = x, l2 = y,
l3 = z. Weights sum to the reference volume (1/2, 1/6).

A fully symmetric rule is a union of orbits of the vertex permutation group (S3 / S4) acting on
barycentric coordinates. Orbit types (generator, orbit size, free parameters incl. the weight):
  triangle     "1" (1/3,1/3,1/3) 1 [1]; "3" (a,a,1-2a) 3 [2]; "6" (a,b,1-a-b) 6 [3]
  tetrahedron  "1" centroid 1 [1]; "31" (a,a,a,1-3a) 4 [2]; "22" (a,a,1/2-a,1/2-a) 6 [2];
               "211" (a,a,b,1-2a-b) 12 [3]; "1111" (a,b,c,1-a-b-c) 24 [4]

Moment equations. A symmetric rule integrates p exactly iff it integrates its symmetrisation, so
it suffices to impose the invariant polynomials of degree <= d. With m_i = (n+1) l_i - 1
(n = dimension, sum m_i = 0) the invariants are polynomials in the power sums
t_k = sum_i m_i^k, k = 2..n+1 (algebraically independent), so the equations are
  sum_orbits w_o |o| f(gen_o) = integral of f   for f = t_2^e2 t_3^e3 (t_4^e4), sum k e_k <= d.
Exact integrals come from the Dirichlet formula (integers and fractions.Fraction). The equations
are orthonormalised with the exact Gram matrix of the invariant monomials (LDL^T in Fraction).

Search. For each degree, orbit structures (counts per type) are enumerated in increasing point
count, keeping only those that pass the generic counting conditions: for every set S of orbit
types, the invariants that vanish on all the orbit strata not in S (dimension computed exactly,
modulo a prime, on random integer points of the strata) involve only the orbits of S, whose free
parameters must be at least as many. Each structure gets a batch of random starts (fixed seeds)
solved by Levenberg-Marquardt in variables that keep every iterate feasible (weights exp(v),
barycentric generators softmax of tied logits). Converged rules are polished by Newton in decimal
arithmetic (60 digits) to residuals far below double precision, then rounded, and accepted only
if every weight is at least 1e-2 of the mean weight, every barycentric coordinate at least 1e-3
(MIN_BARYCENTRIC: no point next to a face, where a curved element's geometry is at its worst),
points are distinct, and every monomial x^a y^b z^c of total degree <= d integrates (with the
rounded doubles, in exact rational arithmetic) to a relative error < 1e-14. The first structure
that yields such a rule is kept, so the rule has the fewest points the search found, not
necessarily the fewest that exist.

Output: per rule, the orbit generators (barycentric coordinates, weight per point, 17 significant
digits). The C++ side expands each generator to its distinct permutations.

Usage:
  tools/gen_symmetric_quadrature.py --tri 1-12 --tet 1-10   search, write the committed file
  tools/gen_symmetric_quadrature.py --budget 600            seconds per degree (then give up)
  tools/gen_symmetric_quadrature.py --starts 256            random starts per orbit structure
  tools/gen_symmetric_quadrature.py --keep --tet 11         search tet 11, keep the other rules
  tools/gen_symmetric_quadrature.py --keep --merge F ...    also take the rules of file F
  tools/gen_symmetric_quadrature.py --verify                re-verify the committed file exactly
  tools/gen_symmetric_quadrature.py --output F              write (or verify) F instead
The file's header lists every command that contributed rules. Each search is deterministic for
given options unless a degree hits its time budget (the log then says so).
"""

import argparse
import itertools
import math
import re
import sys
import time
from decimal import Decimal, getcontext
from fractions import Fraction
from pathlib import Path

try:  # the search needs numpy; --verify does not
    import numpy as np
except ImportError:
    np = None

REPO_ROOT = Path(__file__).resolve().parent.parent
OUTPUT = REPO_ROOT / "fem" / "quadrature" / "generated" / "symmetric_rules.inc"
PRIME = (1 << 61) - 1
# Acceptance margins: a point nearer than this to a face (in barycentric terms) samples the
# element's boundary, where curved geometry is at its worst; a weight below this fraction of the
# mean weight is a wasted point. (The collapsed Gauss-Jacobi rules of degree <= 12 keep > 1.2e-4.)
MIN_BARYCENTRIC = 1e-3
MIN_WEIGHT_FRACTION = 1e-2
getcontext().prec = 60

# Orbit types: name -> (orbit size, logit pattern). The generator is softmax(logits) where
# logit j = u[pattern[j]] (pattern entry None = logit 0; "22" is special: logits (u, u, 0, 0)
# give (a, a, 1/2 - a, 1/2 - a)). Parameters per orbit: len(set of u indices) + 1 weight.
TYPES = {
    2: {
        "1": (1, (None, None, None)),
        "3": (3, (0, 0, None)),
        "6": (6, (0, 1, None)),
    },
    3: {
        "1": (1, (None, None, None, None)),
        "31": (4, (0, 0, 0, None)),
        "22": (6, (0, 0, None, None)),
        "211": (12, (0, 0, 1, None)),
        "1111": (24, (0, 1, 2, None)),
    },
}
VOLUME = {2: Fraction(1, 2), 3: Fraction(1, 6)}


def n_free(dim, name):
    pattern = TYPES[dim][name][1]
    return len({p for p in pattern if p is not None})


def n_params(dim, name):
    return n_free(dim, name) + 1


# ---------------------------------------------------------------------------------------------
# Invariants and exact integrals


def invariant_exponents(dim, degree):
    """Exponent tuples (e_2, .., e_{dim+1}) with sum k e_k <= degree, graded order."""
    ks = list(range(2, dim + 2))
    out = []
    for total in range(degree + 1):
        for e in itertools.product(*(range(total // k + 1) for k in ks)):
            if sum(k * ek for k, ek in zip(ks, e)) == total:
                out.append(e)
    return out


def poly_mul(p, q):
    out = {}
    for a, ca in p.items():
        for b, cb in q.items():
            key = tuple(x + y for x, y in zip(a, b))
            out[key] = out.get(key, 0) + ca * cb
    return {k: v for k, v in out.items() if v}


def power_sum_poly(dim, k):
    """t_k = sum_i ((n+1) l_i - 1)^k homogenised with 1 = sum_j l_j: integer coefficients."""
    nv = dim + 1
    out = {}
    for i in range(nv):
        # m_i = n l_i - sum_{j != i} l_j as a linear form
        lin = {}
        for j in range(nv):
            e = tuple(1 if t == j else 0 for t in range(nv))
            lin[e] = dim if j == i else -1
        term = {tuple([0] * nv): 1}
        for _ in range(k):
            term = poly_mul(term, lin)
        for key, c in term.items():
            out[key] = out.get(key, 0) + c
    return {k: v for k, v in out.items() if v}


class InvariantIntegrals:
    """Exact integrals of t_2^e2 t_3^e3 (t_4^e4) over the reference simplex (memoised)."""

    def __init__(self, dim):
        self.dim = dim
        self.nv = dim + 1
        self.t = {k: power_sum_poly(dim, k) for k in range(2, dim + 2)}
        self.polys = {tuple([0] * dim): {tuple([0] * self.nv): 1}}
        self.values = {}
        self.fact = [1]
        for i in range(1, 200):
            self.fact.append(self.fact[-1] * i)

    def poly(self, e):
        if e in self.polys:
            return self.polys[e]
        k = next(i for i, x in enumerate(e) if x > 0)
        lower = list(e)
        lower[k] -= 1
        p = poly_mul(self.poly(tuple(lower)), self.t[k + 2])
        self.polys[e] = p
        return p

    def integral(self, e):
        if e in self.values:
            return self.values[e]
        p = self.poly(e)
        degree = sum((k + 2) * x for k, x in enumerate(e))
        s = 0
        for a, c in p.items():
            term = c
            for ai in a:
                term *= self.fact[ai]
            s += term
        # integral of l^a = vol * n! * prod a_i! / (|a| + n)!   (homogeneous: |a| = degree)
        value = VOLUME[self.dim] * self.fact[self.dim] * Fraction(s, self.fact[degree + self.dim])
        self.values[e] = value
        return value


def orthonormaliser(dim, exps, integrals):
    """T (float, M x M) with T G T^T = I for the exact Gram matrix G of the invariant monomials;
    also the exact integrals I (Fraction list)."""
    m = len(exps)
    gram = [[integrals.integral(tuple(a + b for a, b in zip(exps[i], exps[j])))
             for j in range(m)] for i in range(m)]
    # exact LDL^T
    lower = [[Fraction(0)] * m for _ in range(m)]
    diag = [Fraction(0)] * m
    for j in range(m):
        diag[j] = gram[j][j] - sum(lower[j][k] ** 2 * diag[k] for k in range(j))
        lower[j][j] = Fraction(1)
        for i in range(j + 1, m):
            lower[i][j] = (gram[i][j] - sum(lower[i][k] * lower[j][k] * diag[k]
                                            for k in range(j))) / diag[j]
    # inverse of unit lower triangular, exact
    inv = [[Fraction(0)] * m for _ in range(m)]
    for i in range(m):
        inv[i][i] = Fraction(1)
        for j in range(i):
            inv[i][j] = -sum(lower[i][k] * inv[k][j] for k in range(j, i))
    t = np.array([[float(inv[i][j]) / math.sqrt(diag[i]) for j in range(m)] for i in range(m)])
    return t, [integrals.integral(e) for e in exps]


# ---------------------------------------------------------------------------------------------
# Counting conditions


def stratum_sample(dim, name, rng):
    """Random integer m (sum 0) on the stratum of an orbit type (m_i = (n+1) l_i - 1)."""
    s, r, q = (int(v) for v in rng.integers(-1000, 1000, size=3))
    table = {
        (2, "1"): (0, 0, 0), (2, "3"): (s, s, -2 * s), (2, "6"): (s, r, -s - r),
        (3, "1"): (0, 0, 0, 0), (3, "31"): (s, s, s, -3 * s), (3, "22"): (s, s, -s, -s),
        (3, "211"): (s, s, r, -2 * s - r), (3, "1111"): (s, r, q, -s - r - q),
    }
    return table[(dim, name)]


def rank_mod_p(rows):
    rows = [list(r) for r in rows]
    rank = 0
    ncol = len(rows[0]) if rows else 0
    for c in range(ncol):
        piv = next((i for i in range(rank, len(rows)) if rows[i][c] % PRIME), None)
        if piv is None:
            continue
        rows[rank], rows[piv] = rows[piv], rows[rank]
        inv = pow(rows[rank][c], PRIME - 2, PRIME)
        rows[rank] = [(v * inv) % PRIME for v in rows[rank]]
        for i in range(len(rows)):
            if i != rank and rows[i][c] % PRIME:
                f = rows[i][c]
                rows[i] = [(a - f * b) % PRIME for a, b in zip(rows[i], rows[rank])]
        rank += 1
    return rank


def counting_conditions(dim, exps):
    """[(types in S, dim of invariants vanishing on the strata of all other types)]."""
    names = list(TYPES[dim])
    rng = np.random.default_rng(12345)
    samples = {}
    for name in names:
        rows = []
        for _ in range(len(exps) + 8 if name != "1" else 1):
            m = stratum_sample(dim, name, rng)
            t = [sum(mi ** k for mi in m) for k in range(2, dim + 2)]
            rows.append([math.prod(tk ** ek for tk, ek in zip(t, e)) % PRIME for e in exps])
        samples[name] = rows
    out = []
    for r in range(1, len(names) + 1):
        for subset in itertools.combinations(names, r):
            excluded = [n for n in names if n not in subset]
            rows = [row for n in excluded for row in samples[n]]
            out.append((subset, len(exps) - (rank_mod_p(rows) if rows else 0)))
    return out


def structures(dim, degree, exps, max_points):
    """Orbit-count dicts passing the counting conditions, by (points, params)."""
    conds = counting_conditions(dim, exps)
    names = list(TYPES[dim])
    sizes = {n: TYPES[dim][n][0] for n in names}
    out = []
    ranges = [range(2) if n == "1" else range(max_points // sizes[n] + 1) for n in names]
    for counts in itertools.product(*ranges):
        c = dict(zip(names, counts))
        points = sum(c[n] * sizes[n] for n in names)
        if points == 0 or points > max_points:
            continue
        ok = all(sum(c[n] * n_params(dim, n) for n in subset) >= need
                 for subset, need in conds)
        if ok:
            params = sum(c[n] * n_params(dim, n) for n in names)
            out.append((points, params, c))
    out.sort(key=lambda s: (s[0], s[1], [s[2][n] for n in names]))
    return out


# ---------------------------------------------------------------------------------------------
# Batched residual and Jacobian (float)


class System:
    def __init__(self, dim, degree):
        self.dim = dim
        self.degree = degree
        self.exps = invariant_exponents(dim, degree)
        self.integrals = InvariantIntegrals(dim)
        self.t_mat, self.exact = orthonormaliser(dim, self.exps, self.integrals)
        self.e = np.array(self.exps, dtype=float)  # M x K
        self.exps_int = np.array(self.exps, dtype=int)
        self.rhs = self.t_mat @ np.array([float(v) for v in self.exact])

    def invariants(self, lam):
        """lam (B, n+1) -> f (B, M), df/dlam (B, M, n+1)."""
        n = self.dim
        m = (n + 1) * lam - 1.0
        ks = range(2, n + 2)
        e = self.exps_int
        f = None
        tables = []
        for i, k in enumerate(ks):
            tk = np.sum(m ** k, axis=1)
            emax = int(e[:, i].max())
            tab = np.ones((lam.shape[0], emax + 2))
            for j in range(1, emax + 1):
                tab[:, j] = tab[:, j - 1] * tk
            tables.append(tab)
            f = tab[:, e[:, i]] if f is None else f * tab[:, e[:, i]]
        df = np.zeros((lam.shape[0], len(e), n + 1))
        for i, k in enumerate(ks):
            # df/dt_k = e_k t_k^(e_k - 1) prod_{j != k} t_j^e_j; dt_k/dlam = k (n+1) m^(k-1)
            d = self.e[:, i] * tables[i][:, np.maximum(e[:, i] - 1, 0)]
            for j in range(len(tables)):
                if j != i:
                    d = d * tables[j][:, e[:, j]]
            df += d[:, :, None] * (k * (n + 1) * m ** (k - 1))[:, None, :]
        return f, df


def softmax_generator(dim, name, u):
    """u (B, nfree) -> lam (B, n+1), dlam/du (B, n+1, nfree)."""
    pattern = TYPES[dim][name][1]
    b = u.shape[0]
    nf = u.shape[1]
    a = np.zeros((dim + 1, nf))
    for j, p in enumerate(pattern):
        if p is not None:
            a[j, p] = 1.0
    z = u @ a.T
    z = z - z.max(axis=1, keepdims=True)
    ez = np.exp(z)
    lam = ez / ez.sum(axis=1, keepdims=True)
    jac = (lam[:, :, None] * np.eye(dim + 1)[None] - lam[:, :, None] * lam[:, None, :]) @ a
    if nf == 0:
        jac = np.zeros((b, dim + 1, 0))
    return lam, jac


class Layout:
    """Parameter layout of a structure: per orbit (type, free-index slice, weight index)."""

    def __init__(self, dim, counts):
        self.dim = dim
        self.orbits = []
        k = 0
        for name, c in counts.items():
            for _ in range(c):
                nf = n_free(dim, name)
                self.orbits.append((name, slice(k, k + nf), k + nf))
                k += nf + 1
        self.size = k
        self.points = sum(TYPES[dim][o[0]][0] for o in self.orbits)
        self.groups = []  # per type: (name, free indices (orbits x nfree), weight indices)
        for name in counts:
            mine = [o for o in self.orbits if o[0] == name]
            if mine:
                free = np.array([list(range(o[1].start, o[1].stop)) for o in mine], dtype=int)
                free = free.reshape(len(mine), n_free(dim, name))
                self.groups.append((name, free, np.array([o[2] for o in mine], dtype=int)))


def residual_jacobian(system, layout, theta):
    """Orthonormalised residual (B, M) and Jacobian (B, M, P) in feasible variables."""
    b = theta.shape[0]
    m = len(system.exps)
    total = np.zeros((b, m))
    jac = np.zeros((b, m, layout.size))
    for name, free, weights in layout.groups:
        size = TYPES[layout.dim][name][0]
        no = len(weights)
        nf = free.shape[1]
        u = theta[:, free.reshape(-1)].reshape(b * no, nf)
        lam, dlam = softmax_generator(layout.dim, name, u)
        f, df = system.invariants(lam)
        w = (np.exp(theta[:, weights]) * size).reshape(b * no)
        wf = w[:, None] * f
        total += wf.reshape(b, no, m).sum(axis=1)
        jac[:, :, weights] = np.transpose(wf.reshape(b, no, m), (0, 2, 1))
        if nf:
            dj = w[:, None, None] * (df @ dlam)  # (b no) x M x nf
            dj = np.transpose(dj.reshape(b, no, m, nf), (0, 2, 1, 3)).reshape(b, m, no * nf)
            jac[:, :, free.reshape(-1)] = dj
    r = total @ system.t_mat.T - system.rhs[None, :]
    return r, system.t_mat[None] @ jac


def lm_solve(system, layout, theta, iterations=300, tol=1e-13):
    b = theta.shape[0]
    mu = np.full(b, 1e-2)
    r, jac = residual_jacobian(system, layout, theta)
    cost = np.sum(r * r, axis=1)
    active = np.ones(b, dtype=bool)
    stall = np.zeros(b, dtype=int)
    for _ in range(iterations):
        idx = np.nonzero(active)[0]
        if idx.size == 0:
            break
        j = jac[idx]
        jt = np.transpose(j, (0, 2, 1))
        a = jt @ j
        g = -(jt @ r[idx][:, :, None])[:, :, 0]
        d = np.einsum("bii->bi", a)
        a = a + (mu[idx][:, None] * (d + 1e-12))[:, :, None] * np.eye(layout.size)[None]
        try:
            step = np.linalg.solve(a, g[:, :, None])[:, :, 0]
        except np.linalg.LinAlgError:
            step = np.stack([np.linalg.lstsq(ai, gi, rcond=None)[0] for ai, gi in zip(a, g)])
        new = theta[idx] + np.clip(step, -2.0, 2.0)
        new = np.clip(new, -40.0, 40.0)
        r_new, j_new = residual_jacobian(system, layout, new)
        c_new = np.sum(r_new * r_new, axis=1)
        better = np.isfinite(c_new) & (c_new < cost[idx])
        acc = idx[better]
        rel = np.where(better, (cost[idx] - c_new) / np.maximum(cost[idx], 1e-300), 0.0)
        theta[acc] = new[better]
        r[acc] = r_new[better]
        jac[acc] = j_new[better]
        cost[acc] = c_new[better]
        mu[acc] = np.maximum(mu[acc] / 3.0, 1e-12)
        rej = idx[~better]
        mu[rej] = mu[rej] * 4.0
        stall[idx] = np.where(rel < 1e-4, stall[idx] + 1, 0)
        active[idx] = (cost[idx] > tol ** 2) & (mu[idx] < 1e12) & (stall[idx] < 25)
    return theta, np.sqrt(cost)


def random_starts(layout, rng, count):
    theta = np.empty((count, layout.size))
    vol = float(VOLUME[layout.dim])
    for name, sl, wi in layout.orbits:
        theta[:, sl] = rng.normal(0.0, 1.5, size=(count, sl.stop - sl.start))
        theta[:, wi] = np.log(vol / layout.points * rng.uniform(0.2, 2.0, size=count))
    return theta


# ---------------------------------------------------------------------------------------------
# High-precision polish and exact verification

NATURAL = {  # generator as c + A a in barycentric coordinates, a = free parameters
    (2, "1"): ((Fraction(1, 3),) * 3, ()),
    (2, "3"): ((0, 0, 1), ((1, 1, -2),)),
    (2, "6"): ((0, 0, 1), ((1, 0, -1), (0, 1, -1))),
    (3, "1"): ((Fraction(1, 4),) * 4, ()),
    (3, "31"): ((0, 0, 0, 1), ((1, 1, 1, -3),)),
    (3, "22"): ((0, 0, Fraction(1, 2), Fraction(1, 2)), ((1, 1, -1, -1),)),
    (3, "211"): ((0, 0, 0, 1), ((1, 1, 0, -2), (0, 0, 1, -1))),
    (3, "1111"): ((0, 0, 0, 1), ((1, 0, 0, -1), (0, 1, 0, -1), (0, 0, 1, -1))),
}


def natural_from_lam(dim, name, lam):
    """Free parameters a of the natural parametrisation from a float generator."""
    c, a = NATURAL[(dim, name)]
    if not a:
        return []
    if name == "22":
        return [lam[0]]
    return [lam[j] for j in range(len(a))] if name != "211" else [lam[0], lam[2]]


def natural_lam(dim, name, params):
    c, a = NATURAL[(dim, name)]
    lam = [Decimal(ci.numerator) / Decimal(ci.denominator) if isinstance(ci, Fraction)
           else Decimal(ci) for ci in c]
    for p, col in zip(params, a):
        lam = [li + p * cj for li, cj in zip(lam, col)]
    return lam


def polish(system, dim, orbits, iterations=40):
    """orbits: [(name, [Decimal free params], Decimal weight per point)] -> polished, residual."""
    exact = [Decimal(v.numerator) / Decimal(v.denominator) for v in system.exact]
    k_range = range(2, dim + 2)
    res_norm = None
    for _ in range(iterations):
        total = [Decimal(0)] * len(system.exps)
        cols = []
        for name, params, w in orbits:
            size = TYPES[dim][name][0]
            lam = natural_lam(dim, name, params)
            m = [(dim + 1) * li - 1 for li in lam]
            t = [sum(mi ** k for mi in m) for k in k_range]
            f = [math.prod((tk ** ek for tk, ek in zip(t, e) if ek), start=Decimal(1))
                 for e in system.exps]
            for i, fi in enumerate(f):
                total[i] += w * size * fi
            # float Jacobian in natural parameters
            lam_f = np.array([[float(x) for x in lam]])
            ff, dfl = system.invariants(lam_f)
            _, a = NATURAL[(dim, name)]
            cols.append(size * (system.t_mat @ ff[0]))
            for col in a:
                cols.append(float(w) * size * (system.t_mat @ (dfl[0] @ np.array(col, float))))
        r = np.array([float(x - y) for x, y in zip(total, exact)])
        rr = system.t_mat @ r
        res_norm = float(np.linalg.norm(rr))
        if res_norm < 1e-40:
            break
        jac = np.stack(cols, axis=1)
        step = np.linalg.lstsq(jac, -rr, rcond=None)[0]
        k = 0
        new = []
        for name, params, w in orbits:
            w2 = w + Decimal(float(step[k]))
            k += 1
            p2 = []
            for p in params:
                p2.append(p + Decimal(float(step[k])))
                k += 1
            new.append((name, p2, w2))
        orbits = new
    return orbits, res_norm


def expand_points(dim, gen):
    """Distinct permutations of a barycentric tuple (floats), as Cartesian rows."""
    perms = sorted(set(itertools.permutations(gen)))
    return [p[1:] for p in perms]


def monomial_check(dim, degree, rule):
    """rule: [(generator floats, weight float)]. Worst relative monomial error, exact arithmetic
    (every double is an integer over a power of two: integers over common powers of two)."""
    pts = [(p, w) for gen, w in rule for p in expand_points(dim, gen)]
    shift = max(Fraction(x).denominator for p, w in pts for x in p).bit_length() - 1
    wshift = max(Fraction(w).denominator for _, w in pts).bit_length() - 1
    coords = [[int(Fraction(x) * (1 << shift)) for x in p] for p, _ in pts]
    weights = [int(Fraction(w) * (1 << wshift)) for _, w in pts]
    powers = [[[1] for _ in range(dim)] for _ in pts]
    for q, c in enumerate(coords):
        for d in range(dim):
            for _ in range(degree):
                powers[q][d].append(powers[q][d][-1] * c[d])
    fact = [math.factorial(i) for i in range(degree + dim + 1)]
    worst = 0.0
    for exps in itertools.product(range(degree + 1), repeat=dim):
        total = sum(exps)
        if total > degree:
            continue
        s = 0
        for q, w in enumerate(weights):
            term = w
            for d in range(dim):
                term *= powers[q][d][exps[d]]
            s += term
        value = Fraction(s, 1 << (wshift + shift * total))
        exact = Fraction(math.prod(fact[e] for e in exps), fact[total + dim])
        worst = max(worst, abs(float((value - exact) / exact)))
    return worst, len(pts)


def finalize(system, layout, theta):
    """Float solution -> verified rule [(generator floats, weight)] or None."""
    dim = layout.dim
    orbits = []
    for name, sl, wi in layout.orbits:
        lam, _ = softmax_generator(dim, name, theta[None, sl])
        params = [Decimal(float(x)) for x in natural_from_lam(dim, name, lam[0])]
        orbits.append((name, params, Decimal(float(np.exp(theta[wi])))))
    orbits, res = polish(system, dim, orbits)
    if res is None or not res < 1e-30:
        return None
    rule = []
    min_weight = MIN_WEIGHT_FRACTION * float(VOLUME[dim]) / layout.points
    for name, params, w in orbits:
        lam = natural_lam(dim, name, params)
        if w < min_weight or min(lam) < MIN_BARYCENTRIC:
            return None
        rule.append((tuple(float(x) for x in lam), float(w)))
    pts = np.array([p for gen, _ in rule for p in expand_points(dim, gen)])
    if len(pts) != layout.points:
        return None
    dist = np.linalg.norm(pts[:, None, :] - pts[None, :, :], axis=2) + np.eye(len(pts))
    if dist.min() < 1e-8:
        return None
    err, _ = monomial_check(dim, system.degree, rule)
    if err > 1e-14:
        return None
    return rule, err


def search(dim, degree, budget, starts, log):
    """Smallest rule found for (dim, degree), or None."""
    n = (degree + 2) // 2
    collapsed = n ** dim
    system = System(dim, degree)
    candidates = structures(dim, degree, system.exps, collapsed - 1)
    t0 = time.time()
    log(f"{'tri' if dim == 2 else 'tet'} degree {degree}: {len(system.exps)} equations, "
        f"{len(candidates)} structures below {collapsed} points")
    last_points = None
    for points, params, counts in candidates:
        if points != last_points:
            log(f"  {points} points ({time.time() - t0:.1f} s)")
            last_points = points
        if time.time() - t0 > budget:
            log("  time budget exhausted")
            return None
        layout = Layout(dim, counts)
        seed = hash_seed(dim, degree, counts)
        rng = np.random.default_rng(seed)
        theta = random_starts(layout, rng, starts)
        theta, res = lm_solve(system, layout, theta)
        order = np.argsort(res)
        for i in order:
            if res[i] > 1e-9:
                break
            out = finalize(system, layout, theta[i])
            if out is not None:
                rule, err = out
                log(f"  found {points} points {dict(counts)} seed {seed} "
                    f"max monomial rel. error {err:.1e} ({time.time() - t0:.1f} s)")
                return {"dim": dim, "degree": degree, "points": points, "counts": counts,
                        "rule": rule, "error": err, "seed": seed}
    log("  nothing found below the collapsed rule")
    return None


def hash_seed(dim, degree, counts):
    s = f"{dim}:{degree}:" + ",".join(f"{k}{v}" for k, v in counts.items())
    h = 0
    for ch in s.encode():
        h = (h * 131 + ch) % (1 << 31)
    return h


# ---------------------------------------------------------------------------------------------
# Output


def fmt(x):
    return f"{x:.16e}"


def comment_of(r):
    kind = "triangle" if r["dim"] == 2 else "tetrahedron"
    counts = ", ".join(f"[{k}] x {v}" for k, v in r["counts"].items() if v)
    return (f"{kind}, degree {r['degree']}: {r['points']} points; orbits {counts}; "
            f"max monomial rel. error {r['error']:.1e}")


def render(rules, commands):
    lines = ["// generated by tools/gen_symmetric_quadrature.py — do not edit"]
    lines += [f"// command: {c}" for c in commands]
    lines += [
        "//",
        "// Fully symmetric quadrature rules on the reference triangle and tetrahedron, found",
        "// by search (random starts + Levenberg-Marquardt on the invariant moment equations,",
        "// decimal polish) and verified in exact rational arithmetic on every monomial of",
        "// degree <= degree. Each orbit is one generator in barycentric coordinates",
        "// (l0, l1, l2[, l3]) with its weight per point; the rule's points are the distinct",
        "// permutations of every generator, Cartesian (x, y[, z]) = (l1, l2[, l3]).",
        "// Weights sum to 1/2 (triangle), 1/6 (tetrahedron).",
        "// Included by fem/quadrature/simplex_quadrature.cpp inside namespace",
        "// curvefem::fem::generated.",
        "",
        "// clang-format off",
        "",
        "struct SymmetricOrbit {",
        "  double barycentric[4];  // generator; triangles leave the 4th entry 0",
        "  double weight;          // per point",
        "};",
        "",
        "struct SymmetricRule {",
        "  int dimension;  // 2 triangle, 3 tetrahedron",
        "  int degree;     // exact for total degree <= degree",
        "  int points;     // after expansion",
        "  int orbit_count;",
        "  const SymmetricOrbit* orbits;",
        "};",
        "",
    ]
    entries = []
    for r in sorted(rules, key=lambda r: (r["dim"], r["degree"])):
        dim, degree = r["dim"], r["degree"]
        kind = "triangle" if dim == 2 else "tetrahedron"
        name = f"k_{kind}_{degree}"
        lines.append(f"// {r['comment']}")
        lines.append(f"inline constexpr SymmetricOrbit {name}[] = {{")
        for gen, w in r["rule"]:
            g = list(gen) + [0.0] * (4 - len(gen))
            lines.append("  {{" + ", ".join(fmt(x) for x in g) + "},")
            lines.append(f"   {fmt(w)}}},")
        lines.append("};")
        lines.append("")
        entries.append(f"  {{{dim}, {degree}, {r['points']}, {len(r['rule'])}, {name}}},")
    lines.append("inline constexpr SymmetricRule k_symmetric_rules[] = {")
    lines.extend(entries)
    lines.append("};")
    lines.append("")
    lines.append("// clang-format on")
    return "\n".join(lines) + "\n"


def parse_inc(text):
    """Rules and commands of a rendered file: ([{dim, degree, points, rule, comment}], [cmd])."""
    rules = []
    blocks = re.findall(r"// ((triangle|tetrahedron), degree (\d+): (\d+) points[^\n]*)\n"
                        r"inline constexpr SymmetricOrbit \w+\[\] = \{\n(.*?)\n\};", text, re.S)
    for comment, kind, degree, points, body in blocks:
        dim = 2 if kind == "triangle" else 3
        nums = [float(x) for x in re.findall(r"[-+]?\d\.\d+e[-+]\d+", body)]
        rule = []
        for i in range(0, len(nums), 5):
            rule.append((tuple(nums[i:i + dim + 1]), nums[i + 4]))
        rules.append({"dim": dim, "degree": int(degree), "points": int(points), "rule": rule,
                      "comment": comment})
    commands = re.findall(r"^// command: (.*)$", text, re.M)
    return rules, commands


def verify(rule):
    err, count = monomial_check(rule["dim"], rule["degree"], rule["rule"])
    min_weight = MIN_WEIGHT_FRACTION * float(VOLUME[rule["dim"]]) / rule["points"]
    ok = (count == rule["points"] and err < 1e-14
          and all(w >= min_weight for _, w in rule["rule"])
          and all(min(g) >= MIN_BARYCENTRIC for g, _ in rule["rule"]))
    return ok, err, count


def compact(found):
    """[(2, 2), (2, 3), (2, 5), (3, 4)] -> 'tri 2-3, 5; tet 4'."""
    parts = []
    for dim, kind in ((2, "tri"), (3, "tet")):
        degrees = sorted(d for k, d in found if k == dim)
        runs = []
        for d in degrees:
            if runs and d == runs[-1][1] + 1:
                runs[-1][1] = d
            else:
                runs.append([d, d])
        if runs:
            parts.append(kind + " " + ", ".join(f"{a}-{b}" if b > a else f"{a}" for a, b in runs))
    return "; ".join(parts)


def parse_range(s):
    if not s:
        return []
    out = []
    for part in s.split(","):
        if "-" in part:
            a, b = part.split("-")
            out.extend(range(int(a), int(b) + 1))
        else:
            out.append(int(part))
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tri", default="1-12", help="triangle degrees, e.g. 1-12")
    parser.add_argument("--tet", default="1-10", help="tetrahedron degrees, e.g. 1-10")
    parser.add_argument("--budget", type=float, default=600.0, help="seconds per degree")
    parser.add_argument("--starts", type=int, default=256, help="random starts per structure")
    parser.add_argument("--output", type=Path, default=OUTPUT)
    parser.add_argument("--verify", action="store_true",
                        help="verify the rules in --output exactly and exit")
    parser.add_argument("--keep", action="store_true",
                        help="keep the rules of --output for degrees not searched (re-verified); "
                             "the header lists every command that contributed")
    parser.add_argument("--merge", type=Path, action="append", default=[],
                        help="with --keep: also take the rules (and commands) of this file, "
                             "replacing kept ones of the same degree (re-verified)")
    args = parser.parse_args()

    if args.verify:
        bad = 0
        for r in parse_inc(args.output.read_text())[0]:
            ok, err, count = verify(r)
            bad += not ok
            print(f"{'tri' if r['dim'] == 2 else 'tet'} degree {r['degree']}: {count} points, "
                  f"max monomial rel. error {err:.1e} {'ok' if ok else 'FAILED'}")
        return 1 if bad else 0

    def log(msg):
        print(msg, file=sys.stderr, flush=True)

    if np is None:
        log("the search needs numpy (python3-numpy)")
        return 2
    searched = [(2, d) for d in parse_range(args.tri)] + [(3, d) for d in parse_range(args.tet)]
    rules, commands = [], []
    if args.keep and args.output.exists():
        old_rules, commands = parse_inc(args.output.read_text())
        for extra in args.merge:
            more, more_commands = parse_inc(extra.read_text())
            keys = {(r["dim"], r["degree"]) for r in more}
            old_rules = [r for r in old_rules if (r["dim"], r["degree"]) not in keys] + more
            commands += more_commands
        for r in old_rules:
            if (r["dim"], r["degree"]) in searched:
                continue
            ok, _, _ = verify(r)
            if not ok:
                log(f"dropping kept rule {r['comment']}: verification failed")
                continue
            rules.append(r)
    found_here = []
    for dim, degree in searched:
        found = search(dim, degree, args.budget, args.starts, log)
        if found:
            found["comment"] = comment_of(found)
            rules.append(found)
            found_here.append((dim, degree))
    command = "tools/gen_symmetric_quadrature.py " + " ".join(
        f"'{a}'" if a == "" or " " in a else a for a in sys.argv[1:])
    commands.append(f"{command.strip()}  (rules found: {compact(found_here) or 'none'})")
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(render(rules, commands))
    log(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
