// Host sets: vertex, edge and grid sets wrapping the runtime's struct-of-arrays storage,
// with typed field handles (FieldRef) and element handles (ElementRef).
#pragma once

#include <concepts>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "simit/element.h"

namespace simit {

class Set;
namespace runtime {
class Set;
}
namespace api {
struct SetAccess;
}

// FieldRef's access to a set's storage, out of line (src/api/set.cpp) so that the runtime's
// representation stays behind the API.
namespace detail {
const std::string& field_name(const Set& set, int field);
void* field_data(const Set& set, int field);
// Element e's value; throws Error naming the set and field when e is not one of its elements.
void* field_element(const Set& set, int field, ElementRef e);
}  // namespace detail

// A typed handle to one field of one set. It names the field by (set, index), not by a
// pointer into the storage, so it stays valid when the set grows.
template <Component T, int... dims>
class FieldRef {
 public:
  using View = TensorRef<T, dims...>;
  static constexpr size_t components = View::size;

  FieldRef() = default;

  bool defined() const { return set_ != nullptr; }
  const std::string& name() const { return detail::field_name(*set_, field_); }

  // A view of element e's value (reads and writes the set's storage directly).
  View get(ElementRef e) const { return View(at(e)); }
  View operator()(ElementRef e) const { return get(e); }

  // All components of e, row-major.
  void set(ElementRef e, std::initializer_list<T> values) const { get(e) = values; }
  template <class Collection>
  requires requires(const Collection& c) {
    std::begin(c);
    std::size(c);
  }
  void set(ElementRef e, const Collection& values) const {
    if (std::size(values) != components)
      throw Error("field '" + name() + "' has " + std::to_string(components) +
                  " components per element but " + std::to_string(std::size(values)) +
                  " values were given");
    T* out = at(e);
    for (const auto& v : values) *out++ = static_cast<T>(v);
  }
  void set(ElementRef e, const T& v) const requires(sizeof...(dims) == 0) { *at(e) = v; }

  // The whole array: element 0's components, then element 1's, ... (moves when the set grows).
  T* data() const { return static_cast<T*>(detail::field_data(*set_, field_)); }
  T* getData() const { return data(); }

 private:
  T* at(ElementRef e) const {
    if (!set_) throw Error("use of an undefined FieldRef");
    return static_cast<T*>(detail::field_element(*set_, field_, e));
  }
  // Made by Set::add_field and Set::get_field only, which check that T and dims are the
  // field's type (the storage is reached untyped).
  friend class Set;
  FieldRef(const Set* set, int field) : set_(set), field_(field) {}
  const Set* set_ = nullptr;
  int field_ = -1;
};

// Elements 0..n-1 of a set, or the elements added by one add_many call, as ElementRefs.
class ElementRange {
 public:
  class iterator {
   public:
    using value_type = ElementRef;
    using difference_type = std::ptrdiff_t;
    iterator() = default;
    explicit iterator(int i) : i_(i) {}
    ElementRef operator*() const { return ElementRef(i_); }
    iterator& operator++() {
      ++i_;
      return *this;
    }
    iterator operator++(int) { return iterator(i_++); }
    bool operator==(const iterator&) const = default;

   private:
    int i_ = 0;
  };
  ElementRange(int first, int count) : first_(first), count_(count) {}
  iterator begin() const { return iterator(first_); }
  iterator end() const { return iterator(first_ + count_); }
  int size() const { return count_; }
  ElementRef operator[](int k) const { return ElementRef(first_ + k); }

 private:
  int first_, count_;
};

// A set of elements of the hypergraph. Sets are neither copyable nor movable: edge sets and
// bound functions refer to them by address. Note that `Set b(a);` does not copy `a`: it makes
// an edge set with one endpoint per element in `a` (as in the original API).
class Set {
 public:
  enum Kind { Unstructured, Grid };

  Set() : Set(std::string()) {}
  explicit Set(std::string name);
  explicit Set(const char* name) : Set(std::string(name)) {}
  // An edge set whose elements have one endpoint in each of `endpoints`, in order.
  template <class... S>
  requires(sizeof...(S) >= 1 && (std::same_as<S, Set> && ...)) explicit Set(S&... endpoints)
      : Set(std::string(), std::vector<Set*>{&endpoints...}) {}
  template <class... S>
  requires(sizeof...(S) >= 1 && (std::same_as<S, Set> && ...))
      Set(std::string name, S&... endpoints)
      : Set(std::move(name), std::vector<Set*>{&endpoints...}) {}
  Set(std::string name, std::vector<Set*> endpoints);
  // A periodic grid over the empty vertex set `points` (fills it; coordinate 0 fastest).
  Set(Set& points, std::vector<int> extents) : Set(std::string(), points, std::move(extents)) {}
  Set(std::string name, Set& points, std::vector<int> extents);
  Set(const Set&) = delete;
  Set& operator=(const Set&) = delete;
  ~Set();

