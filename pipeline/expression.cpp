#include "pipeline/expression.hpp"

#include <muParser.h>

#include <atomic>
#include <unordered_map>

#include "meshing/core/error.hpp"

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
  } catch (const mu::Parser::exception_type& err) {
    throw InputError(where + ": bad expression \"" + m_text + "\": " + err.GetMsg());
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
  Eigen::Vector3d g;
  for (int d = 0; d < 3; ++d) {
    Eigen::Vector3d e = Eigen::Vector3d::Zero();
    e[d] = h;
    g[d] = (-(*this)(x + 2 * e) + 8 * (*this)(x + e) - 8 * (*this)(x - e) + (*this)(x - 2 * e)) /
           (12 * h);
  }
  return g;
}

}  // namespace curvefem::pipeline
