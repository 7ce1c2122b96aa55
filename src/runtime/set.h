// Sets of the hypergraph: elements, struct-of-arrays fields, edge endpoints and grid lattices.
#pragma once

#include <complex>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "runtime/fault.h"
#include "runtime/tensor.h"

namespace simit::runtime {

// What one element of a field holds: a dense tensor of `dims` (none for a scalar) whose
// components have `kind`. `single` stores float components as binary32 (and complex ones as
// two binary32), for hosts that run with float size 4; the language value stays binary64.
struct FieldType {
  ComponentKind kind = ComponentKind::Float;
  std::vector<int> dims;
  bool single = false;

  size_t components() const;  // per element
  size_t component_bytes() const;
  std::string str() const;  // e.g. "float 3x3", "int", "float32 3"
  bool operator==(const FieldType& o) const = default;
};

// One field: a contiguous array with the tensor of element 0, then element 1, ..., each
// stored row-major. The array is a shared, reference-counted heap block, the same kind of
// block runtime::Tensor uses: reading the field as a tensor (Set::field_tensor) shares it,
// and every mutable access below copies it first while it is shared (copy-on-write), so a
// tensor read earlier keeps its values. The array moves when the set grows and when a
// mutable access finds it shared, so keep the field, not the pointer.
class Field {
 public:
  Field(std::string name, FieldType type) : name_(std::move(name)), type_(std::move(type)) {}

  const std::string& name() const { return name_; }
  const FieldType& type() const { return type_; }
  size_t components() const { return type_.components(); }
  size_t element_bytes() const { return components() * type_.component_bytes(); }
  // The array; an array whose newest contents are in an executor's memory is brought back
  // first (runtime/residency.h), as by every accessor below but the raw ones.
  std::byte* bytes() { return mutable_bytes(); }  // unshares first
  const std::byte* bytes() const {
    residency::before_host_access(buffer_.get());
    return buffer_.get();
  }
  // bytes() for an executor copying the array into its own memory, where a newer copy of it
  // may be: not brought back (the mutable form still counts a write and unshares).
  std::byte* raw_bytes();
  const std::byte* raw_bytes() const { return buffer_.get(); }

  // Typed view of the whole array; T must be the storage type of the components
  // (int32_t, double, float, bool, std::complex<double>, std::complex<float>).
  // The non-const forms unshare the array first.
  template <class T>
  T* data() {
    check_storage(storage_tag<T>());
    return reinterpret_cast<T*>(mutable_bytes());
  }
  template <class T>
  const T* data() const {
    check_storage(storage_tag<T>());
    residency::before_host_access(buffer_.get());
    return reinterpret_cast<const T*>(buffer_.get());
  }
  // The components of one element (no bounds check: use Set::get for checked access).
  template <class T>
  T* at(int element) {
    return data<T>() + static_cast<size_t>(element) * components();
  }
  template <class T>
  const T* at(int element) const {
    return data<T>() + static_cast<size_t>(element) * components();
  }

  // The shared block holding the array (null while it is empty), and whether anything
  // else (a tensor read from the field) shares it now.
  const std::shared_ptr<std::byte[]>& buffer() const { return buffer_; }
  bool shared() const { return buffer_.use_count() > 1; }
  // Counts the mutable accesses (and the arrays adopted or dropped), whether or not they
  // changed a value: a cache derived from the field's values is valid while it is unchanged.
  uint64_t write_version() const { return write_version_; }

