#include "meshing/curved/jacobian_certificate.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cfenv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/core/lagrange_nodes.hpp"

namespace curvefem::meshing::curved {
namespace generated {
#include "meshing/curved/generated/bernstein_tables.inc"
}  // namespace generated

namespace {

// ---------------------------------------------------------------------------------------------
// Error model (round-to-nearest, IEEE double). u = 2^-53 is the unit roundoff: every operation
// satisfies |fl(a∘b) − a∘b| ≤ u·|fl(a∘b)| + (underflow) with an underflow term ≤ 2^-1074 for
// products (0 for sums). Dot products of length n obey |fl(Σ a_i b_i) − Σ a_i b_i| ≤ γ_n Σ|a_i
// b_i|, γ_n = n u/(1 − n u). Every radius below is an a priori bound of that kind, multiplied by 2:
// the factor covers the rounding committed while evaluating the bound itself (a handful of products
// of non-negative numbers, relative error ≤ 6u) and the second-order terms of γ_n. Absolute terms
// k_tiny (≫ any sum of underflow errors, including flush-to-zero) cover underflow.
constexpr double k_u = 0x1p-53;
constexpr double k_tiny = 1e-290;

// Outward rounding of one round-to-nearest result z = fl(exact): down(z) ≤ exact ≤ up(z).
// z·2^-52 ≥ ulp(z), so z ± |z|·2^-52 reaches the next double outwards (Rump's succ/pred); the
// added 2^-1022 covers zero, subnormals and flush-to-zero.
inline double up(double z) { return z + (std::abs(z) * 0x1p-52 + 0x1p-1022); }
inline double down(double z) { return z - (std::abs(z) * 0x1p-52 + 0x1p-1022); }

// Switches the calling thread to round-to-nearest for the scope, if it is in another mode.
class NearestRounding {
 public:
  NearestRounding() : m_mode(std::fegetround()) {
    if (m_mode != FE_TONEAREST) std::fesetround(FE_TONEAREST);
  }
  ~NearestRounding() {
    if (m_mode != FE_TONEAREST) std::fesetround(m_mode);
  }
  NearestRounding(const NearestRounding&) = delete;
  NearestRounding& operator=(const NearestRounding&) = delete;

