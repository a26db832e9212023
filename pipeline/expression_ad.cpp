#include "pipeline/expression_ad.hpp"

#include <muParser.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace curvefem::pipeline {

enum class Op {
  constant,
  var_x,
  var_y,
  var_z,
  var_t,
  var_nx,
  var_ny,
  var_nz,
  neg,
  add,
  sub,
  mul,
  div,
  pow,
  lt,
  gt,
  le,
  ge,
  eq,
  ne,
  land,
  lor,
  ternary,
  sin,
  cos,
  tan,
  asin,
  acos,
  atan,
  sinh,
  cosh,
  tanh,
  asinh,
  acosh,
  atanh,
  log2,
  log10,
  ln,
  exp,
  sqrt,
  sign,
  rint,
  abs,
  atan2,
  min,  // a binary node; min(a, b, c) is min(min(a, b), c)
  max,
  scale,  // a · constant (avg's 1/n)
};

struct DualExpression::Node {
  Op op = Op::constant;
  int a = -1, b = -1, c = -1;
  double value = 0;  // constant, scale factor
};

namespace {

struct Dual {
  double v, g[3];
};

using Node = DualExpression::Node;

class Parser {
 public:
  explicit Parser(const std::string& text) : s(text) {}
  std::vector<Node> nodes;

  int parse() {
    const int root = ternary();
    skip();
    if (i != s.size()) throw std::runtime_error("trailing text");
    return root;
  }

 private:
  const std::string& s;
  std::size_t i = 0;

  void skip() {
    while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
  }
  bool take(const char* token) {
    skip();
    const std::size_t n = std::strlen(token);
    if (s.compare(i, n, token) != 0) return false;
    i += n;
    return true;
  }
  char peek() {
    skip();
    return i < s.size() ? s[i] : '\0';
  }
  int add_node(Op op, int a = -1, int b = -1, int c = -1, double value = 0) {
    nodes.push_back({op, a, b, c, value});
    return int(nodes.size()) - 1;
  }

