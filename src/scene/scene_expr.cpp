// A small recursive-descent parser and tree evaluator for scene expressions.
#include "scene/scene_expr.h"

#include "runtime/math/math_functions.h"  // the functions Simit programs call, bit for bit

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <vector>

namespace simit::scene {

struct PositionExpr::Node {
  // Sum, Product, And and Or hold a whole flat chain (a + b - c is one Sum), so that the
  // tree is only as deep as the expression's nesting.
  enum class Op { Num, Var, Neg, Not, Sum, Product, Pow, Lt, Le, Gt, Ge, Eq, Ne, And, Or, Call };
  Op op = Op::Num;
  double value = 0.0;
  int var = 0;  // Var: 0..2 position, 3..5 lower corner, 6..8 upper corner
  std::string func;
  std::vector<std::unique_ptr<Node>> args;
  std::vector<bool> inverse;  // Sum: subtract args[k]; Product: divide by args[k]
};

namespace {

using Node = PositionExpr::Node;
using Op = Node::Op;
using NodePtr = std::unique_ptr<Node>;

NodePtr make(Op op, std::vector<NodePtr> args = {}) {
  auto n = std::make_unique<Node>();
  n->op = op;
  n->args = std::move(args);
  return n;
}

NodePtr make2(Op op, NodePtr a, NodePtr b) {
  std::vector<NodePtr> args;
  args.push_back(std::move(a));
  args.push_back(std::move(b));
  return make(op, std::move(args));
}

// Appends `b` to the chain `a` of kind `op`, starting the chain when `a` is something else.
NodePtr chain(Op op, NodePtr a, NodePtr b, bool inverse = false) {
  if (a->op != op) {
    NodePtr c = make(op);
    c->args.push_back(std::move(a));
    c->inverse.push_back(false);
    a = std::move(c);
  }
  a->args.push_back(std::move(b));
  a->inverse.push_back(inverse);
  return a;
}

struct FuncInfo {
  const char* name;
  int arity;
};
constexpr FuncInfo kFuncs[] = {{"sqrt", 1}, {"abs", 1}, {"sin", 1}, {"cos", 1},
                               {"tan", 1},  {"exp", 1}, {"log", 1}, {"floor", 1},
                               {"ceil", 1}, {"min", 2}, {"max", 2}};

class Parser {
 public:
  explicit Parser(const std::string& s) : s_(s) {}

  NodePtr parse() {
    if (s_.size() > kMaxExprLength) {
      throw std::invalid_argument("the expression is " + std::to_string(s_.size()) +
                                  " characters long; at most " + std::to_string(kMaxExprLength) +
                                  " are allowed");
    }
    NodePtr n = parse_or();
    skip();
    if (i_ < s_.size()) fail("unexpected '" + std::string(1, s_[i_]) + "'");
    return n;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw std::invalid_argument("column " + std::to_string(i_ + 1) + ": " + what);
  }
  void skip() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  bool accept(const std::string& tok) {
    skip();
    if (s_.compare(i_, tok.size(), tok) != 0) return false;
    // A word must not run on into a longer name ("order" is not "or").
    if (std::isalpha(static_cast<unsigned char>(tok[0])) && i_ + tok.size() < s_.size() &&
        (std::isalnum(static_cast<unsigned char>(s_[i_ + tok.size()])) ||
         s_[i_ + tok.size()] == '_'))
      return false;
    last_ = i_;
    i_ += tok.size();
    return true;
  }
  // Counts one level of nesting (parentheses, a call, a prefix operator, `^`) for the
  // duration of a scope; the error names the column of the operator at offset `at`.
  class Nest {
   public:
    Nest(Parser& p, size_t at) : p_(p) {
      if (++p_.depth_ <= kMaxExprDepth) return;
      p_.i_ = at;
      p_.fail("the expression is nested more than " + std::to_string(kMaxExprDepth) +
              " levels deep");
    }
    ~Nest() { --p_.depth_; }
    Nest(const Nest&) = delete;
    Nest& operator=(const Nest&) = delete;

   private:
    Parser& p_;
  };

