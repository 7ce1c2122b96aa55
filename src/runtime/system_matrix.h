// System matrices: block CSR values over a sparsity pattern that is computed once per
// (edge set, row set, column set) and shared by every matrix assembled through that edge set.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <tuple>
#include <vector>

#include "runtime/residency.h"
#include "runtime/set.h"
#include "runtime/tensor.h"

namespace simit::runtime {

// Where each element's blocks live in the value array of a matrix assembled by a map over
// the element's set. An element's members are position 0 (the element itself) and positions
// k + 1 (its endpoint k); which positions lie in the row and column sets is the same for
// every element, so the table only stores block positions: per element, one entry per
// (row member, column member) pair, row-major.
struct AssemblyIndex {
  std::vector<int> row_members;
  std::vector<int> col_members;
  std::vector<int32_t> table;

  size_t pairs() const { return row_members.size() * col_members.size(); }
  const int32_t* of(int element) const {
    return table.data() + static_cast<size_t>(element) * pairs();
  }
  int32_t position(int element, int row_local, int col_local) const {
    return of(element)[static_cast<size_t>(row_local) * col_members.size() + col_local];
  }
};

// The element index of member `member` of `element` (0: the element itself).
inline int32_t member_element(const Set& s, int element, int member) {
  return member == 0 ? element : s.endpoint(element, member - 1);
}
// The set member `member` of s's elements lies in.
inline const Set& member_set(const Set& s, int member) {
  return member == 0 ? s : s.endpoint_set(member - 1);
}

// The set whose elements are a pattern's block rows (or columns), kept where that set has mesh
// numbers (Set::mesh_number: a scene renumbered it), so that a message about a row of the
// matrix (a solver's) names the element as the mesh does. A copy, not the set: a matrix may
// outlive the sets it was assembled over.
struct MeshAxis {
  std::string set;                    // Set::describe(), e.g. "set 'verts'"
  std::vector<int32_t> mesh_numbers;  // per block row (column)

  // Null unless `s` has mesh numbers.
  static std::shared_ptr<const MeshAxis> of(const Set& s);
  // "element 12 of set 'verts'" for block row (column) `block`, 12 its mesh number.
  std::string element(int block) const;
};
using MeshAxisPtr = std::shared_ptr<const MeshAxis>;

// The block structure of a matrix with rows() block rows and cols() block columns: row
// pointers (rows() + 1 ints) and one column index per block. Columns are ascending and
// distinct within each row ("canonical"), except in stencil patterns, whose rows follow the
// offsets and may repeat a column (those entries are summed).
class MatrixPattern {
 public:
  // LANGUAGE.md §8.5.5: for every element e of `edges`, every pair (x, y) of {e} ∪
  // endpoints(e) with x in `rows` and y in `cols`. A vertex set gives the diagonal.
  static std::shared_ptr<const MatrixPattern> assembled(const Set& edges, const Set& rows,
                                                        const Set& cols);
  // From CSR arrays; canonical() tells whether the columns are ascending and distinct. A
  // pattern derived from others passes on their axes (an axis of another length is dropped).
  static std::shared_ptr<const MatrixPattern> from_csr(int rows, int cols,
                                                       std::vector<int32_t> row_ptr,
                                                       std::vector<int32_t> col_idx,
                                                       MeshAxisPtr row_axis = nullptr,
                                                       MeshAxisPtr col_axis = nullptr);
  // LANGUAGE.md §8.7: one entry per point and per offset, the entry for offsets[j] in row p
  // at position row_ptr[p] + j, lying in the column of the (wrapped) point at that offset.
  static std::shared_ptr<const MatrixPattern> stencil(const Set& grid,
                                                      const std::vector<std::vector<int>>& offsets);

  int rows() const { return rows_; }
  int cols() const { return cols_; }
  int64_t nnz() const { return static_cast<int64_t>(col_idx_.size()); }  // blocks
  const std::vector<int32_t>& row_ptr() const { return row_ptr_; }
  const std::vector<int32_t>& col_idx() const { return col_idx_; }
  bool canonical() const { return canonical_; }
  // The sets of the block rows and columns where they have mesh numbers (else null):
  // assembled and stencil patterns take them from their sets, unions, transposes and products
  // from their operands.
  const MeshAxisPtr& row_axis() const { return row_axis_; }
  const MeshAxisPtr& col_axis() const { return col_axis_; }

  // Position of (the first) block (row, col), or -1 outside the pattern. A search: for
  // reads, not for assembly, which uses the precomputed index.
  int32_t find(int row, int col) const;