 private:
  int m_mode;
};

constexpr int num_nodes(int k) { return (k + 1) * (k + 2) * (k + 3) / 6; }
constexpr int degree_of(int k) { return 3 * (k - 1); }
constexpr int num_lattice(int k) { return num_nodes(degree_of(k)); }
static_assert(num_lattice(4) == 220 && num_lattice(1) == 1);

long long factorial(int n) {
  long long r = 1;
  for (int i = 2; i <= n; ++i) r *= i;
  return r;
}

long long multinomial(const std::array<int, 4>& a) {
  return factorial(a[0] + a[1] + a[2] + a[3]) /
         (factorial(a[0]) * factorial(a[1]) * factorial(a[2]) * factorial(a[3]));
}

// Red refinement: child tets as 4 points, each 2 × (barycentric coordinates w.r.t. the parent).
// Vertices v_i = 2 e_i, midpoints m_ab = e_a + e_b. Corner tets first, then the 4 inner tets
// around the diagonal m02–m13 (the thesis' choice).
using Point2 = std::array<int, 4>;
constexpr Point2 vtx(int i) {
  Point2 p{0, 0, 0, 0};
  p[i] = 2;
  return p;
}
constexpr Point2 mid(int a, int b) {
  Point2 p{0, 0, 0, 0};
  p[a] = 1;
  p[b] = 1;
  return p;
}
const std::array<std::array<Point2, 4>, 8> k_red_children = {{
    {vtx(0), mid(0, 1), mid(0, 2), mid(0, 3)},
    {mid(0, 1), vtx(1), mid(1, 2), mid(1, 3)},
    {mid(0, 2), mid(1, 2), vtx(2), mid(2, 3)},
    {mid(0, 3), mid(1, 3), mid(2, 3), vtx(3)},
    {mid(0, 2), mid(1, 3), mid(0, 1), mid(0, 3)},
    {mid(0, 2), mid(1, 3), mid(0, 3), mid(2, 3)},
    {mid(0, 2), mid(1, 3), mid(2, 3), mid(1, 2)},
    {mid(0, 2), mid(1, 3), mid(1, 2), mid(0, 1)},
}};

// Tables of one order, prepared once from the generated ones.
struct Prepared {
  int order = 0, degree = 0, n = 0, m = 0;
  std::vector<std::array<int, 4>> lattice;  // m
  double den = 1.0;                         // D: gradients = D · ∂N/∂ξ
  double den3 = 1.0;                        // D³ (exact)
  std::vector<double> gt;                   // [c][i][j]: D ∂N_i/∂ξ_c at lattice point j
  std::vector<double> gs;                   // gt / D (the same layout), for the plain J
  std::vector<double> sg;                   // [c][j]: Σ_i |gt[c][i][j]| (exact integers)
  std::vector<double> l2b;                  // column-major lower enclosure: [j][alpha]
  double abs_row_sum = 1.0, width_row_sum = 0.0;
  std::array<std::vector<double>, 8> sub;  // column-major exact subdivision matrices [alpha][gamma]
  std::vector<std::array<int, 4>> nodes;   // n multi-indices α of the order-k nodes (core order)
  std::array<double, 3> grad_bound{};  // Λ_c ≥ max_ξ Σ_{i≥4} |∂N_i/∂ξ_c| (generated)
};

// Exact subdivision matrix of the Bernstein form on child tet `child` (see k_red_children):
// S[γ][α] = C(d;α) e_{γα} / (C(d;γ) 2^d), e_{γα} the μ^γ coefficient of Π_i L_i(μ)^{α_i},
// L_i(μ) = Σ_j 2·P_j[i] μ_j. Entries are dyadic (blossom values at points with coordinates in
// {0, ½, 1}), hence exact doubles; each row sums to 1. Computed in integers and verified.
std::vector<double> subdivision_matrix(const Prepared& t, const std::array<Point2, 4>& child) {
  const int d = t.degree, m = t.m, stride = d + 1;
  auto key = [stride](const std::array<int, 4>& e) {
    return (e[1] * stride + e[2]) * stride + e[3];
  };
  // Monomials of every degree 0..d and their positions.
  std::vector<std::vector<std::array<int, 4>>> exps(d + 1);
  std::vector<std::vector<int>> pos(d + 1, std::vector<int>(stride * stride * stride, -1));
  for (int deg = 0; deg <= d; ++deg) {
    for (int a1 = 0; a1 <= deg; ++a1)
      for (int a2 = 0; a1 + a2 <= deg; ++a2)
        for (int a3 = 0; a1 + a2 + a3 <= deg; ++a3) {
          const std::array<int, 4> e{deg - a1 - a2 - a3, a1, a2, a3};
          pos[deg][key(e)] = static_cast<int>(exps[deg].size());
          exps[deg].push_back(e);
        }
  }
  // poly[deg][p] = coefficients (over exps[deg]) of Π_i L_i^{α_i}, α = exps[deg][p].
  std::vector<std::vector<std::vector<std::int64_t>>> poly(d + 1);
  poly[0] = {{1}};
  for (int deg = 1; deg <= d; ++deg) {
    poly[deg].resize(exps[deg].size());
    for (std::size_t p = 0; p < exps[deg].size(); ++p) {
      std::array<int, 4> alpha = exps[deg][p];
      int i = 0;
      while (alpha[i] == 0) ++i;
      alpha[i] -= 1;
      const auto& parent = poly[deg - 1][pos[deg - 1][key(alpha)]];
      auto& out = poly[deg][p];
      out.assign(exps[deg].size(), 0);
      for (std::size_t q = 0; q < parent.size(); ++q) {
        if (parent[q] == 0) continue;
        for (int j = 0; j < 4; ++j) {
          if (child[j][i] == 0) continue;
          std::array<int, 4> e = exps[deg - 1][q];
          e[j] += 1;
          out[pos[deg][key(e)]] += parent[q] * child[j][i];
        }
      }
    }
  }
  std::vector<double> sub(static_cast<std::size_t>(m) * m, 0.0);
  const double inv = std::ldexp(1.0, -d);
  for (int a = 0; a < m; ++a) {
    const auto& coef = poly[d][pos[d][key(t.lattice[a])]];
    const long long ca = multinomial(t.lattice[a]);
    for (int g = 0; g < m; ++g) {
      const std::int64_t e = coef[pos[d][key(t.lattice[g])]];
      const long long cg = multinomial(t.lattice[g]);
      CF_VERIFY((ca * e) % cg == 0, "subdivision coefficient is not dyadic");
      sub[static_cast<std::size_t>(a) * m + g] = static_cast<double>((ca * e) / cg) * inv;
    }
  }
  for (int g = 0; g < m; ++g) {
    double s = 0.0;
    for (int a = 0; a < m; ++a) s += sub[static_cast<std::size_t>(a) * m + g];
    CF_VERIFY(s == 1.0, "subdivision matrix rows must sum to 1");
  }
  return sub;
}

Prepared prepare(int order) {
  Prepared t;
  t.order = order;
  t.degree = degree_of(order);
  t.n = num_nodes(order);
  t.m = num_lattice(order);
  const int n = t.n, m = t.m;
  t.gt.assign(static_cast<std::size_t>(3) * n * m, 0.0);
  t.sg.assign(static_cast<std::size_t>(3) * m, 0.0);
  if (order == 1) {
    t.lattice = {{0, 0, 0, 0}};
    for (int c = 0; c < 3; ++c) {
      t.gt[(c * n + 0) * m] = -1.0;
      t.gt[(c * n + c + 1) * m] = 1.0;
    }
    t.l2b = {1.0};
  } else {
    const auto& g = generated::k_bernstein_tables[order - 2];
    CF_VERIFY(g.order == order && g.num_nodes == n && g.num_lattice == m, "bad generated table");
    t.lattice.resize(m);
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < 4; ++i) t.lattice[j][i] = g.lattice[4 * j + i];
    t.den = g.gradient_denominator;
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c)
          t.gt[(static_cast<std::size_t>(c) * n + i) * m + j] = g.gradients[(j * n + i) * 3 + c];
    t.l2b.resize(static_cast<std::size_t>(m) * m);
    for (int a = 0; a < m; ++a)
      for (int j = 0; j < m; ++j)
        t.l2b[static_cast<std::size_t>(j) * m + a] =
            g.l2b_lower[static_cast<std::size_t>(a) * m + j];
    t.abs_row_sum = g.l2b_abs_row_sum;
    t.width_row_sum = g.l2b_width_row_sum;
    for (int c = 0; c < 8; ++c) t.sub[c] = subdivision_matrix(t, k_red_children[c]);
  }
  t.den3 = t.den * t.den * t.den;
  t.nodes = lagrange_lattice(CellKind::tetrahedron, order);
  CF_VERIFY(static_cast<int>(t.nodes.size()) == n, "bad node lattice");
  for (int v = 0; v < 4; ++v) CF_VERIFY(t.nodes[v][v] == order, "the corners must come first");
  for (int c = 0; c < 3; ++c) {
    t.grad_bound[c] = generated::k_gradient_bernstein_bounds[order - 1][c];
    CF_VERIFY(t.grad_bound[c] >= 0.0 && (order > 1 || t.grad_bound[c] == 0.0),
              "bad generated gradient bound");
  }
  for (int c = 0; c < 3; ++c)
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < m; ++j)
        t.sg[c * m + j] += std::abs(t.gt[(static_cast<std::size_t>(c) * n + i) * m + j]);
  t.gs.resize(t.gt.size());
  for (std::size_t i = 0; i < t.gt.size(); ++i) t.gs[i] = t.gt[i] / t.den;
  return t;
}