  int ternary() {
    const int cond = lor();
    if (!take("?")) return cond;
    const int yes = ternary();
    if (!take(":")) throw std::runtime_error("expected ':'");
    const int no = ternary();
    return add_node(Op::ternary, cond, yes, no);
  }
  int lor() {
    int a = land();
    while (take("||")) a = add_node(Op::lor, a, land());
    return a;
  }
  int land() {
    int a = cmp();
    while (take("&&")) a = add_node(Op::land, a, cmp());
    return a;
  }
  int cmp() {
    int a = sum();
    for (;;) {
      Op op;
      if (take("<="))
        op = Op::le;
      else if (take(">="))
        op = Op::ge;
      else if (take("=="))
        op = Op::eq;
      else if (take("!="))
        op = Op::ne;
      else if (take("<"))
        op = Op::lt;
      else if (take(">"))
        op = Op::gt;
      else
        return a;
      a = add_node(op, a, sum());
    }
  }
  int sum() {
    int a = product();
    for (;;) {
      if (take("+"))
        a = add_node(Op::add, a, product());
      else if (take("-"))
        a = add_node(Op::sub, a, product());
      else
        return a;
    }
  }
  int product() {
    int a = unary();
    for (;;) {
      if (take("*"))
        a = add_node(Op::mul, a, unary());
      else if (take("/"))
        a = add_node(Op::div, a, unary());
      else
        return a;
    }
  }
  // muparser: the sign binds less tightly than ^ (-x^2 = -(x^2)); the exponent may carry one.
  int unary() {
    if (take("-")) return add_node(Op::neg, unary());
    if (take("+")) return unary();
    return power();
  }
  int power() {
    const int base = primary();
    if (!take("^")) return base;
    return add_node(Op::pow, base, unary());
  }
  int primary() {
    const char ch = peek();
    if (ch == '(') {
      ++i;
      const int e = ternary();
      if (!take(")")) throw std::runtime_error("expected ')'");
      return e;
    }
    if (std::isdigit(static_cast<unsigned char>(ch)) || ch == '.') {
      const char* begin = s.c_str() + i;
      char* end = nullptr;
      const double v = std::strtod(begin, &end);
      if (end == begin) throw std::runtime_error("bad number");
      i += std::size_t(end - begin);
      return add_node(Op::constant, -1, -1, -1, v);
    }
    if (std::isalpha(static_cast<unsigned char>(ch)) || ch == '_') {
      const std::size_t start = i;
      while (i < s.size() && (std::isalnum(static_cast<unsigned char>(s[i])) || s[i] == '_')) ++i;
      const std::string name = s.substr(start, i - start);
      if (peek() == '(') return call(name);
      static const struct {
        const char* name;
        Op op;
      } vars[] = {{"x", Op::var_x},   {"y", Op::var_y},   {"z", Op::var_z},  {"t", Op::var_t},
                  {"nx", Op::var_nx}, {"ny", Op::var_ny}, {"nz", Op::var_nz}};
      for (const auto& v : vars)
        if (name == v.name) return add_node(v.op);
      // pi is the case files' own constant (Expression defines it); the others are muparser's
      // built-in ones, with its values (its _pi is 3.141592653589).
      if (name == "pi") return add_node(Op::constant, -1, -1, -1, M_PI);
      static const mu::valmap_type builtin = mu::Parser().GetConst();
      if (const auto it = builtin.find(name); it != builtin.end())
        return add_node(Op::constant, -1, -1, -1, it->second);
      throw std::runtime_error("unknown name " + name);
    }
    throw std::runtime_error("unexpected character");
  }
  int call(const std::string& name) {
    take("(");
    std::vector<int> args{ternary()};
    while (take(",")) args.push_back(ternary());
    if (!take(")")) throw std::runtime_error("expected ')'");
    static const struct {
      const char* name;
      Op op;
    } unary_functions[] = {{"sin", Op::sin},     {"cos", Op::cos},     {"tan", Op::tan},
                           {"asin", Op::asin},   {"acos", Op::acos},   {"atan", Op::atan},
                           {"sinh", Op::sinh},   {"cosh", Op::cosh},   {"tanh", Op::tanh},
                           {"asinh", Op::asinh}, {"acosh", Op::acosh}, {"atanh", Op::atanh},
                           {"log2", Op::log2},   {"log10", Op::log10}, {"log", Op::ln},
                           {"ln", Op::ln},       {"exp", Op::exp},     {"sqrt", Op::sqrt},
                           {"sign", Op::sign},   {"rint", Op::rint},   {"abs", Op::abs}};
    for (const auto& f : unary_functions)
      if (name == f.name) {
        if (args.size() != 1) throw std::runtime_error(name + " takes one argument");
        return add_node(f.op, args[0]);
      }
    if (name == "atan2") {
      if (args.size() != 2) throw std::runtime_error("atan2 takes two arguments");
      return add_node(Op::atan2, args[0], args[1]);
    }
    if (name == "min" || name == "max" || name == "sum" || name == "avg") {
      const Op op = name == "min" ? Op::min : name == "max" ? Op::max : Op::add;
      int a = args[0];
      for (std::size_t k = 1; k < args.size(); ++k) a = add_node(op, a, args[k]);
      if (name == "avg") a = add_node(Op::scale, a, -1, -1, 1.0 / double(args.size()));
      return a;
    }
    throw std::runtime_error("unknown function " + name);
  }
};

struct Context {
  const Node* nodes;
  double x[3], n[3], t;
};

inline Dual constant(double v) { return {v, {0, 0, 0}}; }
// f(a) with f'(a) = d.
inline Dual chain(const Dual& a, double v, double d) {
  return {v, {d * a.g[0], d * a.g[1], d * a.g[2]}};
}

Dual eval(const Context& c, int k) {
  const Node& nd = c.nodes[k];
  switch (nd.op) {
    case Op::constant:
      return constant(nd.value);
    case Op::var_x:
      return {c.x[0], {1, 0, 0}};
    case Op::var_y:
      return {c.x[1], {0, 1, 0}};
    case Op::var_z:
      return {c.x[2], {0, 0, 1}};
    case Op::var_t:
      return constant(c.t);
    case Op::var_nx:
      return constant(c.n[0]);
    case Op::var_ny:
      return constant(c.n[1]);
    case Op::var_nz:
      return constant(c.n[2]);
    case Op::ternary:
      return eval(c, eval(c, nd.a).v != 0 ? nd.b : nd.c);
    default:
      break;
  }
  const Dual a = eval(c, nd.a);
  switch (nd.op) {
    case Op::neg:
      return {-a.v, {-a.g[0], -a.g[1], -a.g[2]}};
    case Op::scale:
      return chain(a, nd.value * a.v, nd.value);
    case Op::sin:
      return chain(a, std::sin(a.v), std::cos(a.v));
    case Op::cos:
      return chain(a, std::cos(a.v), -std::sin(a.v));
    case Op::tan: {
      const double v = std::tan(a.v);
      return chain(a, v, 1 + v * v);
    }
    case Op::asin:
      return chain(a, std::asin(a.v), 1 / std::sqrt(1 - a.v * a.v));
    case Op::acos:
      return chain(a, std::acos(a.v), -1 / std::sqrt(1 - a.v * a.v));
    case Op::atan:
      return chain(a, std::atan(a.v), 1 / (1 + a.v * a.v));
    case Op::sinh:
      return chain(a, std::sinh(a.v), std::cosh(a.v));
    case Op::cosh:
      return chain(a, std::cosh(a.v), std::sinh(a.v));
    case Op::tanh: {
      const double v = std::tanh(a.v);
      return chain(a, v, 1 - v * v);
    }
    case Op::asinh:
      return chain(a, std::asinh(a.v), 1 / std::sqrt(a.v * a.v + 1));
    case Op::acosh:
      return chain(a, std::acosh(a.v), 1 / std::sqrt(a.v * a.v - 1));
    case Op::atanh:
      return chain(a, std::atanh(a.v), 1 / (1 - a.v * a.v));
    case Op::log2:
      return chain(a, std::log2(a.v), 1 / (a.v * M_LN2));
    case Op::log10:
      return chain(a, std::log10(a.v), 1 / (a.v * M_LN10));
    case Op::ln:
      return chain(a, std::log(a.v), 1 / a.v);
    case Op::exp: {
      const double v = std::exp(a.v);
      return chain(a, v, v);
    }
    case Op::sqrt: {
      const double v = std::sqrt(a.v);
      return chain(a, v, 0.5 / v);
    }
    case Op::sign:
      return constant(a.v > 0 ? 1.0 : a.v < 0 ? -1.0 : 0.0);
    case Op::rint:
      return constant(std::rint(a.v));
    case Op::abs:
      return chain(a, std::fabs(a.v), a.v < 0 ? -1.0 : 1.0);
    default:
      break;
  }
  const Dual b = eval(c, nd.b);
  switch (nd.op) {
    case Op::add:
      return {a.v + b.v, {a.g[0] + b.g[0], a.g[1] + b.g[1], a.g[2] + b.g[2]}};
    case Op::sub:
      return {a.v - b.v, {a.g[0] - b.g[0], a.g[1] - b.g[1], a.g[2] - b.g[2]}};
    case Op::mul:
      return {
          a.v * b.v,
          {a.g[0] * b.v + a.v * b.g[0], a.g[1] * b.v + a.v * b.g[1], a.g[2] * b.v + a.v * b.g[2]}};
    case Op::div: {
      const double v = a.v / b.v;
      return {
          v,
          {(a.g[0] - v * b.g[0]) / b.v, (a.g[1] - v * b.g[1]) / b.v, (a.g[2] - v * b.g[2]) / b.v}};
    }
    case Op::pow: {
      const double v = std::pow(a.v, b.v);
      // d(a^b) = b a^(b-1) da + a^b ln(a) db; the second term only where b varies (so a
      // constant exponent of a negative base stays finite).
      const double da = b.v == 0 ? 0.0 : b.v * std::pow(a.v, b.v - 1);
      const bool b_varies = b.g[0] != 0 || b.g[1] != 0 || b.g[2] != 0;
      const double db = b_varies ? v * std::log(a.v) : 0.0;
      return {v, {da * a.g[0] + db * b.g[0], da * a.g[1] + db * b.g[1], da * a.g[2] + db * b.g[2]}};
    }
    case Op::atan2: {
      // d atan2(a, b) = (b da − a db) / (a² + b²)
      const double r = a.v * a.v + b.v * b.v;
      return {std::atan2(a.v, b.v),
              {(b.v * a.g[0] - a.v * b.g[0]) / r, (b.v * a.g[1] - a.v * b.g[1]) / r,
               (b.v * a.g[2] - a.v * b.g[2]) / r}};
    }
    case Op::min:
      return a.v <= b.v ? a : b;
    case Op::max:
      return a.v >= b.v ? a : b;
    case Op::lt:
      return constant(a.v < b.v);
    case Op::gt:
      return constant(a.v > b.v);
    case Op::le:
      return constant(a.v <= b.v);
    case Op::ge:
      return constant(a.v >= b.v);
    case Op::eq:
      return constant(a.v == b.v);
    case Op::ne:
      return constant(a.v != b.v);
    case Op::land:
      return constant(a.v != 0 && b.v != 0);
    case Op::lor:
      return constant(a.v != 0 || b.v != 0);
    default:
      return constant(std::nan(""));
  }
}

// ---- batched evaluation --------------------------------------------------------------------
// Each node of the tape owns four lanes of kBlock doubles (value, ∂x, ∂y, ∂z) in a per-thread
// scratch; the nodes are evaluated children first, each as a loop over the block.

constexpr int kBlock = 64;

struct Lanes {
  double* v;
  double* g[3];
};

struct BatchInput {
  const double *x, *y, *z, *nx, *ny, *nz;
  double t;
};

inline Lanes lanes(double* scratch, int k) {
  double* base = scratch + std::size_t(k) * 4 * kBlock;
  return {base, {base + kBlock, base + 2 * kBlock, base + 3 * kBlock}};
}

inline void zero_gradient(const Lanes& r, int m) {
  for (int d = 0; d < 3; ++d) std::fill(r.g[d], r.g[d] + m, 0.0);
}

// r = f(a) with f' = d: f fills the value and the derivative of one point.
template <class F>
inline void unary(const Lanes& a, const Lanes& r, int m, bool grad, F f) {
  double d[kBlock];
  for (int i = 0; i < m; ++i) r.v[i] = f(a.v[i], d[i]);
  if (grad)
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < m; ++i) r.g[k][i] = d[i] * a.g[k][i];
}