 private:
  friend class Set;
  enum class Tag { Int, Double, Single, Bool, ComplexDouble, ComplexSingle, Other };
  template <class T>
  static constexpr Tag storage_tag() {
    if constexpr (std::is_same_v<T, int32_t>) return Tag::Int;
    if constexpr (std::is_same_v<T, double>) return Tag::Double;
    if constexpr (std::is_same_v<T, float>) return Tag::Single;
    if constexpr (std::is_same_v<T, bool>) return Tag::Bool;
    if constexpr (std::is_same_v<T, std::complex<double>>) return Tag::ComplexDouble;
    if constexpr (std::is_same_v<T, std::complex<float>>) return Tag::ComplexSingle;
    return Tag::Other;
  }
  void check_storage(Tag requested) const;
  std::byte* mutable_bytes();  // copies the array first while it is shared
  void resize(size_t elements);
  void reserve(size_t elements);
  void reallocate(size_t capacity_bytes);  // a private copy with this capacity

  std::string name_;
  FieldType type_;
  std::shared_ptr<std::byte[]> buffer_;
  size_t bytes_ = 0;     // in use
  size_t capacity_ = 0;  // allocated
  uint64_t write_version_ = 0;
};

enum class SetKind : uint8_t { Vertex, Edge, Grid };

// A set of elements numbered 0..size-1 in insertion order. An edge set also holds, per element,
// one endpoint in each of its endpoint sets (which must outlive it). A grid set is an edge set
// whose links and points (its single endpoint set) were generated from lattice extents.
// Sets are neither copyable nor movable: edge sets and patterns refer to them by address.
// Elements are only ever appended (removal would renumber what endpoints point at).
class Set {
 public:
  explicit Set(std::string name = "");
  Set(std::string name, std::vector<const Set*> endpoint_sets);
  // A periodic grid over the empty vertex set `points` (LANGUAGE.md §8.7): fills `points` with
  // the product of `extents` elements and this set with one link per point and axis.
  Set(std::string name, Set& points, std::vector<int> extents);
  Set(const Set&) = delete;
  Set& operator=(const Set&) = delete;

  const std::string& name() const { return name_; }
  std::string describe() const;  // "set 'name'" for messages
  SetKind kind() const { return kind_; }
  bool is_grid() const { return kind_ == SetKind::Grid; }
  int size() const { return size_; }
  // Identity and topology stamp: caches of derived structure (matrix patterns) compare these
  // to notice that a set was replaced or grew.
  uint64_t id() const { return id_; }
  uint64_t topology_version() const { return version_; }

  // --- elements -------------------------------------------------------------------------
  int add();                                    // vertex sets
  int add(std::span<const int32_t> endpoints);  // edge sets: one index per endpoint set
  int add(std::initializer_list<int32_t> endpoints) { return add(std::span(endpoints)); }
  int add_many(int count);                       // vertex sets; returns the first new index
  int add_edges(std::span<const int32_t> flat);  // edge sets: arity indices per edge
  void reserve(int elements);

  // --- mesh numbers -----------------------------------------------------------------------
  // A set built from a mesh in another order (a scene renumbers its meshes for locality)
  // remembers each element's number in the mesh, so that what a user sees (messages, output)
  // names elements as the mesh does. Without mesh numbers, and for elements added after
  // them, an element's mesh number is its index.
  int32_t mesh_number(int element) const {
    return static_cast<size_t>(element) < mesh_numbers_.size() ? mesh_numbers_[element] : element;
  }
  bool has_mesh_numbers() const { return !mesh_numbers_.empty(); }
  std::span<const int32_t> mesh_numbers() const { return mesh_numbers_; }
  // `numbers[e]`: element e's number in the mesh; a permutation of 0..size()-1 (Fault if not).
  // A part of a set (a distributed run's rank holds one): with `whole` >= 0, distinct numbers
  // in [0, whole) instead.
  void set_mesh_numbers(std::vector<int32_t> numbers, int32_t whole = -1);

  // --- pinned storage ---------------------------------------------------------------------
  // From now on every field's array stays where it is, for hosts that hold views of it
  // (Python's numpy arrays): reading a whole field as a tensor copies it instead of sharing
  // it, storing a whole field copies into the array instead of adopting the value's, and the
  // set refuses to grow (Fault). Fields added later are pinned too.
  void pin_fields();
  bool fields_pinned() const { return pinned_; }