  NodePtr parse_or() {
    NodePtr a = parse_and();
    while (accept("||") || accept("or")) a = chain(Op::Or, std::move(a), parse_and());
    return a;
  }
  NodePtr parse_and() {
    NodePtr a = parse_not();
    while (accept("&&") || accept("and")) a = chain(Op::And, std::move(a), parse_not());
    return a;
  }
  NodePtr parse_not() {
    skip();
    if (i_ + 1 < s_.size() && s_[i_] == '!' && s_[i_ + 1] == '=') return parse_cmp();
    if (accept("!") || accept("not")) {
      Nest nest(*this, last_);
      std::vector<NodePtr> args;
      args.push_back(parse_not());
      return make(Op::Not, std::move(args));
    }
    return parse_cmp();
  }
  NodePtr parse_cmp() {
    NodePtr a = parse_add();
    static const std::pair<const char*, Op> ops[] = {{"<=", Op::Le}, {">=", Op::Ge}, {"==", Op::Eq},
                                                     {"!=", Op::Ne}, {"<", Op::Lt},  {">", Op::Gt}};
    for (const auto& [tok, op] : ops)
      if (accept(tok)) return make2(op, std::move(a), parse_add());
    return a;
  }
  NodePtr parse_add() {
    NodePtr a = parse_mul();
    for (;;) {
      if (accept("+"))
        a = chain(Op::Sum, std::move(a), parse_mul());
      else if (accept("-"))
        a = chain(Op::Sum, std::move(a), parse_mul(), true);
      else
        return a;
    }
  }
  NodePtr parse_mul() {
    NodePtr a = parse_unary();
    for (;;) {
      if (accept("*"))
        a = chain(Op::Product, std::move(a), parse_unary());
      else if (accept("/"))
        a = chain(Op::Product, std::move(a), parse_unary(), true);
      else
        return a;
    }
  }
  NodePtr parse_unary() {
    if (accept("-")) {
      Nest nest(*this, last_);
      std::vector<NodePtr> args;
      args.push_back(parse_unary());
      return make(Op::Neg, std::move(args));
    }
    if (accept("+")) {
      Nest nest(*this, last_);
      return parse_unary();
    }
    NodePtr a = parse_primary();
    if (accept("^")) {
      Nest nest(*this, last_);
      return make2(Op::Pow, std::move(a), parse_unary());
    }
    return a;
  }
  NodePtr parse_primary() {
    skip();
    if (i_ >= s_.size()) fail("expected a number, x, y, z, a function or '('");
    char c = s_[i_];
    if (c == '(') {
      Nest nest(*this, i_);
      ++i_;
      NodePtr n = parse_or();
      if (!accept(")")) fail("expected ')'");
      return n;
    }
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') {
      const char* begin = s_.c_str() + i_;
      char* end = nullptr;
      double v = std::strtod(begin, &end);
      if (end == begin) fail("malformed number");
      i_ += static_cast<size_t>(end - begin);
      NodePtr n = make(Op::Num);
      n->value = v;
      return n;
    }
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
      size_t start = i_;
      while (i_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[i_])) || s_[i_] == '_'))
        ++i_;
      std::string name = s_.substr(start, i_ - start);
      static const char* const vars[] = {"x",    "y",    "z",    "xmin", "ymin",
                                         "zmin", "xmax", "ymax", "zmax"};
      for (int k = 0; k < 9; ++k)
        if (name == vars[k]) {
          NodePtr n = make(Op::Var);
          n->var = k;
          return n;
        }
      if (name == "pi") {
        NodePtr n = make(Op::Num);
        n->value = M_PI;
        return n;
      }
      for (const FuncInfo& f : kFuncs) {
        if (name != f.name) continue;
        if (!accept("(")) fail("expected '(' after '" + name + "'");
        Nest nest(*this, last_);
        NodePtr n = make(Op::Call);
        n->func = name;
        for (int k = 0; k < f.arity; ++k) {
          if (k > 0 && !accept(","))
            fail("'" + name + "' takes " + std::to_string(f.arity) + " arguments");
          n->args.push_back(parse_or());
        }
        if (!accept(")")) fail("expected ')' to close '" + name + "('");
        return n;
      }
      i_ = start;
      fail("unknown name '" + name + "' (the variables are x, y, z, xmin ... zmax)");
    }
    fail("unexpected '" + std::string(1, c) + "'");
  }

  const std::string& s_;
  size_t i_ = 0;
  size_t last_ = 0;  // where the token accept() took last begins
  int depth_ = 0;
};

double eval_node(const Node& n, const double* const v[3]) {
  auto arg = [&](int k) { return eval_node(*n.args[k], v); };
  switch (n.op) {
    case Op::Num: return n.value;
    case Op::Var: return v[n.var / 3][n.var % 3];
    case Op::Neg: return -arg(0);
    case Op::Not: return arg(0) == 0.0 ? 1.0 : 0.0;
    case Op::Sum: {
      double sum = arg(0);
      for (size_t k = 1; k < n.args.size(); ++k)
        sum = n.inverse[k] ? sum - eval_node(*n.args[k], v) : sum + eval_node(*n.args[k], v);
      return sum;
    }
    case Op::Product: {
      double product = arg(0);
      for (size_t k = 1; k < n.args.size(); ++k) {
        double factor = eval_node(*n.args[k], v);
        product = n.inverse[k] ? product / factor : product * factor;
      }
      return product;
    }
    case Op::Pow: return math::pow(arg(0), arg(1));
    case Op::Lt: return arg(0) < arg(1);
    case Op::Le: return arg(0) <= arg(1);
    case Op::Gt: return arg(0) > arg(1);
    case Op::Ge: return arg(0) >= arg(1);
    case Op::Eq: return arg(0) == arg(1);
    case Op::Ne: return arg(0) != arg(1);
    case Op::And:
    case Op::Or: {
      // Every operand is evaluated, as the binary form did.
      bool all = true, any = false;
      for (const auto& a : n.args) {
        bool nonzero = eval_node(*a, v) != 0.0;
        all = all && nonzero;
        any = any || nonzero;
      }
      return (n.op == Op::And ? all : any) ? 1.0 : 0.0;
    }
    case Op::Call: {
      const std::string& f = n.func;
      if (f == "min") return std::min(arg(0), arg(1));
      if (f == "max") return std::max(arg(0), arg(1));
      double a = arg(0);
      if (f == "sqrt") return std::sqrt(a);
      if (f == "abs") return std::fabs(a);
      if (f == "sin") return math::sin(a);
      if (f == "cos") return math::cos(a);
      if (f == "tan") return math::tan(a);
      if (f == "exp") return math::exp(a);
      if (f == "log") return math::log(a);
      if (f == "floor") return std::floor(a);
      return std::ceil(a);
    }
  }
  return 0.0;
}

}  // namespace

PositionExpr::PositionExpr(const std::string& text) : root_(Parser(text).parse()) {}
PositionExpr::~PositionExpr() = default;
PositionExpr::PositionExpr(PositionExpr&&) noexcept = default;
PositionExpr& PositionExpr::operator=(PositionExpr&&) noexcept = default;

double PositionExpr::eval(const double p[3], const double lo[3], const double hi[3]) const {
  const double* const v[3] = {p, lo, hi};
  return eval_node(*root_, v);
}

}  // namespace simit::scene
