#include "pipeline/expression_ad.hpp"

#include <muParser.h>

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

}  // namespace

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
  return e;
}

double DualExpression::evaluate(const Eigen::Vector3d& x, const Eigen::Vector3d& n, double t,
                                Eigen::Vector3d* gradient) const {
  const Context c{m_nodes.get(), {x[0], x[1], x[2]}, {n[0], n[1], n[2]}, t};
  const Dual d = eval(c, m_root);
  if (gradient) *gradient = Eigen::Vector3d(d.g[0], d.g[1], d.g[2]);
  return d.v;
}

}  // namespace curvefem::pipeline
