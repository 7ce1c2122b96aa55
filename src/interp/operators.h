// Arithmetic, comparison and logic on values (LANGUAGE.md §6.4-6.9, §9.4 complex
// arithmetic). Vector orientation is static, so callers pass it from the operand types.
// Run-time conditions (integer division by zero, shapes that differ at run time) throw
// runtime::Fault; the evaluator turns them into located run-time errors.
#pragma once

#include "frontend/ast.h"
#include "interp/value.h"

namespace simit::interp {

// `l op r`; `lrow` / `rrow` say whether an order-1 operand is a row vector. float32: a
// product's sums add in binary32 steps (runtime/sum_rounding.h); the caller rounds the value.
Value binary_op(frontend::ast::Binary::Op op, const Value& l, bool lrow, const Value& r, bool rrow,
                bool float32 = false);
// `-v` (also of tensors); `+v` is the identity and needs no function.
Value negate(const Value& v);
// `v'`: scalars and vectors are unchanged (orientation is a property of the type).
Value transpose_value(const Value& v);
// One link `l op r` of a comparison chain, on scalars of one kind.
bool compare(frontend::ast::Compare::Op op, const Value& l, const Value& r);

// Float post-processing used by the float32 and check-finite options.
void round_to_float32(Value& v);
bool is_finite(const Value& v);

}  // namespace simit::interp