  bool has_assembly_index() const { return edges_id_ != 0; }
  // Whether the assembly index belongs to `edges` (the pattern was assembled through it).
  bool assembled_through(const Set& edges) const {
    return edges_id_ != 0 && edges.id() == edges_id_;
  }
  const AssemblyIndex& assembly() const { return assembly_; }
  // Block position for a write K(row_element, col_element) inside the mapped call on
  // `element` of `edges` (the set this pattern was assembled through), or -1 when the pair is
  // not {element} ∪ endpoints(element) in the row/column sets.
  int32_t assembly_position(const Set& edges, int element, int row_element, int col_element) const;

  // Bytes of the CSR index (row pointers + column indices) and of the assembly index.
  size_t index_bytes() const;
  size_t assembly_bytes() const;
  size_t bytes() const { return index_bytes() + assembly_bytes(); }

 private:
  MatrixPattern() = default;

  int rows_ = 0, cols_ = 0;
  bool canonical_ = true;
  std::vector<int32_t> row_ptr_;
  std::vector<int32_t> col_idx_;
  AssemblyIndex assembly_;
  uint64_t edges_id_ = 0;  // the set the assembly index belongs to (0: none)
  MeshAxisPtr row_axis_, col_axis_;
};

using PatternPtr = std::shared_ptr<const MatrixPattern>;

// The union of two patterns of one shape (canonical, even when an operand repeats a column),
// where each operand's blocks land in it (from_a, from_b: every block), and for each of its
// blocks the operands' block there (to_a, to_b; -1: none). Where an operand's pattern repeats
// a column (a stencil), several of its blocks land in one union block and to_a / to_b name
// only one of them: only from_a / from_b describe such an operand completely.
struct PatternUnion {
  PatternPtr pattern;
  std::vector<int32_t> from_a, from_b;
  std::vector<int32_t> to_a, to_b;
};
PatternUnion unite(const MatrixPattern& a, const MatrixPattern& b);

// The transposed pattern, and for each block of the original its position in the transpose.
struct PatternTranspose {
  PatternPtr pattern;
  std::vector<int32_t> position;
};
PatternTranspose transpose(const MatrixPattern& p);

// Caches derived patterns so that each is built once: assembly patterns per (edge set, row
// set, column set) and stencil patterns per (grid, offsets), rebuilt when a set involved has
// changed topology since; unions and transposes per pattern. Owned by whoever runs the program (one
// per loaded program, say).
class PatternRegistry {
 public:
  PatternPtr assembled(const Set& edges, const Set& rows, const Set& cols);
  PatternPtr stencil(const Set& grid, const std::vector<std::vector<int>>& offsets);
  std::shared_ptr<const PatternUnion> united(const PatternPtr& a, const PatternPtr& b);
  std::shared_ptr<const PatternTranspose> transposed(const PatternPtr& p);

  int builds() const { return builds_; }  // patterns built so far (for tests and benchmarks)
  void clear();

 private:
  struct Entry {
    uint64_t versions[3];
    PatternPtr pattern;
  };
  std::map<std::tuple<uint64_t, uint64_t, uint64_t>, Entry> assembled_;
  std::map<std::pair<uint64_t, std::vector<std::vector<int>>>, Entry> stencils_;
  // Keyed by address; the entries hold the operands, so an address is never reused meanwhile.
  std::map<std::pair<const MatrixPattern*, const MatrixPattern*>,
           std::pair<std::pair<PatternPtr, PatternPtr>, std::shared_ptr<const PatternUnion>>>
      unions_;
  std::map<const MatrixPattern*, std::pair<PatternPtr, std::shared_ptr<const PatternTranspose>>>
      transposes_;
  int builds_ = 0;
};

// A block-sparse matrix: block_rows × block_cols components per block of the pattern, stored
// row-major one block after another in pattern order. Its own storage is the value array;
// the pattern is shared. Scalar (unblocked) matrices have 1 × 1 blocks. Float components are
// doubles (values()); int and bool components are int32s (ints(); bools are 0 or 1); complex
// components are complex doubles (complexes()).
// Leaves new elements of a vector uninitialised (std::vector value-initialises them): for
// values that are written before they are read.
template <class T>
struct UninitialisedAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitialisedAllocator<U>;
  };
  UninitialisedAllocator() = default;
  template <class U>
  UninitialisedAllocator(const UninitialisedAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  // An array whose newer contents are in an executor's memory drops them as it goes
  // (runtime/residency.h).
  void deallocate(T* p, std::size_t n) noexcept {
    residency::before_free(p);
    std::allocator<T>::deallocate(p, n);
  }
};