const Prepared& tables(int order) {
  static const std::array<Prepared, 4> all = {prepare(1), prepare(2), prepare(3), prepare(4)};
  return all[order - 1];
}

void check_input(int order, const Eigen::Ref<const Eigen::MatrixXd>& nodes) {
  if (order < 1 || order > 4)
    throw InputError("certify_tet_jacobian: order " + std::to_string(order) +
                     " is outside the supported range 1..4");
  if (nodes.rows() != num_nodes(order) || nodes.cols() != 3)
    throw InputError("certify_tet_jacobian: an order-" + std::to_string(order) + " tet needs " +
                     std::to_string(num_nodes(order)) + " x 3 nodes, got " +
                     std::to_string(nodes.rows()) + " x " + std::to_string(nodes.cols()));
}

// ---------------------------------------------------------------------------------------------
// det J at the lattice with radii (scaled by D³), and the Bernstein coefficients.

template <int K>
struct Evaluation {
  static constexpr int N = num_nodes(K);
  static constexpr int M = num_lattice(K);
  std::array<double, M> vm;  // fl(det Jint) at the lattice, Jint = D·J
  std::array<double, M> vr;  // |det Jint − vm| ≤ vr
  bool finite = true;
};

// J entries: Jint[c][r][j] = Σ_i (x_i − x_0)_r · gt[c][i][j]. With d_i = fl(x_i − x_0):
//   |fl(Σ d_i g_i) − Σ (x_i − x_0) g_i| ≤ (γ_n + u) Σ|d_i||g_i| ≤ (γ_n + u) dmax_r sg[c][j].
// det: |det(Jm + E) − fl(det Jm)| ≤ [Π_c(A_c + ρ_c) − Π_c A_c] + γ_5 Π_c A_c with A_c = ‖Jm col
// c‖₁, ρ_c ≥ ‖E col c‖₁ (Hadamard: |det(u,v,w)| ≤ ‖u‖₂‖v‖₂‖w‖₂ ≤ ‖u‖₁‖v‖₁‖w‖₁, multilinearity), the
// bracket evaluated as ρ0 B1 B2 + A0 (ρ1 B2 + A1 ρ2), B = A + ρ (no cancellation).
template <int K>
void evaluate_lattice(const Prepared& t, const Eigen::Ref<const Eigen::MatrixXd>& nodes,
                      Evaluation<K>& ev) {
  constexpr int N = Evaluation<K>::N, M = Evaluation<K>::M;
  std::array<double, N> dx[3];
  double dmax[3] = {0.0, 0.0, 0.0};
  for (int r = 0; r < 3; ++r) {
    const double x0 = nodes(0, r);
    for (int i = 0; i < N; ++i) {
      const double x = nodes(i, r);
      if (!std::isfinite(x) || std::abs(x) > 1e90) ev.finite = false;
      dx[r][i] = x - x0;
      dmax[r] = std::max(dmax[r], std::abs(dx[r][i]));
    }
  }
  if (!ev.finite) return;
  // Jint[c][r] = G_c · d_r: dense GEMVs (any summation order satisfies the γ_n bound).
  Eigen::Matrix<double, M, 3> jac[3];  // [c](j, r)
  for (int c = 0; c < 3; ++c) {
    const Eigen::Map<const Eigen::Matrix<double, M, N>> g(t.gt.data() +
                                                          static_cast<std::size_t>(c) * N * M);
    for (int r = 0; r < 3; ++r) {
      const Eigen::Map<const Eigen::Matrix<double, N, 1>> d(dx[r].data());
      jac[c].col(r).noalias() = g * d;
    }
  }
  const double c1 = 2.0 * (N + 2) * k_u * (dmax[0] + dmax[1] + dmax[2]);
  const double g5 = 2.0 * 6.0 * k_u;
  const double* sg0 = t.sg.data();
  const double* sg1 = sg0 + M;
  const double* sg2 = sg1 + M;
  for (int j = 0; j < M; ++j) {
    const double a00 = jac[0](j, 0), a10 = jac[0](j, 1), a20 = jac[0](j, 2);  // column 0
    const double a01 = jac[1](j, 0), a11 = jac[1](j, 1), a21 = jac[1](j, 2);  // column 1
    const double a02 = jac[2](j, 0), a12 = jac[2](j, 1), a22 = jac[2](j, 2);  // column 2
    const double det = a00 * (a11 * a22 - a21 * a12) - a10 * (a01 * a22 - a21 * a02) +
                       a20 * (a01 * a12 - a11 * a02);
    const double A0 = std::abs(a00) + std::abs(a10) + std::abs(a20);
    const double A1 = std::abs(a01) + std::abs(a11) + std::abs(a21);
    const double A2 = std::abs(a02) + std::abs(a12) + std::abs(a22);
    const double r0 = c1 * sg0[j] + 3.0 * k_tiny;
    const double r1 = c1 * sg1[j] + 3.0 * k_tiny;
    const double r2 = c1 * sg2[j] + 3.0 * k_tiny;
    const double B1 = A1 + r1, B2 = A2 + r2;
    ev.vm[j] = det;
    ev.vr[j] = 2.0 * (r0 * B1 * B2 + A0 * (r1 * B2 + A1 * r2)) + g5 * (A0 * A1 * A2) + k_tiny;
  }
  // std::min/max silently drop NaN: refuse any non-finite value here, once.
  for (int j = 0; j < M; ++j)
    if (!std::isfinite(ev.vm[j]) || !std::isfinite(ev.vr[j])) ev.finite = false;
}