// r = 0/1 from a predicate of the two values (no derivative).
template <class F>
inline void predicate(const Lanes& a, const Lanes& b, const Lanes& r, int m, bool grad, F f) {
  for (int i = 0; i < m; ++i) r.v[i] = f(a.v[i], b.v[i]) ? 1.0 : 0.0;
  if (grad) zero_gradient(r, m);
}

// r = a where pick[i], else b (values and gradients).
inline void select(const bool* pick, const Lanes& a, const Lanes& b, const Lanes& r, int m,
                   bool grad) {
  for (int i = 0; i < m; ++i) r.v[i] = pick[i] ? a.v[i] : b.v[i];
  if (grad)
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < m; ++i) r.g[k][i] = pick[i] ? a.g[k][i] : b.g[k][i];
}

void eval_node(const Node& nd, int k, double* scratch, const BatchInput& in, int m, bool grad) {
  const Lanes r = lanes(scratch, k);
  auto variable = [&](const double* src, double fill, int axis) {
    for (int i = 0; i < m; ++i) r.v[i] = src ? src[i] : fill;
    if (grad) {
      zero_gradient(r, m);
      if (axis >= 0) std::fill(r.g[axis], r.g[axis] + m, 1.0);
    }
  };
  switch (nd.op) {
    case Op::constant:
      return variable(nullptr, nd.value, -1);
    case Op::var_x:
      return variable(in.x, 0.0, 0);
    case Op::var_y:
      return variable(in.y, 0.0, 1);
    case Op::var_z:
      return variable(in.z, 0.0, 2);
    case Op::var_t:
      return variable(nullptr, in.t, -1);
    case Op::var_nx:
      return variable(in.nx, 0.0, -1);
    case Op::var_ny:
      return variable(in.ny, 0.0, -1);
    case Op::var_nz:
      return variable(in.nz, 0.0, -1);
    case Op::ternary: {
      const Lanes cond = lanes(scratch, nd.a);
      bool pick[kBlock];
      for (int i = 0; i < m; ++i) pick[i] = cond.v[i] != 0;
      return select(pick, lanes(scratch, nd.b), lanes(scratch, nd.c), r, m, grad);
    }
    default:
      break;
  }
  const Lanes a = lanes(scratch, nd.a);
  switch (nd.op) {
    case Op::neg:
      return unary(a, r, m, grad, [](double v, double& d) {
        d = -1.0;
        return -v;
      });
    case Op::scale:
      return unary(a, r, m, grad, [s = nd.value](double v, double& d) {
        d = s;
        return s * v;
      });
    case Op::sin:
    case Op::cos: {
      double sn[kBlock], cs[kBlock];
      sincos_batch(m, a.v, sn, cs);
      const bool is_sin = nd.op == Op::sin;
      for (int i = 0; i < m; ++i) r.v[i] = is_sin ? sn[i] : cs[i];
      if (grad)
        for (int k = 0; k < 3; ++k)
          for (int i = 0; i < m; ++i) r.g[k][i] = (is_sin ? cs[i] : -sn[i]) * a.g[k][i];
      return;
    }
    case Op::tan:
      return unary(a, r, m, grad, [](double v, double& d) {
        const double w = std::tan(v);
        d = 1 + w * w;
        return w;
      });
    case Op::asin:
      return unary(a, r, m, grad, [](double v, double& d) {
        d = 1 / std::sqrt(1 - v * v);
        return std::asin(v);
      });
    case Op::acos:
      return unary(a, r, m, grad, [](double v, double& d) {
        d = -1 / std::sqrt(1 - v * v);
        return std::acos(v);
      });
    case Op::atan:
      return unary(a, r, m, grad, [](double v, double& d) {
        d = 1 / (1 + v * v);
        return std::atan(v);
      });
    case Op::sinh:
      return unary(a, r, m, grad, [](double v, double& d) {
        d = std::cosh(v);
        return std::sinh(v);
      });
    case Op::cosh:
      return unary(a, r, m, grad, [](double v, double& d) {
        d = std::sinh(v);
        return std::cosh(v);
      });
    case Op::tanh:
      return unary(a, r, m, grad, [](double v, double& d) {
        const double w = std::tanh(v);
        d = 1 - w * w;
        return w;
      });
    case Op::asinh:
      return unary(a, r, m, grad, [](double v, double& d) {
        d = 1 / std::sqrt(v * v + 1);
        return std::asinh(v);
      });
    case Op::acosh:
      return unary(a, r, m, grad, [](double v, double& d) {
        d = 1 / std::sqrt(v * v - 1);
        return std::acosh(v);
      });
    case Op::atanh:
      return unary(a, r, m, grad, [](double v, double& d) {
        d = 1 / (1 - v * v);
        return std::atanh(v);
      });
    case Op::log2:
      return unary(a, r, m, grad, [](double v, double& d) {
        d = 1 / (v * M_LN2);
        return std::log2(v);
      });
    case Op::log10:
      return unary(a, r, m, grad, [](double v, double& d) {
        d = 1 / (v * M_LN10);
        return std::log10(v);
      });
    case Op::ln:
      return unary(a, r, m, grad, [](double v, double& d) {
        d = 1 / v;
        return std::log(v);
      });
    case Op::exp:
      return unary(a, r, m, grad, [](double v, double& d) {
        d = std::exp(v);
        return d;
      });
    case Op::sqrt:
      return unary(a, r, m, grad, [](double v, double& d) {
        const double w = std::sqrt(v);
        d = 0.5 / w;
        return w;
      });
    case Op::sign:
      return unary(a, r, m, grad, [](double v, double& d) {
        d = 0.0;
        return v > 0 ? 1.0 : v < 0 ? -1.0 : 0.0;
      });
    case Op::rint:
      return unary(a, r, m, grad, [](double v, double& d) {
        d = 0.0;
        return std::rint(v);
      });
    case Op::abs:
      return unary(a, r, m, grad, [](double v, double& d) {
        d = v < 0 ? -1.0 : 1.0;
        return std::fabs(v);
      });
    default:
      break;
  }
  const Lanes b = lanes(scratch, nd.b);
  switch (nd.op) {
    case Op::add:
      for (int i = 0; i < m; ++i) r.v[i] = a.v[i] + b.v[i];
      if (grad)
        for (int k = 0; k < 3; ++k)
          for (int i = 0; i < m; ++i) r.g[k][i] = a.g[k][i] + b.g[k][i];
      return;
    case Op::sub:
      for (int i = 0; i < m; ++i) r.v[i] = a.v[i] - b.v[i];
      if (grad)
        for (int k = 0; k < 3; ++k)
          for (int i = 0; i < m; ++i) r.g[k][i] = a.g[k][i] - b.g[k][i];
      return;
    case Op::mul:
      if (grad)
        for (int k = 0; k < 3; ++k)
          for (int i = 0; i < m; ++i) r.g[k][i] = a.g[k][i] * b.v[i] + a.v[i] * b.g[k][i];
      for (int i = 0; i < m; ++i) r.v[i] = a.v[i] * b.v[i];
      return;
    case Op::div:
      for (int i = 0; i < m; ++i) r.v[i] = a.v[i] / b.v[i];
      if (grad)
        for (int k = 0; k < 3; ++k)
          for (int i = 0; i < m; ++i) r.g[k][i] = (a.g[k][i] - r.v[i] * b.g[k][i]) / b.v[i];
      return;
    case Op::pow:
      for (int i = 0; i < m; ++i) {
        const double v = std::pow(a.v[i], b.v[i]);
        r.v[i] = v;
        if (!grad) continue;
        // As the scalar code: the ln(a) term only where the exponent varies.
        const double da = b.v[i] == 0 ? 0.0 : b.v[i] * std::pow(a.v[i], b.v[i] - 1);
        const bool b_varies = b.g[0][i] != 0 || b.g[1][i] != 0 || b.g[2][i] != 0;
        const double db = b_varies ? v * std::log(a.v[i]) : 0.0;
        for (int k = 0; k < 3; ++k) r.g[k][i] = da * a.g[k][i] + db * b.g[k][i];
      }
      return;
    case Op::atan2:
      for (int i = 0; i < m; ++i) {
        const double q = a.v[i] * a.v[i] + b.v[i] * b.v[i];
        r.v[i] = std::atan2(a.v[i], b.v[i]);
        if (grad)
          for (int k = 0; k < 3; ++k) r.g[k][i] = (b.v[i] * a.g[k][i] - a.v[i] * b.g[k][i]) / q;
      }
      return;
    case Op::min:
    case Op::max: {
      bool pick[kBlock];
      for (int i = 0; i < m; ++i) pick[i] = nd.op == Op::min ? a.v[i] <= b.v[i] : a.v[i] >= b.v[i];
      return select(pick, a, b, r, m, grad);
    }
    case Op::lt:
      return predicate(a, b, r, m, grad, [](double p, double q) { return p < q; });
    case Op::gt:
      return predicate(a, b, r, m, grad, [](double p, double q) { return p > q; });
    case Op::le:
      return predicate(a, b, r, m, grad, [](double p, double q) { return p <= q; });
    case Op::ge:
      return predicate(a, b, r, m, grad, [](double p, double q) { return p >= q; });
    case Op::eq:
      return predicate(a, b, r, m, grad, [](double p, double q) { return p == q; });
    case Op::ne:
      return predicate(a, b, r, m, grad, [](double p, double q) { return p != q; });
    case Op::land:
      return predicate(a, b, r, m, grad, [](double p, double q) { return p != 0 && q != 0; });
    case Op::lor:
      return predicate(a, b, r, m, grad, [](double p, double q) { return p != 0 || q != 0; });
    default:
      for (int i = 0; i < m; ++i) r.v[i] = std::nan("");
      if (grad) zero_gradient(r, m);
      return;
  }
}

}  // namespace

