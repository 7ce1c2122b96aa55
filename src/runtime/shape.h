// The dimensions of a dense tensor: an outer level of dimensions and, for blocked tensors,
// further levels describing the blocks (LANGUAGE.md §5.2.1), outermost first.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <vector>

namespace simit::runtime {

class Shape {
 public:
  static constexpr int kMaxRank = 8;    // dimensions over all levels
  static constexpr int kMaxLevels = 4;  // outer level plus nested blocks

  Shape() = default;  // a scalar
  // An unblocked shape (the scalar shape for no dimensions). Inline: the interpreter builds
  // one for almost every small tensor it computes.
  Shape(std::initializer_list<int> dims) {
    if (dims.size() > static_cast<size_t>(kMaxRank)) *this = of(std::vector<int>(dims));
    for (int d : dims) {
      if (d < 0) [[unlikely]]
        *this = of(std::vector<int>(dims));  // throws the negative-dimension fault
      dims_[rank_++] = d;
    }
    level_order_[0] = rank_;
    levels_ = rank_ ? 1 : 0;
  }
  static Shape of(const std::vector<int>& dims);
  // `outer` dimensions whose entries are blocks of shape `block`.
  static Shape blocked(const std::vector<int>& outer, const Shape& block);
  static Shape blocked(const int* outer, int count, const Shape& block);

  bool is_scalar() const { return levels_ == 0; }
  int levels() const { return levels_; }
  int rank() const { return rank_; }
  int order() const { return levels_ ? level_order_[0] : 0; }  // outer dimensions
  int level_order(int level) const { return level_order_[level]; }
  int dim(int i) const { return dims_[i]; }  // over all levels, outermost level first
  std::vector<int> outer_dims() const;
  // The shape of one block (a scalar shape when unblocked).
  Shape block() const;
  bool is_blocked() const { return levels_ > 1; }
  // Every level has the same order, so the tensor has a logical unblocked form.
  bool uniform() const;
  // The logical unblocked shape: dimension i is the product of dimension i of every level.
  Shape logical() const;

  size_t size() const {  // number of components
    size_t n = 1;
    for (int i = 0; i < rank_; ++i) n *= static_cast<size_t>(dims_[i]);
    return n;
  }
  size_t outer_count() const;  // number of blocks (components when unblocked)
  // Components of one block: the product of the inner levels' dimensions (not size() /
  // outer_count(), which divides by zero for a tensor over an empty set).
  size_t block_size() const {
    size_t n = 1;
    for (int i = levels_ ? level_order_[0] : 0; i < rank_; ++i) n *= static_cast<size_t>(dims_[i]);
    return n;
  }

  bool operator==(const Shape& o) const;
  bool operator!=(const Shape& o) const { return !(*this == o); }
  // e.g. "3x3", "2x2 of 3x3", "scalar"
  std::string str() const;

 private:
  std::array<int32_t, kMaxRank> dims_{};
  std::array<uint8_t, kMaxLevels> level_order_{};
  uint8_t rank_ = 0;
  uint8_t levels_ = 0;
};

}  // namespace simit::runtime