// b = M v: bm = fl(Mlo · vm), |b − bm| ≤ RS·max vr + (W + γ_m RS)·max|vm| (RS bounds the absolute
// row sums of M and Mlo, W those of M − Mlo).
template <int K>
double bernstein(const Prepared& t, const Evaluation<K>& ev,
                 std::array<double, num_lattice(K)>& b) {
  constexpr int M = num_lattice(K);
  double vmax = 0.0, rmax = 0.0;
  for (int j = 0; j < M; ++j) {
    vmax = std::max(vmax, std::abs(ev.vm[j]));
    rmax = std::max(rmax, ev.vr[j]);
  }
  const Eigen::Map<const Eigen::Matrix<double, M, M>> l2b(t.l2b.data());
  Eigen::Map<Eigen::Matrix<double, M, 1>>(b.data()).noalias() =
      l2b * Eigen::Map<const Eigen::Matrix<double, M, 1>>(ev.vm.data());
  const double rs = t.abs_row_sum;
  return up(2.0 * (rs * rmax + (t.width_row_sum + 2.0 * M * k_u * rs) * vmax)) + k_tiny;
}

// Recursive red refinement of one Bernstein coefficient vector (scaled units).
template <int K>
class Refiner {
 public:
  static constexpr int M = num_lattice(K);

  Refiner(const Prepared& t, const CertificateOptions& opts, JacobianCertificate& out)
      : m_t(t), m_opts(opts), m_out(out) {
    m_work.resize(static_cast<std::size_t>(std::max(opts.max_depth, 0)) * 8 * M);
  }

  double min_lower = std::numeric_limits<double>::infinity();
  double min_upper = std::numeric_limits<double>::infinity();

  // (b, r): coefficients of a sub-tet at `depth` that are not all certainly positive.
  JacobianVerdict refine(const double* b, double r, int depth) {
    if (depth >= m_opts.max_depth) return JacobianVerdict::undecided;
    double bmax = 0.0;
    for (int a = 0; a < M; ++a) bmax = std::max(bmax, std::abs(b[a]));
    // Child = S·b with S ≥ 0 exact, rows summing to 1: |S b_true − fl(S bm)| ≤ r + γ_m max|bm|.
    const double child_r = up(r + 4.0 * M * k_u * bmax) + k_tiny;
    double* children = m_work.data() + static_cast<std::size_t>(depth) * 8 * M;
    bool pending[8];
    for (int c = 0; c < 8; ++c) {
      if (m_out.subtets_visited >= m_opts.max_subtets) return JacobianVerdict::undecided;
      ++m_out.subtets_visited;
      m_out.depth_reached = std::max(m_out.depth_reached, depth + 1);
      double* ch = children + static_cast<std::size_t>(c) * M;
      const Eigen::Map<const Eigen::Matrix<double, M, M>> sub(m_t.sub[c].data());
      Eigen::Map<Eigen::Matrix<double, M, 1>>(ch).noalias() =
          sub * Eigen::Map<const Eigen::Matrix<double, M, 1>>(b);
      // Corner coefficients 0..3 are det J at the child's vertices: point values.
      for (int q = 0; q < 4; ++q) {
        const double hi = up(ch[q] + child_r);
        min_upper = std::min(min_upper, hi);
        if (hi <= 0.0) return JacobianVerdict::non_positive;
      }
      double lo = std::numeric_limits<double>::infinity();
      for (int g = 0; g < M; ++g) lo = std::min(lo, down(ch[g] - child_r));
      pending[c] = !(lo > 0.0);
      if (!pending[c]) min_lower = std::min(min_lower, lo);
    }
    for (int c = 0; c < 8; ++c) {
      if (!pending[c]) continue;
      const JacobianVerdict v =
          refine(children + static_cast<std::size_t>(c) * M, child_r, depth + 1);
      if (v != JacobianVerdict::positive) return v;
    }
    return JacobianVerdict::positive;
  }

