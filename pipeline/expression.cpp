#include "pipeline/expression.hpp"

#include <muParser.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <unordered_map>

#include "meshing/core/error.hpp"
#include "pipeline/expression_ad.hpp"

namespace curvefem::pipeline {
namespace {

struct Evaluator {
  mu::Parser parser;
  double x = 0, y = 0, z = 0, t = 0, nx = 0, ny = 0, nz = 0;
  explicit Evaluator(const std::string& text) {
    parser.DefineVar("x", &x);
    parser.DefineVar("y", &y);
    parser.DefineVar("z", &z);
    parser.DefineVar("t", &t);
    parser.DefineVar("nx", &nx);
    parser.DefineVar("ny", &ny);
    parser.DefineVar("nz", &nz);
    parser.DefineConst("pi", 3.14159265358979323846);
    parser.SetExpr(text);
  }
};

std::atomic<long long> g_next_id{0};

Evaluator& evaluator(long long id, const std::string& text) {
  thread_local std::unordered_map<long long, std::unique_ptr<Evaluator>> cache;
  auto& slot = cache[id];
  if (!slot) slot = std::make_unique<Evaluator>(text);
  return *slot;
}

}  // namespace

Expression::Expression(std::string text, std::string where, bool normal_allowed)
    : m_text(std::move(text)) {
  m_id = g_next_id++;
  try {
    Evaluator e(m_text);
    e.x = 0.1, e.y = 0.2, e.z = 0.3, e.nz = 1;
    e.parser.Eval();  // compiles; reports unknown tokens and syntax errors
    for (const auto& [name, ptr] : e.parser.GetUsedVar())
      m_uses_normal |= name == "nx" || name == "ny" || name == "nz";
    if (e.parser.GetUsedVar().empty()) m_constant = e.parser.Eval();
  } catch (const mu::Parser::exception_type& err) {
    throw InputError(where + ": bad expression \"" + m_text + "\": " + err.GetMsg());
  }
  if (auto dual = DualExpression::compile(m_text)) {
    // Used only where it agrees with muparser (values) and with the finite difference
    // (gradients) at fixed points; anything else stays on finite differences.
    static const double points[6][3] = {{0.1, 0.2, 0.3},    {-0.37, 0.81, 0.52}, {1.3, -0.6, 0.25},
                                        {0.77, 0.41, -1.1}, {-0.9, -0.45, -0.2}, {0.05, -1.7, 0.9}};
    const Eigen::Vector3d n = Eigen::Vector3d(1, 2, 3).normalized();
    const double t = 0.37;
    auto same = [](double a, double b, double tol) {
      if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
      return std::fabs(a - b) <= tol * std::max({1.0, std::fabs(a), std::fabs(b)});
    };
    bool agree = true;
    for (const auto& p : points) {
      const Eigen::Vector3d x(p[0], p[1], p[2]);
      Eigen::Vector3d g;
      const double v = dual->evaluate(x, n, t, &g);
      agree = agree && same(v, (*this)(x, n, t), 1e-12);
      if (!agree) break;
      const Eigen::Vector3d fd = difference_gradient(x, n, t);
      for (int d = 0; d < 3 && agree; ++d)
        agree = same(g[d], fd[d], 1e-6) || (std::isnan(fd[d]) && !std::isfinite(v));
    }
    // The batched evaluation (one call over the six points) against the point-wise one.
    if (agree) {
      double xs[3][6], v[6], g[3][6];
      for (int i = 0; i < 6; ++i)
        for (int d = 0; d < 3; ++d) xs[d][i] = points[i][d];
      const double ns[3][6] = {{n[0], n[0], n[0], n[0], n[0], n[0]},
                               {n[1], n[1], n[1], n[1], n[1], n[1]},
                               {n[2], n[2], n[2], n[2], n[2], n[2]}};
      dual->evaluate(6, xs[0], xs[1], xs[2], ns[0], ns[1], ns[2], t, v, g[0], g[1], g[2]);
      for (int i = 0; i < 6 && agree; ++i) {
        Eigen::Vector3d gi;
        const double vi = dual->evaluate(Eigen::Vector3d(xs[0][i], xs[1][i], xs[2][i]), n, t, &gi);
        agree = same(v[i], vi, 1e-14);
        for (int d = 0; d < 3 && agree; ++d) agree = same(g[d][i], gi[d], 1e-14);
      }
    }
    if (agree) m_dual = std::move(dual);
  }
  if (m_uses_normal && !normal_allowed)
    throw InputError(where + ": \"" + m_text +
                     "\" uses nx, ny or nz (the outward normal), which only Neumann values "
                     "have");
}

double Expression::operator()(const Eigen::Vector3d& p, double t) const {
  return (*this)(p, Eigen::Vector3d::Zero(), t);
}

double Expression::operator()(const Eigen::Vector3d& p, const Eigen::Vector3d& n, double t) const {
  Evaluator& e = evaluator(m_id, m_text);
  e.x = p[0], e.y = p[1], e.z = p[2], e.t = t;
  e.nx = n[0], e.ny = n[1], e.nz = n[2];
  return e.parser.Eval();
}

Eigen::Vector3d Expression::gradient(const Eigen::Vector3d& x, double h) const {
  if (!m_dual) return difference_gradient(x, h);
  Eigen::Vector3d g;
  m_dual->evaluate(x, Eigen::Vector3d::Zero(), 0.0, &g);
  return g;
}

double Expression::value_and_gradient(const Eigen::Vector3d& x, Eigen::Vector3d* gradient) const {
  if (!m_dual) {
    *gradient = difference_gradient(x);
    return (*this)(x);
  }
  return m_dual->evaluate(x, Eigen::Vector3d::Zero(), 0.0, gradient);
}

void Expression::values_and_gradients(int count, const double* x, const double* y, const double* z,
                                      double* value, double* gx, double* gy, double* gz) const {
  if (m_dual) {
    m_dual->evaluate(count, x, y, z, nullptr, nullptr, nullptr, 0.0, value, gx, gy, gz);
    return;
  }
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d p(x[i], y[i], z[i]);
    value[i] = (*this)(p);
    if (!gx) continue;
    const Eigen::Vector3d g = difference_gradient(p);
    gx[i] = g[0], gy[i] = g[1], gz[i] = g[2];
  }
}

Eigen::Vector3d Expression::difference_gradient(const Eigen::Vector3d& x, double h) const {
  return difference_gradient(x, Eigen::Vector3d::Zero(), 0.0, h);
}

Eigen::Vector3d Expression::difference_gradient(const Eigen::Vector3d& x, const Eigen::Vector3d& n,
                                                double t, double h) const {
  Eigen::Vector3d g;
  for (int d = 0; d < 3; ++d) {
    Eigen::Vector3d e = Eigen::Vector3d::Zero();
    e[d] = h;
    g[d] = (-(*this)(x + 2 * e, n, t) + 8 * (*this)(x + e, n, t) - 8 * (*this)(x - e, n, t) +
            (*this)(x - 2 * e, n, t)) /
           (12 * h);
  }
  return g;
}

}  // namespace curvefem::pipeline
