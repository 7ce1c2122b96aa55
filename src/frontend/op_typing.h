// Typing rules of operators and intrinsics (LANGUAGE.md §6.4-6.9, §9) as pure functions
// of operand types, so the checker's tree walk stays small.
#pragma once

#include <string>
#include <vector>

#include "frontend/ast.h"
#include "frontend/diagnostics.h"
#include "frontend/types.h"

namespace simit::frontend {

// A result type, or an error (kind + message) when the operands are not allowed.
struct Typing {
  TypeRef type;  // null on error
  SemanticKind kind = SemanticKind::None;
  std::string error;
  bool ok() const { return type != nullptr; }
  static Typing success(TypeRef t) { return {std::move(t), SemanticKind::None, {}}; }
  static Typing failure(SemanticKind k, std::string msg) { return {nullptr, k, std::move(msg)}; }
};

// `l op r` for + - * / \ .* ./ ^ and or xor (outside index notation; inside it the
// checker applies the scalar rules of §7.2 itself).
Typing type_binary(ast::Binary::Op op, const Type& l, const Type& r);
// `-x`, `+x`, `not x`.
Typing type_unary(ast::Unary::Op op, const Type& operand);
// `x'`.
Typing type_transpose(const Type& operand);
// One link `l op r` of a comparison chain (the result of the whole chain is bool).
Typing type_compare(ast::Compare::Op op, const Type& l, const Type& r);

// A call of an intrinsic with already-typed arguments. `explicit_generics` are the
// resolved explicit generic arguments (`lusolve<nodes,nodes>`); `bindings` receives one
// IndexSet per generic parameter of the intrinsic (empty for non-generic ones).
Typing type_intrinsic_call(Intrinsic id, const std::vector<const Type*>& args,
                           const std::vector<IndexSet>& explicit_generics,
                           std::vector<IndexSet>& bindings);

}  // namespace simit::frontend