// ---- sin and cos over a batch ---------------------------------------------------------------

void sincos_batch(int count, const double* x, double* sin_out, double* cos_out) {
  constexpr double two_over_pi = 0x1.45f306dc9c883p-1;
  // π/2 = c1 + c2 + c3 (+ 2^-122 relative): c1 and c2 have 33 significant bits, so q·c1 and q·c2
  // are exact for |q| < 2^20.
  constexpr double c1 = 0x1.921fb544p+0, c2 = 0x1.0b4611a6p-34, c3 = 0x1.3198a2e037073p-69;
  constexpr double round_magic = 0x1.8p52;  // (v + magic) − magic rounds v to an integer
  constexpr double limit = 1e5;
  constexpr int block = 64;
  double s[block], c[block];
  for (int start = 0; start < count; start += block) {
    const int m = std::min(block, count - start);
    const double* xs = x + start;
    // Points outside [−limit, limit] (and NaN) are reduced as 0 here and recomputed by the
    // fallback; the main loop has no comparison, so it vectorizes.
    int outside = 0;
    double in_range[block] = {};  // a whole block always: a fixed trip count vectorizes at -O2
    for (int i = 0; i < m; ++i) {
      const bool inside = std::fabs(xs[i]) <= limit;
      outside += !inside;
      in_range[i] = inside ? xs[i] : 0.0;
    }
    for (int i = 0; i < block; ++i) {
      const double w = in_range[i];
      const double q = (w * two_over_pi + round_magic) - round_magic;
      const double r = ((w - q * c1) - q * c2) - q * c3;
      const double r2 = r * r;
      // sin r = r − r³/3! + … − r^19/19! ; cos r = 1 − r²/2! + … + r^18/18!, by Horner in r².
      const double sp = 1.0 / 6227020800.0 -
                        r2 * (1.0 / 1307674368000.0 -
                              r2 * (1.0 / 355687428096000.0 - r2 * (1.0 / 121645100408832000.0)));
      const double sn =
          r - r * r2 *
                  (1.0 / 6 -
                   r2 * (1.0 / 120 - r2 * (1.0 / 5040 -
                                           r2 * (1.0 / 362880 - r2 * (1.0 / 39916800 - r2 * sp)))));
      const double cp = 1.0 / 479001600.0 -
                        r2 * (1.0 / 87178291200.0 -
                              r2 * (1.0 / 20922789888000.0 - r2 * (1.0 / 6402373705728000.0)));
      const double cs =
          1.0 -
          r2 * (0.5 - r2 * (1.0 / 24 - r2 * (1.0 / 720 -
                                             r2 * (1.0 / 40320 - r2 * (1.0 / 3628800 - r2 * cp)))));
      // Quadrant q mod 4 by exact arithmetic selects (products with 0 and ±1), which vectorize.
      const int qi = static_cast<int>(q);
      const double odd = qi & 1, sin_sign = 1 - (qi & 2), cos_sign = 1 - ((qi + 1) & 2);
      s[i] = sin_sign * (sn * (1 - odd) + cs * odd);
      c[i] = cos_sign * (cs * (1 - odd) + sn * odd);
    }
    if (outside > 0)
      for (int i = 0; i < m; ++i)
        if (!(std::fabs(xs[i]) <= limit)) ::sincos(xs[i], &s[i], &c[i]);
    if (sin_out) std::copy(s, s + m, sin_out + start);
    if (cos_out) std::copy(c, c + m, cos_out + start);
  }
}