 private:
  const Prepared& m_t;
  const CertificateOptions& m_opts;
  JacobianCertificate& m_out;
  std::vector<double> m_work;
};

// ---------------------------------------------------------------------------------------------
// Affine path (nearly straight tets, where the Bernstein bounds above, which scale like |J|³, swamp
// det J ≪ |J|³).
//
// The order-k basis reproduces affine maps, so with J_a = [x1 − x0, x2 − x0, x3 − x0] and the
// node deviations d_i = x_i − aff(ξ_i) (zero at the corners): J(ξ) = J_a + E(ξ),
// E(ξ) = Σ_{i≥4} d_i ∇N_i(ξ)ᵀ, hence ‖column c of E(ξ)‖₂ ≤ ε_c = Λ_c max_i ‖d_i‖₂ on the whole tet
// (Λ_c generated, see tools/gen_bernstein_tables.py). det is multilinear in the columns and every
// term with at least one E column is bounded by the product of its column norms (Hadamard), so
//   |det J(ξ) − det J_a| ≤ Π_c (A_c + ε_c) − Π_c A_c = ε0 B1 B2 + A0 (ε1 B2 + A1 ε2) =: δ,
// A_c ≥ ‖column c of J_a‖₂, B = A + ε (no cancellation). Rounding:
//  * y_v = fl(x_v − x0): |y_v − (x_v − x0)| ≤ u|y_v| componentwise (a difference never underflows).
//  * det J_a: every Leibniz term of det Y differs from the exact one by ≤ ((1+u)³ − 1) relative and
//    the cofactor evaluation commits ≤ γ5 per term, so |fl(det Y) − det J_a| ≤ 8.01u perm|Y|; we
//    use 16u·fl(perm|Y|) (the factor 2 covers the rounding of perm) plus k_tiny (1 + ‖y_1‖₁) for
//    underflow (≤ 4·2^-1022 (‖y_1‖₁ + 1)).
//  * k d_i = k (x_i − x0) − Σ_{v=1..3} α_v (x_v − x0) exactly (α the node's multi-index, integer
//    weights); t = fl(k y_i − Σ α_v y_v) is a length-4 dot product of rounded inputs, so
//    |k d_i − t| ≤ (γ4 + u) S ≤ 10u·fl(S) componentwise, S = k|y_i| + Σ α_v |y_v| (products by
//    integers ≤ 4 are exact when subnormal: no underflow term).
//  * everything else is non-negative and rounded outwards with up()/down().
// Result: det J(ξ) ∈ [lower, upper] for every ξ in the tet (±∞ when not finite).
struct AffineBounds {
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
};

// Upper bound of the Euclidean norm of a vector given by non-negative component upper bounds.
inline double norm2_up(double a, double b, double c) {
  return up(std::sqrt(up(up(up(a * a) + up(b * b)) + up(c * c))));
}

