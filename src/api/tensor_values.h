// Conversions between host tensors (TensorSlot) and interpreter values, shared by Function
// and by the tools that bind scene tensors themselves.
#pragma once

#include "frontend/types.h"
#include "interp/value.h"
#include "simit/tensor.h"

namespace simit::api {

// The host tensor's value as an interpreter value of type `t` (already checked to match).
interp::Value to_value(const TensorSlot& s, const frontend::Type& t);
// Writes an interpreter value back into the host tensor it came from.
void from_value(const interp::Value& v, const TensorSlot& s);

}  // namespace simit::api
