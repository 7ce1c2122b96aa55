// Host sets: forwarding to the runtime's sets, with runtime faults reported as simit::Error.
#include "simit/set.h"

#include <ostream>
#include <utility>

#include "api/set_access.h"
#include "runtime/fault.h"

namespace simit {

namespace {

// Runs f, turning a runtime Fault into the API's Error.
template <class F>
auto guarded(F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const runtime::Fault& e) {
    throw Error(e.what());
  }
}

std::vector<const runtime::Set*> runtime_sets(const std::vector<Set*>& sets) {
  std::vector<const runtime::Set*> out;
  for (Set* s : sets) {
    if (!s) throw Error("an endpoint set is null");
    out.push_back(&api::SetAccess::of(*s));
  }
  return out;
}

}  // namespace

namespace api {

runtime::ComponentKind runtime_kind(ComponentKind kind) {
  switch (kind) {
    case ComponentKind::Int: return runtime::ComponentKind::Int;
    case ComponentKind::Float: return runtime::ComponentKind::Float;
    case ComponentKind::Bool: return runtime::ComponentKind::Bool;
    case ComponentKind::Complex: return runtime::ComponentKind::Complex;
  }
  return runtime::ComponentKind::Float;
}

ComponentKind host_kind(runtime::ComponentKind kind) {
  switch (kind) {
    case runtime::ComponentKind::Int: return ComponentKind::Int;
    case runtime::ComponentKind::Bool: return ComponentKind::Bool;
    case runtime::ComponentKind::Complex: return ComponentKind::Complex;
    default: return ComponentKind::Float;
  }
}

runtime::FieldType runtime_field_type(const FieldType& type) {
  return runtime::FieldType{runtime_kind(type.kind), type.dims, type.single};
}

}  // namespace api

namespace detail {

const std::string& field_name(const Set& set, int field) {
  return api::SetAccess::of(set).field(field).name();
}

// Non-const access: a write through the pointer must not reach storage shared with a copy.
void* field_data(const Set& set, int field) {
  return api::SetAccess::mutable_of(set).field(field).bytes();
}

void* field_element(const Set& set, int field, ElementRef e) {
  const runtime::Set& s = api::SetAccess::of(set);
  if (!e.defined() || e.ident() >= s.size())
    throw Error(s.describe() + " has no element " + std::to_string(e.ident()) + " (field '" +
                field_name(set, field) + "')");
  runtime::Field& f = api::SetAccess::mutable_of(set).field(field);
  return f.bytes() + static_cast<size_t>(e.ident()) * f.element_bytes();
}

}  // namespace detail

Set::Set(std::string name) : impl_(std::make_unique<runtime::Set>(std::move(name))) {}

Set::Set(std::string name, std::vector<Set*> endpoints)
    : impl_(guarded([&] {
        return std::make_unique<runtime::Set>(std::move(name), runtime_sets(endpoints));
      })),
      endpoint_sets_(std::move(endpoints)) {}

Set::Set(std::string name, Set& points, std::vector<int> extents)
    : impl_(guarded([&] {
        return std::make_unique<runtime::Set>(std::move(name), api::SetAccess::of(points),
                                              std::move(extents));
      })),
      endpoint_sets_{&points} {}

Set::~Set() = default;

const std::string& Set::name() const { return impl_->name(); }
int Set::size() const { return impl_->size(); }
int Set::cardinality() const { return impl_->arity(); }
Set::Kind Set::kind() const { return impl_->is_grid() ? Grid : Unstructured; }
bool Set::is_homogeneous() const { return impl_->homogeneous(); }
const int32_t* Set::endpoints_data() const { return impl_->endpoints(); }
bool Set::has_field(const std::string& name) const { return impl_->field_index(name) >= 0; }
const std::vector<int>& Set::grid_extents() const { return impl_->extents(); }

ElementRef Set::add() {
  return guarded([&] { return ElementRef(impl_->add()); });
}

ElementRef Set::add(std::span<const ElementRef> endpoints) {
  std::vector<int32_t> ids;
  for (ElementRef e : endpoints) ids.push_back(e.ident());
  return guarded([&] { return ElementRef(impl_->add(std::span<const int32_t>(ids))); });
}

ElementRange Set::add_many(int count) {
  return guarded([&] { return ElementRange(impl_->add_many(count), count); });
}

void Set::check_element(ElementRef e, const char* what) const {
  if (!e.defined() || e.ident() >= size())
    throw Error(impl_->describe() + " has no " + what + " " + std::to_string(e.ident()));
}

ElementRef Set::endpoint(ElementRef edge, int k) const {
  check_element(edge, "element");
  if (k < 0 || k >= cardinality())
    throw Error(impl_->describe() + " has " + std::to_string(cardinality()) +
                " endpoints per element; there is no endpoint " + std::to_string(k));
  return ElementRef(impl_->endpoint(edge.ident(), k));
}

std::vector<ElementRef> Set::endpoints(ElementRef edge) const {
  std::vector<ElementRef> out;
  for (int k = 0; k < cardinality(); ++k) out.push_back(endpoint(edge, k));
  return out;
}

Set* Set::endpoint_set(int k) const {
  if (k < 0 || k >= static_cast<int>(endpoint_sets_.size()))
    throw Error(impl_->describe() + " has no endpoint set " + std::to_string(k));
  return endpoint_sets_[k];
}

int Set::add_field(const std::string& name, const FieldType& type) {
  return guarded([&] { return impl_->add_field(name, api::runtime_field_type(type)); });
}

int Set::require_field(const std::string& name, const FieldType& type) const {
  return guarded([&] { return impl_->require_field(name, api::runtime_field_type(type)); });
}

void* Set::field_data(const std::string& name) {
  return guarded([&] { return static_cast<void*>(impl_->field(name).bytes()); });
}

void Set::pin_fields() { impl_->pin_fields(); }
bool Set::fields_pinned() const { return impl_->fields_pinned(); }

ElementRef Set::grid_point(std::span<const int> coords) const {
  return guarded([&] { return ElementRef(impl_->grid_point(coords)); });
}

std::vector<int> Set::grid_point_coords(ElementRef point) const {
  return guarded([&] { return impl_->grid_coords(point.ident()); });
}

ElementRef Set::grid_edge(std::span<const int> coords, int axis) const {
  return guarded([&] { return ElementRef(impl_->grid_link(impl_->grid_point(coords), axis)); });
}

std::ostream& operator<<(std::ostream& os, const Set& set) {
  const runtime::Set& s = api::SetAccess::of(set);
  os << s.describe() << ": " << s.size() << " elements";
  if (s.arity() > 0) os << ", " << s.arity() << " endpoints each";
  for (int f = 0; f < s.field_count(); ++f)
    os << (f ? ", " : "; fields ") << s.field(f).name() << " (" << s.field(f).type().str() << ")";
  return os;
}

}  // namespace simit