DualExpression::DualExpression() = default;
DualExpression::~DualExpression() = default;

std::unique_ptr<const DualExpression> DualExpression::compile(const std::string& text) {
  Parser p(text);
  int root = -1;
  try {
    root = p.parse();
  } catch (const std::exception&) {
    return nullptr;
  }
  std::unique_ptr<DualExpression> e(new DualExpression());
  e->m_size = int(p.nodes.size());
  e->m_nodes = std::make_unique<Node[]>(std::size_t(e->m_size));
  for (int k = 0; k < e->m_size; ++k) e->m_nodes[k] = p.nodes[std::size_t(k)];
  e->m_root = root;
  // Children before parents (a node's children were parsed, hence appended, before it), and
  // only what the root reaches.
  std::vector<char> reached(std::size_t(e->m_size), 0);
  reached[std::size_t(root)] = 1;
  for (int k = root; k >= 0; --k) {
    if (!reached[std::size_t(k)]) continue;
    for (const int child : {e->m_nodes[k].a, e->m_nodes[k].b, e->m_nodes[k].c})
      if (child >= 0) reached[std::size_t(child)] = 1;
  }
  for (int k = 0; k <= root; ++k)
    if (reached[std::size_t(k)]) e->m_order.push_back(k);
  return e;
}

double DualExpression::evaluate(const Eigen::Vector3d& x, const Eigen::Vector3d& n, double t,
                                Eigen::Vector3d* gradient) const {
  const Context c{m_nodes.get(), {x[0], x[1], x[2]}, {n[0], n[1], n[2]}, t};
  const Dual d = eval(c, m_root);
  if (gradient) *gradient = Eigen::Vector3d(d.g[0], d.g[1], d.g[2]);
  return d.v;
}

void DualExpression::evaluate(int count, const double* x, const double* y, const double* z,
                              const double* nx, const double* ny, const double* nz, double t,
                              double* value, double* gx, double* gy, double* gz) const {
  thread_local std::vector<double> scratch;
  scratch.resize(std::size_t(m_size) * 4 * kBlock);
  const bool grad = gx != nullptr;
  for (int start = 0; start < count; start += kBlock) {
    const int m = std::min(kBlock, count - start);
    auto at = [start](const double* p) { return p ? p + start : nullptr; };
    const BatchInput in{at(x), at(y), at(z), at(nx), at(ny), at(nz), t};
    for (const int k : m_order) eval_node(m_nodes[k], k, scratch.data(), in, m, grad);
    const Lanes r = lanes(scratch.data(), m_root);
    std::copy(r.v, r.v + m, value + start);
    if (grad) {
      std::copy(r.g[0], r.g[0] + m, gx + start);
      std::copy(r.g[1], r.g[1] + m, gy + start);
      std::copy(r.g[2], r.g[2] + m, gz + start);
    }
  }
}

}  // namespace curvefem::pipeline