  const std::string& name() const;
  int size() const;
  int cardinality() const;
  Kind kind() const;
  bool is_homogeneous() const;

  // --- elements ------------------------------------------------------------------------
  ElementRef add();  // vertex sets
  template <class... E>
  requires(sizeof...(E) >= 1 && (std::same_as<E, ElementRef> && ...)) ElementRef
      add(E... endpoints) {
    const ElementRef ends[] = {endpoints...};
    return add(std::span<const ElementRef>(ends));
  }
  ElementRef add(std::span<const ElementRef> endpoints);  // edge sets, one per endpoint set
  ElementRange add_many(int count);                       // vertex sets
  ElementRange elements() const { return ElementRange(0, size()); }
  ElementRange::iterator begin() const { return elements().begin(); }
  ElementRange::iterator end() const { return elements().end(); }

  // --- endpoints -----------------------------------------------------------------------
  ElementRef endpoint(ElementRef edge, int k) const;
  std::vector<ElementRef> endpoints(ElementRef edge) const;
  Set* endpoint_set(int k) const;
  const int32_t* endpoints_data() const;

  // --- fields --------------------------------------------------------------------------
  template <Component T, int... dims>
  FieldRef<T, dims...> add_field(const std::string& name) {
    return FieldRef<T, dims...>(this, add_field(name, field_type_of<T, dims...>()));
  }
  // A field described at run time (choice 2 of API.md §8); returns its index.
  int add_field(const std::string& name, const FieldType& type);
  // An existing field; its component type and dimensions must be exactly T and dims.
  template <Component T, int... dims>
  FieldRef<T, dims...> get_field(const std::string& name) const {
    return FieldRef<T, dims...>(this, require_field(name, field_type_of<T, dims...>()));
  }
  bool has_field(const std::string& name) const;
  void* field_data(const std::string& name);
  // From now on the fields' arrays never move, so field_data pointers stay valid for the
  // set's life (views a host keeps, Python's numpy arrays); the set can no longer grow
  // (adding elements throws Error). Runs copy where they would otherwise share an array.
  void pin_fields();
  bool fields_pinned() const;

  // --- grids ---------------------------------------------------------------------------
  const std::vector<int>& grid_extents() const;
  ElementRef grid_point(std::span<const int> coords) const;
  ElementRef grid_point(std::initializer_list<int> coords) const {
    return grid_point(std::span<const int>(coords.begin(), coords.size()));
  }
  std::vector<int> grid_point_coords(ElementRef point) const;
  ElementRef grid_edge(std::span<const int> coords, int axis) const;

  // --- the spellings of the original API ---------------------------------------------------
  template <Component T, int... dims>
  FieldRef<T, dims...> addField(const std::string& name) {
    return add_field<T, dims...>(name);
  }
  template <Component T, int... dims>
  FieldRef<T, dims...> getField(const std::string& name) const {
    return get_field<T, dims...>(name);
  }
  void* getFieldData(const std::string& name) { return field_data(name); }
  int getSize() const { return size(); }
  int getCardinality() const { return cardinality(); }
  Kind getKind() const { return kind(); }
  const std::string& getName() const { return name(); }
  ElementRef getEndpoint(ElementRef edge, int k) const { return endpoint(edge, k); }
  std::vector<ElementRef> getEndpoints(ElementRef edge) const { return endpoints(edge); }
  const Set* getEndpointSet(int k) const { return endpoint_set(k); }
  bool isHomogeneous() const { return is_homogeneous(); }
  const int32_t* getEndpointsData() const { return endpoints_data(); }
  std::vector<int> getDimensions() const { return grid_extents(); }
  ElementRef getGridPoint(std::initializer_list<int> coords) const { return grid_point(coords); }
  std::vector<int> getGridPointCoords(ElementRef p) const { return grid_point_coords(p); }

 private:
  friend struct api::SetAccess;  // the engine binds the storage itself (shared, never copied)
  int require_field(const std::string& name, const FieldType& type) const;
  void check_element(ElementRef e, const char* what) const;

  std::unique_ptr<runtime::Set> impl_;
  std::vector<Set*> endpoint_sets_;
};

std::ostream& operator<<(std::ostream& os, const Set& set);

}  // namespace simit