template <int K>
AffineBounds affine_bounds(const Prepared& t, const Eigen::Ref<const Eigen::MatrixXd>& nodes) {
  constexpr int N = num_nodes(K);
  AffineBounds out;
  // y[v] = fl(x_v − x0), v = 1..3: the columns of J_a (rounded).
  double y[4][3];
  for (int v = 1; v < 4; ++v)
    for (int r = 0; r < 3; ++r) y[v][r] = nodes(v, r) - nodes(0, r);
  // Deviations.
  double dmax = 0.0;
  for (int i = 4; i < N; ++i) {
    const std::array<int, 4>& a = t.nodes[i];
    double bound[3];
    for (int r = 0; r < 3; ++r) {
      const double yi = nodes(i, r) - nodes(0, r);
      const double tr = K * yi - a[1] * y[1][r] - a[2] * y[2][r] - a[3] * y[3][r];
      const double s = K * std::abs(yi) + a[1] * std::abs(y[1][r]) + a[2] * std::abs(y[2][r]) +
                       a[3] * std::abs(y[3][r]);
      bound[r] = up(up(std::abs(tr) + up(10.0 * k_u * s)) / K);
    }
    dmax = std::max(dmax, norm2_up(bound[0], bound[1], bound[2]));
  }
  // det J_a and its radius; A_c ≥ ‖(x_{c+1} − x0)‖₂ (the factor 1 + 2^-52 ≥ 1 + u covers the
  // rounding of y).
  const double a00 = y[1][0], a10 = y[1][1], a20 = y[1][2];  // column 0
  const double a01 = y[2][0], a11 = y[2][1], a21 = y[2][2];  // column 1
  const double a02 = y[3][0], a12 = y[3][1], a22 = y[3][2];  // column 2
  const double det =
      a00 * (a11 * a22 - a21 * a12) - a10 * (a01 * a22 - a21 * a02) + a20 * (a01 * a12 - a11 * a02);
  using std::abs;
  const double perm = abs(a00) * (abs(a11) * abs(a22) + abs(a21) * abs(a12)) +
                      abs(a10) * (abs(a01) * abs(a22) + abs(a21) * abs(a02)) +
                      abs(a20) * (abs(a01) * abs(a12) + abs(a11) * abs(a02));
  const double col0_l1 = abs(a00) + abs(a10) + abs(a20);
  const double rad = up(up(16.0 * k_u * perm) + k_tiny * (1.0 + col0_l1));
  double A[3], eps[3];
  for (int c = 0; c < 3; ++c) {
    A[c] = up(norm2_up(abs(y[c + 1][0]), abs(y[c + 1][1]), abs(y[c + 1][2])) * (1.0 + 0x1p-52));
    eps[c] = up(t.grad_bound[c] * dmax);
  }
  const double B1 = up(A[1] + eps[1]), B2 = up(A[2] + eps[2]);
  const double delta =
      up(up(eps[0] * up(B1 * B2)) + up(A[0] * up(up(eps[1] * B2) + up(A[1] * eps[2]))));
  const double lower = down(down(det - rad) - delta);
  const double upper = up(up(det + rad) + delta);
  // std::max drops NaN: check dmax too (the caller has already refused non-finite nodes).
  if (std::isfinite(dmax) && std::isfinite(lower) && std::isfinite(upper)) {
    out.lower = lower;
    out.upper = upper;
  }
  return out;
}

template <int K>
JacobianCertificate certify(const Prepared& t, const Eigen::Ref<const Eigen::MatrixXd>& nodes,
                            const CertificateOptions& opts) {
  constexpr int M = num_lattice(K);
  JacobianCertificate out;
  Evaluation<K> ev;
  evaluate_lattice<K>(t, nodes, ev);
  if (!ev.finite) return out;
  const double den3 = t.den3;
  double est = std::numeric_limits<double>::infinity();
  double lat_lo = std::numeric_limits<double>::infinity();
  double lat_hi = std::numeric_limits<double>::infinity();
  for (int j = 0; j < M; ++j) {
    est = std::min(est, ev.vm[j]);
    lat_lo = std::min(lat_lo, down(ev.vm[j] - ev.vr[j]));
    lat_hi = std::min(lat_hi, up(ev.vm[j] + ev.vr[j]));
  }
  out.min_lattice_estimate = est / den3;
  out.min_lattice_lower = down(lat_lo / den3);
  out.min_lattice_upper = up(lat_hi / den3);
  out.min_upper_bound = out.min_lattice_upper;
  if (lat_hi <= 0.0) {
    out.verdict = JacobianVerdict::non_positive;
    out.decided_by = CertificatePath::lattice;
    return out;
  }
  // Affine path: a handful of flops, so computed whenever enabled; its bounds only tighten the
  // proven lower_bound / min_upper_bound, and it decides only what the element's Bernstein
  // coefficients leave open (before any subdivision).
  AffineBounds affine;
  if (opts.affine_path) affine = affine_bounds<K>(t, nodes);
  out.min_upper_bound = std::min(out.min_upper_bound, affine.upper);
  std::array<double, M> b;
  const double r = bernstein<K>(t, ev, b);
  bool bernstein_finite = std::isfinite(r);
  for (int a = 0; a < M; ++a) bernstein_finite = bernstein_finite && std::isfinite(b[a]);
  double lo = -std::numeric_limits<double>::infinity();
  if (bernstein_finite) {
    lo = std::numeric_limits<double>::infinity();
    for (int a = 0; a < M; ++a) lo = std::min(lo, down(b[a] - r));
  }
  if (lo > 0.0) {
    out.verdict = JacobianVerdict::positive;
    out.decided_by = CertificatePath::bernstein;
    out.lower_bound = std::max(down(lo / den3), affine.lower);
    return out;
  }
  if (affine.lower > 0.0) {
    out.verdict = JacobianVerdict::positive;
    out.decided_by = CertificatePath::affine;
    out.lower_bound = affine.lower;
    return out;
  }
  if (affine.upper <= 0.0) {  // det J ≤ upper ≤ 0 on the whole tet
    out.verdict = JacobianVerdict::non_positive;
    out.decided_by = CertificatePath::affine;
    return out;
  }
  if (!bernstein_finite) return out;
  if (t.degree == 0) return out;  // constant det J: subdivision cannot help
  Refiner<K> refiner(t, opts, out);
  out.verdict = refiner.refine(b.data(), r, 0);
  if (out.verdict != JacobianVerdict::undecided) out.decided_by = CertificatePath::subdivision;
  if (out.verdict == JacobianVerdict::positive) out.lower_bound = down(refiner.min_lower / den3);
  out.min_upper_bound = std::min(out.min_upper_bound, up(refiner.min_upper / den3));
  return out;
}

