// Names of AST node kinds and operators, and small lookups on declarations.
#include "frontend/ast.h"

namespace simit::frontend::ast {

const char* node_kind_name(NodeKind k) {
  switch (k) {
#define SIMIT_NODE_NAME(n) \
  case NodeKind::n: return #n;
    SIMIT_AST_NODES(SIMIT_NODE_NAME)
#undef SIMIT_NODE_NAME
  }
  return "?";
}

const char* binary_op_spelling(Binary::Op op) {
  switch (op) {
    case Binary::Op::Add: return "+";
    case Binary::Op::Sub: return "-";
    case Binary::Op::Mul: return "*";
    case Binary::Op::Div: return "/";
    case Binary::Op::LeftDiv: return "\\";
    case Binary::Op::ElemMul: return ".*";
    case Binary::Op::ElemDiv: return "./";
    case Binary::Op::Pow: return "^";
    case Binary::Op::And: return "and";
    case Binary::Op::Or: return "or";
    case Binary::Op::Xor: return "xor";
  }
  return "?";
}

const char* compare_op_spelling(Compare::Op op) {
  switch (op) {
    case Compare::Op::Eq: return "==";
    case Compare::Op::Ne: return "!=";
    case Compare::Op::Lt: return "<";
    case Compare::Op::Gt: return ">";
    case Compare::Op::Le: return "<=";
    case Compare::Op::Ge: return ">=";
  }
  return "?";
}

int ElementDecl::field_index(const std::string& n) const {
  for (size_t i = 0; i < fields.size(); ++i)
    if (fields[i].name == n) return static_cast<int>(i);
  return -1;
}

const FuncDecl* Program::find_func(const std::string& name) const {
  for (const auto& d : decls)
    if (const auto* f = d->as<FuncDecl>(); f && f->name == name) return f;
  return nullptr;
}

}  // namespace simit::frontend::ast
