// Sets: element storage, struct-of-arrays fields, endpoints and grid lattices.
#include "runtime/set.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <new>

namespace simit::runtime {

namespace {

std::atomic<uint64_t> next_set_id{1};

std::string dims_str(const std::vector<int>& dims) {
  std::string s;
  for (size_t i = 0; i < dims.size(); ++i) s += (i ? "x" : "") + std::to_string(dims[i]);
  return s;
}

std::string tensor_str(const Tensor& t) {
  const Shape& s = t.shape();
  return std::string(component_name(t.kind())) + (s.is_scalar() ? "" : " " + s.str());
}

std::string element_str(const Set& set, int element) {
  return set.describe() + ", element " + std::to_string(element);
}

int wrap(int c, int n) { return ((c % n) + n) % n; }

}  // namespace

// ---------------------------------------------------------------------------
// FieldType and Field

size_t FieldType::components() const {
  size_t n = 1;
  for (int d : dims) n *= static_cast<size_t>(d);
  return n;
}

size_t FieldType::component_bytes() const {
  if (!single) return simit::runtime::component_bytes(kind);
  if (kind == ComponentKind::Float) return sizeof(float);
  if (kind == ComponentKind::Complex) return sizeof(std::complex<float>);
  return simit::runtime::component_bytes(kind);
}

std::string FieldType::str() const {
  std::string s = component_name(kind);
  if (single && (kind == ComponentKind::Float || kind == ComponentKind::Complex)) s += "32";
  return dims.empty() ? s : s + " " + dims_str(dims);
}

void Field::check_storage(Tag requested) const {
  Tag stored = Tag::Other;
  switch (type_.kind) {
    case ComponentKind::Int: stored = Tag::Int; break;
    case ComponentKind::Bool: stored = Tag::Bool; break;
    case ComponentKind::Float: stored = type_.single ? Tag::Single : Tag::Double; break;
    case ComponentKind::Complex:
      stored = type_.single ? Tag::ComplexSingle : Tag::ComplexDouble;
      break;
    case ComponentKind::String: break;
  }
  if (requested != stored || stored == Tag::Other)
    throw Fault("field '" + name_ + "' holds " + type_.str() +
                " components; it was accessed with another component type");
}

void Field::reallocate(size_t capacity) {
  std::shared_ptr<std::byte[]> fresh;
  if (capacity) {
    try {
      fresh = residency::new_host_array(capacity);
    } catch (const std::bad_alloc&) {
      throw Fault("out of memory while allocating " + std::to_string(capacity) +
                  " bytes for field '" + name_ + "'");
    }
    const size_t keep = std::min(bytes_, capacity);
    if (keep) residency::before_host_access(buffer_.get());
    if (keep) std::memcpy(fresh.get(), buffer_.get(), keep);
    std::memset(fresh.get() + keep, 0, capacity - keep);
  }
  buffer_ = std::move(fresh);
  ++write_version_;
  capacity_ = capacity;
  bytes_ = std::min(bytes_, capacity);
}

std::byte* Field::mutable_bytes() {
  residency::before_host_access(buffer_.get());
  return raw_bytes();
}

std::byte* Field::raw_bytes() {
  ++write_version_;
  if (buffer_.use_count() > 1) reallocate(bytes_);
  return buffer_.get();
}

void Field::resize(size_t elements) {
  const size_t n = elements * element_bytes();
  if (n > capacity_) {
    reallocate(std::max(n, 2 * capacity_));
  } else if (n > bytes_ && shared()) {
    reallocate(capacity_);
  }
  if (n > bytes_) std::memset(buffer_.get() + bytes_, 0, n - bytes_);
  bytes_ = n;
  ++write_version_;
}

void Field::reserve(size_t elements) {
  const size_t n = elements * element_bytes();
  if (n > capacity_) reallocate(n);
}

// ---------------------------------------------------------------------------
// Construction

Set::Set(std::string name) : name_(std::move(name)), id_(next_set_id++) {}

Set::Set(std::string name, std::vector<const Set*> endpoint_sets) : Set(std::move(name)) {
  for (size_t k = 0; k < endpoint_sets.size(); ++k)
    if (!endpoint_sets[k])
      throw Fault(describe() + ": endpoint set " + std::to_string(k) + " is null");
  endpoint_sets_ = std::move(endpoint_sets);
  kind_ = endpoint_sets_.empty() ? SetKind::Vertex : SetKind::Edge;
}

Set::Set(std::string name, Set& points, std::vector<int> extents) : Set(std::move(name)) {
  if (points.size() != 0 || points.arity() != 0)
    throw Fault(describe() + ": a grid needs an empty vertex set as its points, but " +
                points.describe() + " has " +
                (points.arity() ? "endpoints" : std::to_string(points.size()) + " elements"));
  if (extents.empty()) throw Fault(describe() + ": a grid needs at least one extent");
  size_t count = 1;
  for (int n : extents) {
    if (n < 1) throw Fault(describe() + ": grid extent " + std::to_string(n) + " is not positive");
    count *= static_cast<size_t>(n);
  }
  if (count > static_cast<size_t>(INT32_MAX) / extents.size())
    throw Fault(describe() + ": grid of " + std::to_string(count) + " points is too large");
  kind_ = SetKind::Grid;
  extents_ = std::move(extents);
  endpoint_sets_ = {&points, &points};
  points.add_many(static_cast<int>(count));
  const int d = dimensions();
  endpoints_.resize(count * d * 2);
  std::vector<int> unit(d, 0);
  for (int p = 0; p < static_cast<int>(count); ++p) {
    for (int k = 0; k < d; ++k) {
      unit[k] = 1;
      const size_t link = static_cast<size_t>(p) * d + k;
      endpoints_[2 * link] = p;
      endpoints_[2 * link + 1] = grid_point_at(p, unit);
      unit[k] = 0;
    }
  }
  grow(static_cast<int>(count) * d);
}

std::string Set::describe() const { return name_.empty() ? "unnamed set" : "set '" + name_ + "'"; }

bool Set::homogeneous() const {
  for (const Set* s : endpoint_sets_)
    if (s != endpoint_sets_.front()) return false;
  return true;
}

// ---------------------------------------------------------------------------
// Elements

void Set::grow(int count) {
  if (pinned_)
    throw Fault(describe() + " cannot grow: its fields are pinned (a host holds views of them)");
  size_ += count;
  ++version_;
  for (auto& f : fields_) f->resize(static_cast<size_t>(size_));
}

void Set::pin_fields() {
  // An array a tensor still shares would move at the field's next write: unshare it now.
  for (auto& f : fields_)
    if (f->shared()) f->mutable_bytes();
  pinned_ = true;
}

void Set::reserve(int elements) {
  if (pinned_) return;  // it cannot grow
  for (auto& f : fields_) f->reserve(static_cast<size_t>(elements));
  endpoints_.reserve(static_cast<size_t>(elements) * arity());
}

void Set::set_mesh_numbers(std::vector<int32_t> numbers, int32_t whole) {
  if (numbers.size() != static_cast<size_t>(size_))
    throw Fault(describe() + ": " + std::to_string(numbers.size()) + " mesh numbers for " +
                std::to_string(size_) + " elements");
  const int32_t limit = whole < 0 ? size_ : whole;
  std::vector<char> seen(static_cast<size_t>(std::max(limit, 0)), 0);
  for (size_t e = 0; e < numbers.size(); ++e) {
    const int32_t m = numbers[e];
    if (m < 0 || m >= limit || seen[m])
      throw Fault(element_str(*this, static_cast<int>(e)) + ": mesh number " + std::to_string(m) +
                  (m < 0 || m >= limit ? " is out of range" : " is given twice") +
                  (whole < 0
                       ? " (the mesh numbers must be a permutation of the elements)"
                       : " (the mesh numbers of a part must be distinct elements of the mesh)"));
    seen[m] = 1;
  }
  mesh_numbers_ = std::move(numbers);
}

int Set::add() { return add_many(1); }

int Set::add_many(int count) {
  if (arity() != 0)
    throw Fault(describe() + " is an edge set: each element needs " + std::to_string(arity()) +
                " endpoints");
  if (count < 0) throw Fault(describe() + ": cannot add " + std::to_string(count) + " elements");
  const int first = size_;
  grow(count);
  return first;
}

void Set::check_endpoints(int element, std::span<const int32_t> endpoints) const {
  for (int k = 0; k < arity(); ++k) {
    const Set& target = *endpoint_sets_[k];
    if (endpoints[k] < 0 || endpoints[k] >= target.size())
      throw Fault(element_str(*this, element) + ": endpoint " + std::to_string(k) + " is " +
                  std::to_string(endpoints[k]) + ", but " + target.describe() + " has " +
                  std::to_string(target.size()) + " elements");
  }
}

int Set::add(std::span<const int32_t> endpoints) {
  if (arity() == 0 && endpoints.empty()) return add();
  if (arity() != 0 && static_cast<int>(endpoints.size()) != arity())
    throw Fault(describe() + ": an element needs " + std::to_string(arity()) +
                " endpoints but got " + std::to_string(endpoints.size()));
  return add_edges(endpoints);
}

int Set::add_edges(std::span<const int32_t> flat) {
  if (is_grid()) throw Fault(describe() + " is a grid: its links come from its extents");
  if (arity() == 0) throw Fault(describe() + " is a vertex set: its elements have no endpoints");
  if (flat.size() % arity() != 0)
    throw Fault(describe() + ": " + std::to_string(flat.size()) +
                " endpoint indices are not a whole number of " + std::to_string(arity()) +
                "-endpoint elements");
  const int count = static_cast<int>(flat.size() / arity());
  for (int i = 0; i < count; ++i)
    check_endpoints(size_ + i, flat.subspan(static_cast<size_t>(i) * arity(), arity()));
  endpoints_.insert(endpoints_.end(), flat.begin(), flat.end());
  const int first = size_;
  grow(count);
  return first;
}

void Set::check_element(int element, std::string_view what) const {
  if (element < 0 || element >= size_)
    throw Fault(describe() + " has no element " + std::to_string(element) + " (" +
                std::to_string(size_) + " elements)" + (what.empty() ? "" : ": ") +
                std::string(what));
}

// ---------------------------------------------------------------------------
// Fields

int Set::add_field(const std::string& name, FieldType type) {
  if (field_index(name) >= 0) throw Fault(describe() + " already has a field '" + name + "'");
  if (type.kind == ComponentKind::String)
    throw Fault(describe() + ", field '" + name + "': fields cannot hold strings");
  for (int d : type.dims)
    if (d < 1)
      throw Fault(describe() + ", field '" + name + "': dimension " + std::to_string(d) +
                  " is not positive");
  fields_.push_back(std::make_unique<Field>(name, std::move(type)));
  fields_.back()->resize(static_cast<size_t>(size_));
  return field_count() - 1;
}

int Set::field_index(std::string_view name) const {
  for (int i = 0; i < field_count(); ++i)
    if (fields_[i]->name() == name) return i;
  return -1;
}

Field& Set::field(std::string_view name) {
  return const_cast<Field&>(static_cast<const Set*>(this)->field(name));
}

const Field& Set::field(std::string_view name) const {
  int i = field_index(name);
  if (i < 0) throw Fault(describe() + " has no field '" + std::string(name) + "'");
  return *fields_[i];
}

int Set::require_field(std::string_view name, const FieldType& type) const {
  const Field& f = field(name);
  if (!(f.type() == type))
    throw Fault(describe() + ", field '" + f.name() + "' holds " + f.type().str() + " but " +
                type.str() + " is required");
  return field_index(name);
}

void Set::check_field(int field) const {
  if (field < 0 || field >= field_count())
    throw Fault(describe() + " has no field number " + std::to_string(field));
}

Tensor Set::get(int field_number, int element) const {
  check_field(field_number);
  const Field& f = *fields_[field_number];
  check_element(element, "reading field '" + f.name() + "'");
  const FieldType& t = f.type();
  Tensor value(t.kind, Shape::of(t.dims));
  const size_t n = f.components();
  const size_t first = static_cast<size_t>(element) * n;
  if (t.single && t.kind == ComponentKind::Float) {
    const float* src = f.data<float>() + first;
    double* dst = value.mutable_floats();
    for (size_t i = 0; i < n; ++i) dst[i] = src[i];
  } else if (t.single && t.kind == ComponentKind::Complex) {
    const std::complex<float>* src = f.data<std::complex<float>>() + first;
    Complex* dst = value.mutable_complexes();
    for (size_t i = 0; i < n; ++i) dst[i] = Complex(src[i]);
  } else {
    std::memcpy(value.mutable_ints(), f.bytes() + first * t.component_bytes(), f.element_bytes());
  }
  return value;
}

void Set::set(int field_number, int element, const Tensor& value) {
  check_field(field_number);
  Field& f = *fields_[field_number];
  check_element(element, "writing field '" + f.name() + "'");
  const FieldType& t = f.type();
  if (value.kind() != t.kind || value.shape() != Shape::of(t.dims))
    throw Fault(element_str(*this, element) + ", field '" + f.name() + "': expected a " + t.str() +
                " value but got " + tensor_str(value));
  const size_t n = f.components();
  const size_t first = static_cast<size_t>(element) * n;
  if (t.single && t.kind == ComponentKind::Float) {
    float* dst = f.data<float>() + first;
    for (size_t i = 0; i < n; ++i) dst[i] = static_cast<float>(value.floats()[i]);
  } else if (t.single && t.kind == ComponentKind::Complex) {
    std::complex<float>* dst = f.data<std::complex<float>>() + first;
    for (size_t i = 0; i < n; ++i) dst[i] = std::complex<float>(value.complexes()[i]);
  } else {
    std::memcpy(f.bytes() + first * t.component_bytes(), value.ints(), f.element_bytes());
  }
}

Tensor Set::field_tensor(int field_number) const {
  check_field(field_number);
  const Field& f = *fields_[field_number];
  const FieldType& t = f.type();
  const Shape shape = Shape::blocked(std::vector<int>{size_}, Shape::of(t.dims));
  if (!t.single && !pinned_) return Tensor(t.kind, shape, f.buffer());
  Tensor out(t.kind, shape);
  if (!t.single) {  // pinned: a copy, so that later writes to the field stay in place
    const size_t bytes = out.size() * t.component_bytes();
    if (bytes) std::memcpy(out.mutable_ints(), f.bytes(), bytes);
    return out;
  }
  const size_t n = out.size();
  if (t.kind == ComponentKind::Float) {
    const float* src = f.data<float>();
    double* dst = out.mutable_floats();
    for (size_t i = 0; i < n; ++i) dst[i] = src[i];
  } else {
    const std::complex<float>* src = f.data<std::complex<float>>();
    Complex* dst = out.mutable_complexes();
    for (size_t i = 0; i < n; ++i) dst[i] = Complex(src[i]);
  }
  return out;
}

void Set::assign_field(int field_number, const Tensor& value) {
  check_field(field_number);
  Field& f = *fields_[field_number];
  const FieldType& t = f.type();
  const size_t n = f.components() * static_cast<size_t>(size_);
  if (value.kind() != t.kind)
    throw Fault("a " + tensor_str(value) + " value cannot be stored in field '" + f.name() +
                "' of " + describe() + ", which holds " + t.str());
  if (value.size() != n)
    throw Fault("a vector of " + std::to_string(value.size()) +
                " components cannot be stored in field '" + f.name() + "' of " + describe());
  if (t.single && t.kind == ComponentKind::Float) {
    float* dst = f.data<float>();
    const double* src = value.floats();
    for (size_t i = 0; i < n; ++i) dst[i] = static_cast<float>(src[i]);
    return;
  }
  if (t.single && t.kind == ComponentKind::Complex) {
    std::complex<float>* dst = f.data<std::complex<float>>();
    const Complex* src = value.complexes();
    for (size_t i = 0; i < n; ++i) dst[i] = std::complex<float>(src[i]);
    return;
  }
  const size_t bytes = n * t.component_bytes();
  if (value.shared_buffer() && !pinned_) {  // adopt: the value's heap block becomes the array
    if (value.shared_buffer() == f.buffer_) return;  // `S.f = S.f`
    f.buffer_ = value.shared_buffer();
    f.bytes_ = f.capacity_ = bytes;
    ++f.write_version_;
    return;
  }
  if (bytes) std::memcpy(f.mutable_bytes(), value.ints(), bytes);
}

Tensor Set::take_field(int field_number) {
  Tensor out = field_tensor(field_number);
  Field& f = *fields_[field_number];
  if (!f.type().single && !pinned_) {
    f.buffer_.reset();
    f.bytes_ = f.capacity_ = 0;
    ++f.write_version_;
  }
  return out;
}

// ---------------------------------------------------------------------------
// Grids

void Set::require_grid() const {
  if (!is_grid()) throw Fault(describe() + " is not a grid");
}

int Set::grid_point(std::span<const int> coords) const {
  require_grid();
  if (static_cast<int>(coords.size()) != dimensions())
    throw Fault(describe() + " has " + std::to_string(dimensions()) + " dimensions but " +
                std::to_string(coords.size()) + " coordinates were given");
  int index = 0, stride = 1;
  for (int k = 0; k < dimensions(); ++k) {
    index += wrap(coords[k], extents_[k]) * stride;
    stride *= extents_[k];
  }
  return index;
}

std::vector<int> Set::grid_coords(int point) const {
  require_grid();
  points().check_element(point, "a grid point of " + describe());
  std::vector<int> coords(dimensions());
  for (int k = 0; k < dimensions(); ++k) {
    coords[k] = point % extents_[k];
    point /= extents_[k];
  }
  return coords;
}

int Set::grid_point_at(int point, std::span<const int> offset) const {
  std::vector<int> coords = grid_coords(point);
  if (offset.size() != coords.size())
    throw Fault(describe() + " has " + std::to_string(dimensions()) +
                " dimensions but an offset of " + std::to_string(offset.size()) + " was given");
  for (size_t k = 0; k < coords.size(); ++k) coords[k] += offset[k];
  return grid_point(coords);
}

int Set::grid_link(int point, int axis) const {
  require_grid();
  points().check_element(point, "a grid point of " + describe());
  if (axis < 0 || axis >= dimensions())
    throw Fault(describe() + " has no axis " + std::to_string(axis));
  return point * dimensions() + axis;
}

int Set::grid_link_between(int point, std::span<const int> from, std::span<const int> to) const {
  require_grid();
  const int d = dimensions();
  int axis = -1;
  bool neighbours = static_cast<int>(from.size()) == d && static_cast<int>(to.size()) == d;
  for (int k = 0; neighbours && k < d; ++k) {
    const int diff = to[k] - from[k];
    if (diff == 0) continue;
    neighbours = (diff == 1 || diff == -1) && axis < 0;
    axis = k;
  }
  if (!neighbours || axis < 0)
    throw Fault(describe() + ": the offsets of a link must differ by 1 along exactly one axis");
  const std::span<const int> start = to[axis] > from[axis] ? from : to;
  return grid_link(grid_point_at(point, start), axis);
}

}  // namespace simit::runtime
