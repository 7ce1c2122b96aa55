// The runtime storage inside a simit::Set, for the engine's bindings and the API's own code:
// programs read and write it in place, so it is shared, never copied.
#pragma once

#include "runtime/set.h"
#include "simit/set.h"

namespace simit::api {

struct SetAccess {
  static runtime::Set& of(Set& set) { return *set.impl_; }
  static const runtime::Set& of(const Set& set) { return *set.impl_; }
  // A FieldRef writes through a const handle, as a pointer into the storage would.
  static runtime::Set& mutable_of(const Set& set) { return *set.impl_; }
};

// The runtime's description of a host field type (same kinds, same order of dimensions).
runtime::ComponentKind runtime_kind(ComponentKind kind);
runtime::FieldType runtime_field_type(const FieldType& type);
// The host's name for a runtime component kind (String, which no host binds, as Float).
ComponentKind host_kind(runtime::ComponentKind kind);

}  // namespace simit::api
