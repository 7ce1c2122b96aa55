// Solver loops' products two rows at a time: under --float32 on the CPU, a product reads the
// binary32 copy of its matrix in pairs of rows (PrunedMatrix::pairs), and each row's sums
// fill half of one vector of binary32 lanes, so that one instruction computes both rows'
// terms of a block column (jit/llvm/emitter.h, docs/jit.md).
#include <bit>

#include "jit/llvm/emitter.h"
#include "jit/pruned_matrix.h"
#include "runtime/blocked_sum.h"

namespace simit::jit::codegen {

bool SystemEmitter::products_in_pairs(const VectorOp& op) const {
  return rows_in_pairs(st_, slots_[static_cast<size_t>(op.values)], op.block);
}

// Rows r and r + 1 (r an even i64) of arrays[y] = matrix * arrays[x], then the op's body for
// each component of row r and then of row r + 1 (when r + 1 < rows), their sums' runs added
// to lanes `lane` and `lane` + 1 (null: no sums). Each row's sum is the one spmv_row adds:
// block by block in the row's order, a block's part its columns' terms added in turn; the
// padding blocks add +-0 (PrunedMatrix::pairs). The op's body may not write the product's
// operands (fuse_passes), so running row r's body after row r + 1's product changes nothing.
void SystemEmitter::spmv_pair(const VectorOp& op, Value* r, Value* rows, Value* lane) {
  const int n = op.block;
  const int w = static_cast<int>(std::bit_ceil(static_cast<unsigned>(n)));
  llvm::Type* i64 = b_.getInt64Ty();
  llvm::Type* f32 = b_.getFloatTy();
  llvm::Type* f64 = b_.getDoubleTy();
  auto* half = llvm::FixedVectorType::get(f32, static_cast<unsigned>(w));
  auto* vec = llvm::FixedVectorType::get(f32, static_cast<unsigned>(2 * w));
  auto* vec64 = llvm::FixedVectorType::get(f64, static_cast<unsigned>(2 * w));
  const bool single_x = slots_[static_cast<size_t>(op.x)].single;
  Value* sums;
  {
    llvm::IRBuilder<> entry(&fn_->getEntryBlock(), fn_->getEntryBlock().begin());
    sums = entry.CreateAlloca(vec);
  }
  b_.CreateStore(llvm::ConstantFP::get(vec, 0.0), sums);
  auto load_i32 = [&](int slot, Value* at) {
    return b_.CreateSExt(
        b_.CreateLoad(b_.getInt32Ty(), b_.CreateInBoundsGEP(b_.getInt32Ty(), arrays_[slot], at)),
        i64);
  };
  Value* q = b_.CreateLShr(r, b_.getInt64(1));
  Value* lo = load_i32(op.row_ptr, q);
  Value* hi = load_i32(op.row_ptr, b_.CreateAdd(q, b_.getInt64(1)));
  // Lanes 0 .. w-1 of a pair's column hold row r's n values, lanes w .. 2w-1 row r + 1's.
  std::vector<int> spread;
  for (int side = 0; side < 2; ++side)
    for (int i = 0; i < w; ++i) spread.push_back(i < n ? side * n + i : -1);
  loop(lo, hi, [&](Value* k) {
    Value* xc[2];
    for (int side = 0; side < 2; ++side)
      xc[side] = b_.CreateMul(
          load_i32(op.cols, b_.CreateAdd(b_.CreateMul(k, b_.getInt64(2)), b_.getInt64(side))),
          b_.getInt64(n));
    // Both columns' x: n components each, read by a masked load (the lanes past n are not
    // read, so the last element's needs no padding after it).
    Value* xs = nullptr;
    if (single_x) {
      std::vector<llvm::Constant*> bits;
      for (int i = 0; i < w; ++i) bits.push_back(b_.getInt1(i < n));
      Value* mask = llvm::ConstantVector::get(bits);
      Value* part_x[2];
      for (int side = 0; side < 2; ++side)
        part_x[side] = b_.CreateMaskedLoad(half, b_.CreateInBoundsGEP(f32, arrays_[op.x], xc[side]),
                                           llvm::Align(4), mask, llvm::ConstantFP::get(half, 0.0));
      std::vector<int> both;
      for (int i = 0; i < 2 * w; ++i) both.push_back(i);
      xs = b_.CreateShuffleVector(part_x[0], part_x[1], both);
    }
    Value* blk = b_.CreateMul(k, b_.getInt64(2 * n * n));
    Value* part = nullptr;
    for (int j = 0; j < n; ++j) {
      llvm::LoadInst* column = b_.CreateLoad(
          vec,
          b_.CreateInBoundsGEP(f32, arrays_[op.values], b_.CreateAdd(blk, b_.getInt64(2 * n * j))));
      column->setAlignment(llvm::Align(4));
      Value* a = n == w ? static_cast<Value*>(column) : b_.CreateShuffleVector(column, spread);
      Value* term;
      if (single_x) {
        std::vector<int> at_j;
        for (int side = 0; side < 2; ++side)
          for (int i = 0; i < w; ++i) at_j.push_back(side * w + j);
        term = b_.CreateFMul(a, b_.CreateShuffleVector(xs, at_j));
      } else {
        // A binary64 vector: the product in binary64, rounded (as spmv_row computes it).
        Value* x = llvm::PoisonValue::get(vec64);
        for (int side = 0; side < 2; ++side) {
          Value* c = load_component(op.x, b_.CreateAdd(xc[side], b_.getInt64(j)));
          for (int i = 0; i < w; ++i)
            x = b_.CreateInsertElement(x, c, static_cast<uint64_t>(side * w + i));
        }
        term = b_.CreateFPTrunc(b_.CreateFMul(b_.CreateFPExt(a, vec64), x), vec);
      }
      part = part ? b_.CreateFAdd(part, term) : term;
    }
    b_.CreateStore(b_.CreateFAdd(b_.CreateLoad(vec, sums), part), sums);
  });
  Value* total = b_.CreateLoad(vec, sums);
  const bool single_y = slots_[static_cast<size_t>(op.y)].single;
  auto finish_row = [&](int side, Value* row_lane) {
    Value* row = b_.CreateMul(b_.CreateAdd(r, b_.getInt64(side)), b_.getInt64(n));
    for (int i = 0; i < n; ++i) {
      Value* at = b_.CreateAdd(row, b_.getInt64(i));
      Value* sum = b_.CreateExtractElement(total, static_cast<uint64_t>(side * w + i));
      if (single_y)
        b_.CreateStore(sum, b_.CreateInBoundsGEP(f32, arrays_[op.y], at));
      else
        store_component(op.y, at, b_.CreateFPExt(sum, f64));
    }
    run_of(op, row, n, row_lane);
  };
  finish_row(0, lane);
  auto* second = llvm::BasicBlock::Create(ctx_, "pair.second", fn_);
  auto* done = llvm::BasicBlock::Create(ctx_, "pair.done", fn_);
  b_.CreateCondBr(b_.CreateICmpSLT(b_.CreateAdd(r, b_.getInt64(1)), rows), second, done);
  b_.SetInsertPoint(second);
  finish_row(1, lane ? b_.CreateAdd(lane, b_.getInt64(1)) : nullptr);
  b_.CreateBr(done);
  b_.SetInsertPoint(done);
}

// arrays[y] = matrix * arrays[x] in pairs of rows. Chunks and the threads' units of rows
// start at multiples of runtime::kSumChunk (even), so a pair never straddles two of them.
void SystemEmitter::spmv_pairs(const VectorOp& op, const std::vector<Value*>& sizes) {
  static_assert(runtime::kSumChunk % 2 == 0 && runtime::kSumLanes % 2 == 0);
  Value* rows = sizes[op.rows];
  auto in_pairs = [&](Value* begin, Value* end, Value* chunk_begin) {
    Value* first = b_.CreateLShr(begin, b_.getInt64(1));
    Value* last = b_.CreateLShr(b_.CreateAdd(end, b_.getInt64(1)), b_.getInt64(1));
    loop(first, last, [&](Value* q) {
      Value* r = b_.CreateShl(q, b_.getInt64(1));
      spmv_pair(op, r, rows, chunk_begin ? lane_of(b_.CreateSub(r, chunk_begin)) : nullptr);
    });
  };
  if (op.sums.empty()) {
    const auto [lo, hi] = unit_range(rows, static_cast<int64_t>(runtime::kSumChunk));
    return in_pairs(lo, hi, nullptr);
  }
  chunked(op, rows, [&](Value* begin, Value* end) { in_pairs(begin, end, begin); });
}

}  // namespace simit::jit::codegen