// A matrix's values: copying them brings a newer copy in an executor's memory back first
// (runtime/residency.h); moving them keeps the array where it is.
struct MatrixValues : std::vector<double, UninitialisedAllocator<double>> {
  using Base = std::vector<double, UninitialisedAllocator<double>>;
  MatrixValues() = default;
  MatrixValues(const MatrixValues& o) : Base((residency::before_host_access(o.data()), o)) {}
  MatrixValues(MatrixValues&&) noexcept = default;
  MatrixValues& operator=(const MatrixValues& o) {
    residency::before_host_access(o.data());
    residency::before_host_access(data());
    Base::operator=(o);
    return *this;
  }
  MatrixValues& operator=(MatrixValues&&) noexcept = default;
};

class SystemMatrix {
 public:
  SystemMatrix() = default;  // a placeholder without pattern: assign before use
  // Float values left uninitialised, for whoever writes every one of them (runtime::add).
  struct Unset {};
  SystemMatrix(Unset, PatternPtr pattern, int block_rows, int block_cols);
  // All zero; a String kind is a Fault.
  SystemMatrix(PatternPtr pattern, int block_rows = 1, int block_cols = 1,
               ComponentKind kind = ComponentKind::Float);

  const MatrixPattern& pattern() const { return *pattern_; }
  const PatternPtr& shared_pattern() const { return pattern_; }
  ComponentKind kind() const { return kind_; }
  bool is_float() const { return kind_ == ComponentKind::Float; }
  int rows() const { return pattern_->rows(); }  // in blocks (elements of the row set)
  int cols() const { return pattern_->cols(); }
  int block_rows() const { return block_rows_; }
  int block_cols() const { return block_cols_; }
  int block_size() const { return block_rows_ * block_cols_; }
  int64_t scalar_rows() const { return static_cast<int64_t>(rows()) * block_rows_; }
  int64_t scalar_cols() const { return static_cast<int64_t>(cols()) * block_cols_; }

  // The components of a Float matrix (null for the other kinds). Values whose newest
  // contents are in an executor's memory are brought back first (runtime/residency.h), by
  // block() too; raw_values() does not, for an executor copying them into that memory.
  double* values() {
    residency::before_host_access(values_.data());
    return values_.data();
  }
  const double* values() const {
    residency::before_host_access(values_.data());
    return values_.data();
  }
  double* raw_values() { return values_.data(); }
  const double* raw_values() const { return values_.data(); }
  // The components of an Int or Bool matrix (null for the other kinds).
  int32_t* ints() { return ints_.data(); }
  const int32_t* ints() const { return ints_.data(); }
  // The components of a Complex matrix (null for the other kinds).
  Complex* complexes() { return complexes_.data(); }
  const Complex* complexes() const { return complexes_.data(); }
  // values(), ints() or complexes(), by the component type: double, int32_t or Complex.
  template <class T>
  T* data();
  template <class T>
  const T* data() const;
  size_t value_count() const { return values_.size() + ints_.size() + complexes_.size(); }
  double* block(int32_t position) {
    return values() + static_cast<size_t>(position) * block_size();
  }
  const double* block(int32_t position) const {
    return values() + static_cast<size_t>(position) * block_size();
  }
  void set_zero();

  // Component (i, j) of the logical unblocked matrix: zero outside the pattern, the sum of
  // the entries when a stencil pattern repeats the column. component() converts int
  // components to double (a Fault for complex ones); component_as<T> reads the matrix of
  // T's kind exactly (int32_t for int and bool).
  double component(int64_t i, int64_t j) const;
  template <class T>
  T component_as(int64_t i, int64_t j) const;

  size_t value_bytes() const {
    return values_.size() * sizeof(double) + ints_.size() * sizeof(int32_t) +
           complexes_.size() * sizeof(Complex);
  }

 private:
  PatternPtr pattern_;
  int block_rows_ = 1, block_cols_ = 1;
  ComponentKind kind_ = ComponentKind::Float;
  MatrixValues values_;
  std::vector<int32_t> ints_;
  std::vector<Complex> complexes_;
};

template <>
inline double* SystemMatrix::data<double>() {
  return values();
}
template <>
inline const double* SystemMatrix::data<double>() const {
  return values();
}
template <>
inline int32_t* SystemMatrix::data<int32_t>() {
  return ints();
}
template <>
inline const int32_t* SystemMatrix::data<int32_t>() const {
  return ints();
}
template <>
inline Complex* SystemMatrix::data<Complex>() {
  return complexes();
}
template <>
inline const Complex* SystemMatrix::data<Complex>() const {
  return complexes();
}

// The logical rows and columns of a matrix block of shape `block`: 1 x 1 for a scalar, the
// unblocked dimensions for a block of blocks (3x3 of 2x2 gives 6 x 6).
struct BlockDims {
  int rows = 1, cols = 1;
};
BlockDims block_dims(const Shape& block);

// Bytes used by these matrices: their values, plus each distinct pattern once.
size_t memory_bytes(std::span<const SystemMatrix* const> matrices);

}  // namespace simit::runtime
