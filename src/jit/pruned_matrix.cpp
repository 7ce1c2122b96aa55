// PrunedMatrix (jit/pruned_matrix.h): one pass over the values, copying the non-zero blocks.
#include "jit/pruned_matrix.h"

#include <algorithm>
#include <bit>
#include <functional>
#include <type_traits>

#include "runtime/system_ops.h"

namespace simit::jit {

namespace {

// Whether every component is +0.0 or -0.0: the bits but the sign, or-ed together, without a
// branch or a chain of floating-point additions per component (a NaN or an infinity has bits
// there, and the block is kept).
template <int N>
bool all_zero(const double* b) {
  uint64_t m = 0;
  for (int i = 0; i < N; ++i) m |= std::bit_cast<uint64_t>(b[i]);
  return (m << 1) == 0;
}

// Whether block `blk` (bs components) is all zero; n is the run-time size when N is 0.
template <int N>
bool zero_block(const double* blk, int bs) {
  if constexpr (N != 0) {
    return all_zero<N * N>(blk);
  } else {
    bool zero = true;
    for (int i = 0; i < bs && zero; ++i) zero = blk[i] == 0.0;
    return zero;
  }
}

// Sizes `v` to exactly n elements, giving its storage back first when it holds far more (a
// matrix on its full pattern the first call, on a specialised one after: jit/specialise.h).
template <class T>
void fit(std::vector<T>& v, size_t n) {
  if (v.capacity() > n + n / 4) std::vector<T>().swap(v);
  v.resize(n);
}

// Rows with N x N blocks; n is the run-time size when N is 0. Two passes over tasks of
// kRowsPerTask rows: the first counts each task's non-zero blocks, so that the arrays hold
// only those (on a first call, when the matrix is still on its full pattern, more than half
// of its blocks may be zero) and each task knows where its blocks go; the second copies each
// of them (by columns: a compiled product reads block column j as one vector), as binary32
// when T is float (false if a value is not one). The copy is the same whoever runs a task.
// Tasks of 512 rows, so that even a small matrix is copied by every thread, each its home
// share of the rows (jit/thread_pool.h), about the rows its share of the loop's products
// then reads: at 4,096 rows the fem bunny's 3,607 rows were one task, copied by the calling
// thread, and its solve on 2 threads took 3.5% longer (median of 6 interleaved runs).
constexpr size_t kRowsPerTask = 512;

// A matrix's blocks row by row, as stored: f(k, block) for each block k of row r (N x N
// blocks, N 0 when known only at run time).
struct StoredBlocks {
  static constexpr bool kBinary32 = false;  // whether every value is known to be binary32
  const int32_t* rp;
  const double* v;
  size_t bs;
  template <int N, class F>
  void row(size_t r, F&& f) const {
    for (int32_t k = rp[r]; k < rp[r + 1]; ++k) f(k, v + static_cast<size_t>(k) * bs);
  }
};

// A pending fused sum's blocks (runtime::LazySum), each summed as it is read. A float32 sum
// rounds every value to binary32 (Binary32 true): the copy's check of each is left out.
template <bool Binary32>
struct SummedBlocks {
  static constexpr bool kBinary32 = Binary32;
  const runtime::LazySum* sum;
  template <int N, class F>
  void row(size_t r, F&& f) const {
    sum->row<N * N>(static_cast<int32_t>(r), f);
  }
};

// Whether the values a task copies are binary32 values, by their bits: the bits rounding to
// binary32 changes, or-ed (branch-free: a comparison value by value with its NaN case made a
// refresh of 30,509 rows of 3 x 3 blocks take 1.23 ms rather than 1.14), and whether a NaN
// went by, whose payload the rounding may change though it counts as a binary32 value: then
// the task's rows are looked at value by value (rows_binary32).
struct Binary32Bits {
  uint64_t differ = 0;
  bool nan = false;
  void add(double x) {
    differ |= std::bit_cast<uint64_t>(static_cast<double>(static_cast<float>(x))) ^
              std::bit_cast<uint64_t>(x);
    nan = nan | (x != x);
  }
};

// Whether every value of rows [first, end) is a binary32 value, value by value.
template <int N, class Src>
bool rows_binary32(const Src& src, size_t first, size_t end, int bs) {
  bool all = true;
  for (size_t r = first; r < end; ++r)
    src.template row<N>(r, [&](int32_t, const double* blk) {
      for (int i = 0; i < bs; ++i) all = all && runtime::is_binary32(blk[i]);
    });
  return all;
}

// A task's verdict from its bits (rows [first, end) looked at again only for a NaN).
template <int N, class Src>
bool task_binary32(const Binary32Bits& bits, const Src& src, size_t first, size_t end, int bs) {
  if (bits.differ == 0) return true;
  return bits.nan && rows_binary32<N>(src, first, end, bs);
}

// Runs tasks 0 .. tasks-1, on the executor's threads when there are several.
void run_tasks(size_t tasks, const runtime::ForEachTask& for_each,
               const std::function<void(int64_t)>& task) {
  if (for_each && tasks > 1) {
    for_each(static_cast<int64_t>(tasks), task);
  } else {
    for (size_t t = 0; t < tasks; ++t) task(static_cast<int64_t>(t));
  }
}

template <int N, class T, class Src>
bool prune(PrunedMatrix& p, std::vector<T>& values, const int32_t* rp, const int32_t* ci,
           const Src& src, size_t rows, int n, const runtime::ForEachTask& for_each) {
  const int m = N ? N : n;
  const int bs = m * m;
  const size_t tasks = (rows + kRowsPerTask - 1) / kRowsPerTask;
  auto run = [&](const std::function<void(int64_t)>& task) { run_tasks(tasks, for_each, task); };
  std::vector<int32_t> first(tasks + 1, 0);  // each task's first kept block
  run([&](int64_t t) {
    int32_t kept = 0;
    const size_t end = std::min(rows, (static_cast<size_t>(t) + 1) * kRowsPerTask);
    for (size_t r = static_cast<size_t>(t) * kRowsPerTask; r < end; ++r)
      src.template row<N>(
          r, [&](int32_t, const double* blk) { kept += zero_block<N>(blk, bs) ? 0 : 1; });
    first[static_cast<size_t>(t) + 1] = kept;
  });
  for (size_t t = 0; t < tasks; ++t) first[t + 1] += first[t];
  const size_t nonzero = static_cast<size_t>(first[tasks]);
  fit(p.cols, nonzero);
  fit(values, nonzero * static_cast<size_t>(bs) +
                  (std::bit_ceil(static_cast<unsigned>(m)) - static_cast<unsigned>(m)));
  int32_t* cols = p.cols.data();
  T* out = values.data();
  p.slot.resize(static_cast<size_t>(rp[rows]));
  std::vector<uint8_t> exact(tasks, 1);
  p.row_ptr[0] = 0;
  run([&](int64_t t) {
    int32_t at = first[static_cast<size_t>(t)];
    Binary32Bits bits;
    const size_t begin = static_cast<size_t>(t) * kRowsPerTask;
    const size_t end = std::min(rows, begin + kRowsPerTask);
    for (size_t r = begin; r < end; ++r) {
      src.template row<N>(r, [&](int32_t k, const double* blk) {
        p.slot[static_cast<size_t>(k)] = -1;
        if (zero_block<N>(blk, bs)) return;
        p.slot[static_cast<size_t>(k)] = at;
        T* o = out + static_cast<size_t>(at) * bs;
        for (int j = 0; j < m; ++j)
          for (int i = 0; i < m; ++i) {
            const double x = blk[i * m + j];
            o[j * m + i] = static_cast<T>(x);
            // A NaN stays a NaN (its payload is not the interpreter's concern).
            if constexpr (std::is_same_v<T, float> && !Src::kBinary32) bits.add(x);
          }
        cols[at++] = ci[k];
      });
      p.row_ptr[r + 1] = at;
    }
    exact[static_cast<size_t>(t)] = task_binary32<N>(bits, src, begin, end, bs);
  });
  p.kept = static_cast<int64_t>(nonzero);
  return std::all_of(exact.begin(), exact.end(), [](uint8_t e) { return e != 0; });
}

// Rows in pairs, as binary32 (PrunedMatrix::pairs); N x N blocks, 2 <= N <= 4. The same two
// passes over tasks of kRowsPerTask rows (an even number, so that a task holds whole pairs).
template <int N, class Src>
bool prune_pairs(PrunedMatrix& p, const int32_t* rp, const int32_t* ci, const Src& src, size_t rows,
                 const runtime::ForEachTask& for_each) {
  constexpr int bs = N * N;
  static_assert(kRowsPerTask % 2 == 0);
  const size_t pairs = (rows + 1) / 2;
  const size_t tasks = (rows + kRowsPerTask - 1) / kRowsPerTask;
  auto run = [&](const std::function<void(int64_t)>& task) { run_tasks(tasks, for_each, task); };
  auto kept_in = [&](size_t r) {
    int32_t n = 0;
    if (r < rows)
      src.template row<N>(r,
                          [&](int32_t, const double* blk) { n += zero_block<N>(blk, bs) ? 0 : 1; });
    return n;
  };
  std::vector<int32_t> first(tasks + 1, 0);  // each task's first block pair
  std::vector<int64_t> kept(tasks, 0);
  run([&](int64_t t) {
    int32_t slots = 0;
    int64_t real = 0;
    const size_t end = std::min(rows, (static_cast<size_t>(t) + 1) * kRowsPerTask);
    for (size_t r = static_cast<size_t>(t) * kRowsPerTask; r < end; r += 2) {
      const int32_t a = kept_in(r), b = kept_in(r + 1);
      slots += std::max(a, b);
      real += a + b;
    }
    first[static_cast<size_t>(t) + 1] = slots;
    kept[static_cast<size_t>(t)] = real;
  });
  for (size_t t = 0; t < tasks; ++t) first[t + 1] += first[t];
  const auto slots = static_cast<size_t>(first[tasks]);
  constexpr int width = static_cast<int>(std::bit_ceil(static_cast<unsigned>(N)));
  fit(p.cols, 2 * slots);
  // The last pair's last column loads 2 width values from 2 N (N - 1).
  fit(p.values32, slots * 2 * bs + static_cast<size_t>(2 * (width - N)));
  std::fill(p.values32.begin() + static_cast<std::ptrdiff_t>(slots * 2 * bs), p.values32.end(),
            0.0f);
  p.row_ptr.resize(pairs + 1);
  p.row_ptr[0] = 0;
  p.slot.resize(static_cast<size_t>(rp[rows]));
  std::vector<uint8_t> exact(tasks, 1);
  run([&](int64_t t) {
    int32_t at = first[static_cast<size_t>(t)];
    Binary32Bits bits;
    const size_t begin = static_cast<size_t>(t) * kRowsPerTask;
    const size_t end = std::min(rows, begin + kRowsPerTask);
    float* values = p.values32.data();
    int32_t* cols = p.cols.data();
    for (size_t r = begin; r < end; r += 2) {
      // Each row's kept blocks into its side of the pairs from `at`, then the shorter row's
      // padding.
      int32_t length[2] = {0, 0};
      for (int side = 0; side < 2 && r + static_cast<size_t>(side) < rows; ++side) {
        const size_t row = r + static_cast<size_t>(side);
        int32_t s = at;
        src.template row<N>(row, [&](int32_t k, const double* blk) {
          p.slot[static_cast<size_t>(k)] = -1;
          if (zero_block<N>(blk, bs)) return;
          p.slot[static_cast<size_t>(k)] = 2 * s + side;
          float* o = values + static_cast<size_t>(s) * 2 * bs + side * N;
          for (int j = 0; j < N; ++j)
            for (int i = 0; i < N; ++i) {
              const double x = blk[i * N + j];
              o[j * 2 * N + i] = static_cast<float>(x);
              if constexpr (!Src::kBinary32) bits.add(x);
            }
          cols[2 * static_cast<size_t>(s) + static_cast<size_t>(side)] = ci[k];
          ++s;
        });
        length[side] = s - at;
      }
      const int32_t pairs_here = std::max(length[0], length[1]);
      for (int side = 0; side < 2; ++side) {
        const int32_t col =
            length[side] > 0
                ? cols[2 * static_cast<size_t>(at + length[side] - 1) + static_cast<size_t>(side)]
                : 0;
        for (int32_t s = at + length[side]; s < at + pairs_here; ++s) {
          float* o = values + static_cast<size_t>(s) * 2 * bs + side * N;
          for (int j = 0; j < N; ++j)
            for (int i = 0; i < N; ++i) o[j * 2 * N + i] = 0.0f;
          cols[2 * static_cast<size_t>(s) + static_cast<size_t>(side)] = col;
        }
      }
      at += pairs_here;
      p.row_ptr[r / 2 + 1] = at;
    }
    exact[static_cast<size_t>(t)] = task_binary32<N>(bits, src, begin, end, bs);
  });
  p.kept = 0;
  for (int64_t n : kept) p.kept += n;
  return std::all_of(exact.begin(), exact.end(), [](uint8_t e) { return e != 0; });
}

template <int N, class Src>
bool prune_into(PrunedMatrix& p, bool single, const int32_t* rp, const int32_t* ci, const Src& src,
                size_t rows, int n, const runtime::ForEachTask& for_each) {
  if (single) {
    std::vector<double>().swap(p.values);
    return prune<N>(p, p.values32, rp, ci, src, rows, n, for_each);
  }
  std::vector<float>().swap(p.values32);
  return prune<N>(p, p.values, rp, ci, src, rows, n, for_each);
}

// The values of `src` into the layout the last build made (PrunedMatrix::slot), in one pass: a
// block the build kept is copied to its slot (zero or not: a zero block adds +-0, as a padding
// block does), and a block it dropped must still be zero. False in `still` when one is not
// (the layout must be rebuilt); the result says whether every value is a binary32 value, as
// for a build.
template <int N, class T, bool Pairs, class Src>
bool refresh(PrunedMatrix& p, std::vector<T>& values, const Src& src, size_t rows, int n,
             const runtime::ForEachTask& for_each, bool& still) {
  const int m = N ? N : n;
  const int bs = m * m;
  const size_t tasks = (rows + kRowsPerTask - 1) / kRowsPerTask;
  std::vector<uint8_t> exact(tasks, 1), kept(tasks, 1);
  T* out = values.data();
  const int32_t* slot = p.slot.data();
  run_tasks(tasks, for_each, [&](int64_t t) {
    Binary32Bits bits;
    bool same = true;
    const size_t begin = static_cast<size_t>(t) * kRowsPerTask;
    const size_t end = std::min(rows, begin + kRowsPerTask);
    for (size_t r = begin; r < end; ++r)
      src.template row<N>(r, [&](int32_t k, const double* blk) {
        const int32_t s = slot[k];
        if (s < 0) {
          same = same && zero_block<N>(blk, bs);
          return;
        }
        // Pairs: slot 2 q + side, the block's column j at 2 bs q + 2 m j + m side.
        T* o = Pairs ? out + static_cast<size_t>(s / 2) * 2 * bs + (s % 2) * m
                     : out + static_cast<size_t>(s) * bs;
        const int stride = Pairs ? 2 * m : m;
        for (int j = 0; j < m; ++j)
          for (int i = 0; i < m; ++i) {
            const double x = blk[i * m + j];
            o[j * stride + i] = static_cast<T>(x);
            if constexpr (std::is_same_v<T, float> && !Src::kBinary32) bits.add(x);
          }
      });
    exact[static_cast<size_t>(t)] = task_binary32<N>(bits, src, begin, end, bs);
    kept[static_cast<size_t>(t)] = same;
  });
  still = std::all_of(kept.begin(), kept.end(), [](uint8_t e) { return e != 0; });
  return std::all_of(exact.begin(), exact.end(), [](uint8_t e) { return e != 0; });
}

template <int N, class Src>
bool refresh_into(PrunedMatrix& p, const Src& src, size_t rows, int n,
                  const runtime::ForEachTask& for_each, bool& still) {
  if (p.pairs) return refresh<N, float, true>(p, p.values32, src, rows, n, for_each, still);
  if (p.single) return refresh<N, float, false>(p, p.values32, src, rows, n, for_each, still);
  return refresh<N, double, false>(p, p.values, src, rows, n, for_each, still);
}

// PrunedMatrix::assign from `src`, the blocks of a matrix on `pattern` with n x n blocks.
template <class Src>
bool assign_from(PrunedMatrix& p, const runtime::PatternPtr& pattern, int n, bool single,
                 bool want_pairs, const Src& src, const runtime::ForEachTask& for_each) {
  const auto& rp = pattern->row_ptr();
  const int32_t* ci = pattern->col_idx().data();
  const size_t rows = rp.size() - 1;
  // The same pattern, block and layout as the last build: one pass over the values.
  if (p.built_for == pattern && p.built_block == n && p.single == single && p.pairs == want_pairs &&
      !p.slot.empty()) {
    bool still = true, exact = true;
    switch (n) {
      case 1: exact = refresh_into<1>(p, src, rows, n, for_each, still); break;
      case 2: exact = refresh_into<2>(p, src, rows, n, for_each, still); break;
      case 3: exact = refresh_into<3>(p, src, rows, n, for_each, still); break;
      default: exact = refresh_into<0>(p, src, rows, n, for_each, still);
    }
    if (still) {
      ++p.refreshed;
      return exact;
    }
  }
  p.built_for = pattern;
  p.built_block = n;
  p.single = single;
  p.pairs = want_pairs;
  if (p.pairs) {
    std::vector<double>().swap(p.values);
    switch (n) {
      case 2: return prune_pairs<2>(p, rp.data(), ci, src, rows, for_each);
      case 3: return prune_pairs<3>(p, rp.data(), ci, src, rows, for_each);
      default: return prune_pairs<4>(p, rp.data(), ci, src, rows, for_each);
    }
  }
  p.row_ptr.resize(rp.size());
  switch (n) {
    case 1: return prune_into<1>(p, single, rp.data(), ci, src, rows, n, for_each);
    case 2: return prune_into<2>(p, single, rp.data(), ci, src, rows, n, for_each);
    case 3: return prune_into<3>(p, single, rp.data(), ci, src, rows, n, for_each);
    default: return prune_into<0>(p, single, rp.data(), ci, src, rows, n, for_each);
  }
}

}  // namespace

bool PrunedMatrix::assign(const runtime::SystemMatrix& m, bool single,
                          const runtime::ForEachTask& for_each, bool in_pairs,
                          const runtime::LazySum* sum) {
  total = m.pattern().nnz();
  const int n = m.block_rows();
  const bool want_pairs = single && in_pairs && n >= 2 && n <= 4 && m.block_cols() == n;
  // A pending sum's values are read through it: m.values() would write the sum into them.
  if (sum && sum->float32())
    return assign_from(*this, m.shared_pattern(), n, single, want_pairs, SummedBlocks<true>{sum},
                       for_each);
  if (sum)
    return assign_from(*this, m.shared_pattern(), n, single, want_pairs, SummedBlocks<false>{sum},
                       for_each);
  const StoredBlocks stored{m.pattern().row_ptr().data(), m.values(),
                            static_cast<size_t>(m.block_size())};
  return assign_from(*this, m.shared_pattern(), n, single, want_pairs, stored, for_each);
}

}  // namespace simit::jit
