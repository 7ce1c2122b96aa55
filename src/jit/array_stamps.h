// Stamps naming a map argument's contents for good (MapArgs::array_version_in), for an
// executor that keeps copies of the arrays between calls (the GPU's): a number hashed from
// what decides the contents, with a kind of its own per kind of array; never 0, which means
// unknown. Two contents share a stamp only by a 64-bit hash collision.
#pragma once

#include <cstdint>
#include <initializer_list>

#include "runtime/set.h"
#include "runtime/system_matrix.h"

namespace simit::jit {

enum class StampKind : uint64_t { Field = 1, Endpoints, Pattern, Specialised, Split };

// The stamp of `parts` under `kind`.
uint64_t stamp(StampKind kind, std::initializer_list<uint64_t> parts);

// Field `field` of `set`: the set's process-wide identity, the field's number and its write
// version, which every mutable access counts. 0 when the set's fields are pinned: its host
// holds pointers into them and writes through them without counting (a scene's stepper).
uint64_t field_stamp(const runtime::Set& set, int field);

// The endpoint table of `set`: only ever appended to, which counts in its topology version.
uint64_t endpoints_stamp(const runtime::Set& set);

// A number naming the pattern `p` for good: the same while it lives, never another
// pattern's (its address alone may be a later pattern's once it is freed). A pattern never
// changes its tables, so its number names them too.
uint64_t pattern_number(const runtime::PatternPtr& p);

}  // namespace simit::jit