// Plain floating-point J at every lattice point (k = 1: one point): out[c][r][j] = J(r, c) at
// lattice point j, accumulated over the nodes i = 1..N-1 in order (d_i · ∂N_i/∂ξ_c, the tables
// divided by D once in prepare()).
template <int K>
void lattice_jacobians(const Prepared& t, const Eigen::Ref<const Eigen::MatrixXd>& nodes,
                       std::array<std::array<std::array<double, num_lattice(K)>, 3>, 3>& out) {
  constexpr int N = num_nodes(K), M = num_lattice(K);
  for (auto& c : out)
    for (auto& r : c) r.fill(0.0);
  for (int i = 1; i < N; ++i) {
    const double d[3] = {nodes(i, 0) - nodes(0, 0), nodes(i, 1) - nodes(0, 1),
                         nodes(i, 2) - nodes(0, 2)};
    for (int c = 0; c < 3; ++c) {
      const double* g = t.gs.data() + (static_cast<std::size_t>(c) * N + i) * M;
      for (int r = 0; r < 3; ++r) {
        double* o = out[std::size_t(c)][std::size_t(r)].data();
        const double x = d[r];
        for (int j = 0; j < M; ++j) o[j] += x * g[j];
      }
    }
  }
}

// min over the lattice points and the four corner frames of √2 det J / (product of the frame's
// edge lengths). The frames' edges are J's columns and their differences (J T with T of 0 and ±1
// entries, which is exact), so the six lengths are computed once per point.
// The scaled Jacobian of one lattice point's J: min over the four corner frames.
inline double scaled_jacobian_of(const Eigen::Matrix3d& J) {
  const double sqrt2 = std::sqrt(2.0);
  const double det = J.determinant();
  const Eigen::Vector3d c0 = J.col(0), c1 = J.col(1), c2 = J.col(2);
  const double n0 = c0.norm(), n1 = c1.norm(), n2 = c2.norm();
  const double n10 = Eigen::Vector3d(c1 - c0).norm(), n20 = Eigen::Vector3d(c2 - c0).norm(),
               n21 = Eigen::Vector3d(c2 - c1).norm();
  // Corner 0: (e1, e2, e3); 1: (e2-e1, -e1, e3-e1); 2: (-e2, e1-e2, e3-e2); 3: (e1-e3, -e3,
  // e2-e3) — each with det +1 (corners 1 and 3 with their first two edges swapped).
  const double len[4] = {n0 * n1 * n2, n10 * n0 * n20, n1 * n10 * n21, n20 * n2 * n21};
  const double x = sqrt2 * det;
  const double shortest = std::min(std::min(len[0], len[1]), std::min(len[2], len[3]));
  if (x > 0.0 && shortest > 0.0)  // x / l falls as l grows: one division, the same value
    return x / std::max(std::max(len[0], len[1]), std::max(len[2], len[3]));
  double best = std::numeric_limits<double>::infinity();
  for (const double l : len) best = std::min(best, l > 0.0 ? x / l : 0.0);
  return best;
}

template <int K>
double min_scaled_jacobian_k(const Prepared& t, const Eigen::Ref<const Eigen::MatrixXd>& nodes,
                             int* argmin) {
  constexpr int M = num_lattice(K);
  std::array<std::array<std::array<double, M>, 3>, 3> jac;
  lattice_jacobians<K>(t, nodes, jac);
  double best = std::numeric_limits<double>::infinity();
  int at = 0;
  for (int j = 0; j < M; ++j) {
    Eigen::Matrix3d J;
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) J(r, c) = jac[std::size_t(c)][std::size_t(r)][std::size_t(j)];
    const double v = scaled_jacobian_of(J);
    if (v < best) {
      best = v;
      at = j;
    }
  }
  if (argmin) *argmin = at;
  return best;
}

// The same at lattice point j alone: J summed over the nodes in the order lattice_jacobians
// sums them.
template <int K>
double scaled_jacobian_at_k(const Prepared& t, const Eigen::Ref<const Eigen::MatrixXd>& nodes,
                            int j) {
  constexpr int N = num_nodes(K), M = num_lattice(K);
  Eigen::Matrix3d J = Eigen::Matrix3d::Zero();
  for (int i = 1; i < N; ++i) {
    const double d[3] = {nodes(i, 0) - nodes(0, 0), nodes(i, 1) - nodes(0, 1),
                         nodes(i, 2) - nodes(0, 2)};
    for (int c = 0; c < 3; ++c) {
      const double g = t.gs[(static_cast<std::size_t>(c) * N + i) * M + std::size_t(j)];
      for (int r = 0; r < 3; ++r) J(r, c) += d[r] * g;
    }
  }
  return scaled_jacobian_of(J);
}

// Gradients of the order-k basis at the 56 points of the level-5 lattice (for curved_mips).
struct MipsTable {
  std::vector<Eigen::MatrixXd> grads;  // 56 × (n × 3)
};