  // --- fields ---------------------------------------------------------------------------
  int add_field(const std::string& name, FieldType type);  // zero for every element
  int field_count() const { return static_cast<int>(fields_.size()); }
  int field_index(std::string_view name) const;  // -1 if absent
  Field& field(int index) { return *fields_[index]; }
  const Field& field(int index) const { return *fields_[index]; }
  Field& field(std::string_view name);  // Fault if absent
  const Field& field(std::string_view name) const;
  // Fault unless the field exists with exactly this type (binding a program to host data).
  int require_field(std::string_view name, const FieldType& type) const;

  // Element values as runtime tensors (float kind for float32 storage too).
  Tensor get(int field, int element) const;
  void set(int field, int element, const Tensor& value);

  // A whole field as one tensor: `size()` blocks of the element shape (components for a
  // scalar field). It shares the field's array, no copy (a converted copy for float32
  // storage); later writes to the field copy the array first, so the tensor keeps the
  // values it was read with.
  Tensor field_tensor(int field) const;
  // Stores `value` (same component kind, size() x components components, any shape) as
  // the whole field. A value whose components are on the heap is adopted, not copied (it
  // becomes the field's array, shared copy-on-write); the field's old array is released.
  void assign_field(int field, const Tensor& value);
  // Moves the field's array out as field_tensor would read it, leaving this set's
  // reference to it released, so that writes through the tensor copy nothing when no one
  // else shares it. Put it back with assign_field before the field is used again.
  Tensor take_field(int field);

  // --- endpoints ------------------------------------------------------------------------
  int arity() const { return static_cast<int>(endpoint_sets_.size()); }
  const Set& endpoint_set(int k) const { return *endpoint_sets_[k]; }
  const std::vector<const Set*>& endpoint_sets() const { return endpoint_sets_; }
  bool homogeneous() const;
  const int32_t* endpoints() const { return endpoints_.data(); }  // size × arity, edge-major
  std::span<const int32_t> endpoints_of(int element) const {
    return {endpoints_.data() + static_cast<size_t>(element) * arity(),
            static_cast<size_t>(arity())};
  }
  int32_t endpoint(int element, int k) const {
    return endpoints_[static_cast<size_t>(element) * arity() + k];
  }

  // --- grids (kind() == Grid) --------------------------------------------------------------
  const std::vector<int>& extents() const { return extents_; }
  int dimensions() const { return static_cast<int>(extents_.size()); }
  const Set& points() const { return endpoint_set(0); }
  // The point with these coordinates, each wrapped periodically.
  int grid_point(std::span<const int> coords) const;
  std::vector<int> grid_coords(int point) const;
  // The point at `offset` from `point` (periodic).
  int grid_point_at(int point, std::span<const int> offset) const;
  // The link leaving `point` in the + direction of `axis`.
  int grid_link(int point, int axis) const;
  // The link between the points at offsets `from` and `to` of `point`: they must differ by
  // exactly 1 along exactly one axis; the link starts at the smaller one (before wrapping).
  int grid_link_between(int point, std::span<const int> from, std::span<const int> to) const;

 private:
  void check_element(int element, std::string_view what) const;
  void check_field(int field) const;
  void check_endpoints(int element, std::span<const int32_t> endpoints) const;
  void grow(int count);
  void require_grid() const;

  std::string name_;
  SetKind kind_ = SetKind::Vertex;
  int size_ = 0;
  uint64_t id_;
  uint64_t version_ = 0;
  std::vector<std::unique_ptr<Field>> fields_;  // unique_ptr: Field references stay valid
  std::vector<const Set*> endpoint_sets_;
  std::vector<int32_t> endpoints_;
  std::vector<int> extents_;
  std::vector<int32_t> mesh_numbers_;  // empty: every element is its own mesh number
  bool pinned_ = false;
};

}  // namespace simit::runtime
