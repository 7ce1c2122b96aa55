// Shapes of dense and blocked tensors.
#include "runtime/shape.h"

#include "runtime/fault.h"

namespace simit::runtime {

namespace {

void check_rank(size_t rank, size_t levels) {
  if (rank > static_cast<size_t>(Shape::kMaxRank) ||
      levels > static_cast<size_t>(Shape::kMaxLevels))
    throw Fault("tensors of more than " + std::to_string(Shape::kMaxRank) + " dimensions or " +
                std::to_string(Shape::kMaxLevels) + " blocking levels are not supported");
}

std::string dims_text(const Shape& s) {
  std::string text;
  for (int i = 0; i < s.rank(); ++i) text += (i ? "x" : "") + std::to_string(s.dim(i));
  return text;
}

void check_dim(int d) {
  if (d < 0) throw Fault("negative tensor dimension " + std::to_string(d));
}

// A backstop for shapes built at run time (the type checker bounds those written in a
// program): the component count must not wrap around size_t.
void check_size(const Shape& s) {
  constexpr size_t kLimit = size_t{1} << 48;
  size_t n = 1;
  for (int i = 0; i < s.rank(); ++i) {
    const auto d = static_cast<size_t>(s.dim(i));
    if (d != 0 && n > kLimit / d)
      throw Fault("a tensor with dimensions of sizes " + dims_text(s) + " is too large");
    n *= d;
  }
}

}  // namespace

Shape Shape::of(const std::vector<int>& dims) { return blocked(dims, Shape()); }

Shape Shape::blocked(const std::vector<int>& outer, const Shape& block) {
  return blocked(outer.data(), static_cast<int>(outer.size()), block);
}

Shape Shape::blocked(const int* outer, int count, const Shape& block) {
  if (count == 0) return block;
  check_rank(static_cast<size_t>(count) + block.rank_, 1u + block.levels_);
  Shape s;
  for (int i = 0; i < count; ++i) {
    check_dim(outer[i]);
    s.dims_[s.rank_++] = outer[i];
  }
  for (int i = 0; i < block.rank_; ++i) s.dims_[s.rank_++] = block.dims_[i];
  check_size(s);
  s.level_order_[0] = static_cast<uint8_t>(count);
  for (int l = 0; l < block.levels_; ++l) s.level_order_[l + 1] = block.level_order_[l];
  s.levels_ = static_cast<uint8_t>(block.levels_ + 1);
  return s;
}

std::vector<int> Shape::outer_dims() const {
  return std::vector<int>(dims_.begin(), dims_.begin() + order());
}

Shape Shape::block() const {
  Shape s;
  if (levels_ <= 1) return s;
  int skip = order();
  for (int i = skip; i < rank_; ++i) s.dims_[s.rank_++] = dims_[i];
  for (int l = 1; l < levels_; ++l) s.level_order_[l - 1] = level_order_[l];
  s.levels_ = static_cast<uint8_t>(levels_ - 1);
  return s;
}

bool Shape::uniform() const {
  for (int l = 1; l < levels_; ++l)
    if (level_order_[l] != level_order_[0]) return false;
  return true;
}

Shape Shape::logical() const {
  if (levels_ <= 1) return *this;
  if (!uniform()) throw Fault("a tensor whose blocks differ in order has no unblocked form");
  std::vector<int> dims(order(), 1);
  for (int l = 0, base = 0; l < levels_; base += level_order_[l], ++l)
    for (int i = 0; i < order(); ++i) dims[i] *= dims_[base + i];
  return of(dims);
}

size_t Shape::outer_count() const {
  size_t n = 1;
  for (int i = 0; i < order(); ++i) n *= static_cast<size_t>(dims_[i]);
  return n;
}

bool Shape::operator==(const Shape& o) const {
  if (rank_ != o.rank_ || levels_ != o.levels_) return false;
  for (int i = 0; i < rank_; ++i)
    if (dims_[i] != o.dims_[i]) return false;
  for (int l = 0; l < levels_; ++l)
    if (level_order_[l] != o.level_order_[l]) return false;
  return true;
}

std::string Shape::str() const {
  if (levels_ == 0) return "scalar";
  std::string out;
  for (int l = 0, i = 0; l < levels_; ++l) {
    if (l > 0) out += " of ";
    for (int k = 0; k < level_order_[l]; ++k, ++i) {
      if (k > 0) out += "x";
      out += std::to_string(dims_[i]);
    }
  }
  return out;
}

}  // namespace simit::runtime