MipsTable build_mips(int order) {
  MipsTable mt;
  const Eigen::MatrixXd pts = lagrange_reference_nodes(CellKind::tetrahedron, 5);
  for (int p = 0; p < pts.rows(); ++p) {
    const Eigen::Vector3d xi = pts.row(p).transpose();
    mt.grads.push_back(lagrange_shape_gradients(CellKind::tetrahedron, order, xi));
  }
  return mt;
}

const MipsTable& mips_table(int order) {
  static const std::array<MipsTable, 4> all = {build_mips(1), build_mips(2), build_mips(3),
                                               build_mips(4)};
  return all[order - 1];
}

}  // namespace

const char* to_string(JacobianVerdict verdict) {
  switch (verdict) {
    case JacobianVerdict::positive:
      return "positive";
    case JacobianVerdict::non_positive:
      return "non_positive";
    case JacobianVerdict::undecided:
      return "undecided";
  }
  return "undecided";
}

const char* to_string(CertificatePath path) {
  switch (path) {
    case CertificatePath::none:
      return "none";
    case CertificatePath::lattice:
      return "lattice";
    case CertificatePath::bernstein:
      return "bernstein";
    case CertificatePath::affine:
      return "affine";
    case CertificatePath::subdivision:
      return "subdivision";
  }
  return "none";
}

int jacobian_degree(int order) {
  if (order < 1 || order > 4)
    throw InputError("jacobian_degree: order " + std::to_string(order) + " is outside 1..4");
  return degree_of(order);
}

Eigen::MatrixXi jacobian_lattice(int order) {
  jacobian_degree(order);
  const Prepared& t = tables(order);
  Eigen::MatrixXi out(t.m, 4);
  for (int j = 0; j < t.m; ++j)
    for (int i = 0; i < 4; ++i) out(j, i) = t.lattice[j][i];
  return out;
}

/// f(std::integral_constant<int, K>{}) for the order K in 1..4 (4 for anything above 3: the
/// callers have checked the order).
template <class F>
decltype(auto) with_order(int order, F&& f) {
  switch (order) {
    case 1:
      return f(std::integral_constant<int, 1>{});
    case 2:
      return f(std::integral_constant<int, 2>{});
    case 3:
      return f(std::integral_constant<int, 3>{});
    default:
      return f(std::integral_constant<int, 4>{});
  }
}

JacobianCertificate certify_tet_jacobian(int order, const Eigen::Ref<const Eigen::MatrixXd>& nodes,
                                         const CertificateOptions& opts) {
  check_input(order, nodes);
  NearestRounding rounding;
  const Prepared& t = tables(order);
  return with_order(order, [&](auto k) { return certify<decltype(k)::value>(t, nodes, opts); });
}

Eigen::VectorXd jacobian_bernstein_coefficients(int order,
                                                const Eigen::Ref<const Eigen::MatrixXd>& nodes) {
  check_input(order, nodes);
  NearestRounding rounding;
  const Prepared& t = tables(order);
  auto run = [&](auto k_tag) -> Eigen::VectorXd {
    constexpr int K = decltype(k_tag)::value;
    constexpr int M = num_lattice(K);
    Evaluation<K> ev;
    evaluate_lattice<K>(t, nodes, ev);
    std::array<double, M> b;
    if (!ev.finite)
      b.fill(std::numeric_limits<double>::quiet_NaN());
    else
      bernstein<K>(t, ev, b);
    Eigen::VectorXd out(M);
    for (int a = 0; a < M; ++a) out[a] = b[a] / t.den3;
    return out;
  };
  return with_order(order, run);
}

double min_scaled_jacobian(int order, const Eigen::Ref<const Eigen::MatrixXd>& nodes, int* argmin) {
  check_input(order, nodes);
  const Prepared& t = tables(order);
  return with_order(
      order, [&](auto k) { return min_scaled_jacobian_k<decltype(k)::value>(t, nodes, argmin); });
}

double scaled_jacobian_at(int order, const Eigen::Ref<const Eigen::MatrixXd>& nodes, int point) {
  check_input(order, nodes);
  const Prepared& t = tables(order);
  CF_VERIFY(point >= 0 && point < t.m, "scaled_jacobian_at: no such lattice point");
  return with_order(
      order, [&](auto k) { return scaled_jacobian_at_k<decltype(k)::value>(t, nodes, point); });
}

double curved_mips(int order, const Eigen::Ref<const Eigen::MatrixXd>& nodes) {
  check_input(order, nodes);
  const MipsTable& mt = mips_table(order);
  double sum = 0.0;
  for (const Eigen::MatrixXd& g : mt.grads) {
    // J(r, c) = Σ_i x_i,r ∂N_i/∂ξ_c; ‖J⁻¹‖²_F = ‖adj J‖²_F / det² (curved_mips_term).
    const double term = curved_mips_term(jacobian_at(nodes, g));
    if (term == std::numeric_limits<double>::infinity()) return term;
    sum += term;
  }
  return sum / static_cast<double>(mt.grads.size());
}

const std::vector<Eigen::MatrixXd>& curved_mips_gradients(int order) {
  if (order < 1 || order > 4)
    throw InputError("curved_mips_gradients: order " + std::to_string(order) + " is outside 1..4");
  return mips_table(order).grads;
}

}  // namespace curvefem::meshing::curved
