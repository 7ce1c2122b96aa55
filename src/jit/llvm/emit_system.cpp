// Solver loops: a system trace's vector operations as loops, the sparse products over the
// solver's column copy, and the passes with sums in the blocked order (jit/llvm/emitter.h).
#include <algorithm>
#include <bit>
#include <functional>

#include <llvm/IR/MDBuilder.h>

#include "jit/llvm/emitter.h"
#include "jit/target.h"
#include "jit/tunables.h"
#include "runtime/blocked_sum.h"
#include "runtime/system_ops.h"

namespace simit::jit::codegen {

// One op of a system trace. A product runs row block by row block: each component's sum
// over the row's blocks in pattern order, then the fused body for each component of the row.
// An op with sums (inner products) runs its elements chunk by chunk (chunked).
void SystemEmitter::vector_op(const VectorOp& op, const std::vector<Value*>& sizes) {
  switch (op.kind) {
    case VectorOp::Kind::Scalar: return block(op.body);
    case VectorOp::Kind::Pass:
      if (!op.sums.empty()) {
        const int g = op.group;
        Value* elements = b_.CreateSDiv(sizes[op.length], b_.getInt64(g));
        return chunked(op, elements, [&](Value* begin, Value* end) {
          Value* rest = begin;
          if (pass_in_lanes(op)) {
            // Four runs at a time in vectors, into four neighbouring lanes (a chunk starts
            // at a multiple of four runs); the runs left over one by one.
            Value* quads = b_.CreateSDiv(b_.CreateSub(end, begin), b_.getInt64(kLanes));
            loop(b_.getInt64(0), quads, [&](Value* q) {
              Value* offset = b_.CreateMul(q, b_.getInt64(kLanes));
              runs_in_lanes(op, b_.CreateMul(b_.CreateAdd(begin, offset), b_.getInt64(g)),
                            lane_of(offset));
            });
            rest = b_.CreateAdd(begin, b_.CreateMul(quads, b_.getInt64(kLanes)));
          }
          loop(rest, end, [&](Value* e) {
            run_of(op, b_.CreateMul(e, b_.getInt64(g)), g, lane_of(b_.CreateSub(e, begin)));
          });
        });
      }
      {
        const auto [lo, hi] = unit_range(sizes[op.length], pass_unit(op));
        return loop(b_.CreateTrunc(lo, b_.getInt32Ty()), b_.CreateTrunc(hi, b_.getInt32Ty()),
                    [&](Value* k) {
                      element_ = k;
                      block(op.body);
                    });
      }
    case VectorOp::Kind::SpMV: return spmv(op, sizes);
  }
}

// The lane of the element `offset` (an i64) elements after its chunk's first.
Value* SystemEmitter::lane_of(Value* offset) {
  return b_.CreateAnd(offset, b_.getInt64(static_cast<int64_t>(runtime::kSumLanes - 1)));
}

// An op's elements 0 .. elements - 1 (an i64) chunk by chunk, in the blocked order of
// runtime/blocked_sum.h (docs/arithmetic.md, "Sums"): per chunk, each sum's kSumLanes lane
// accumulators start at +0.0, work(begin, end) runs the chunk's elements (run_of and
// runs_in_lanes add each element's part to its lane), the halving tree folds the lanes into
// the chunk's partial, and the partial is added to the sum: s = s + P_0 + P_1 + ... One
// chunk's work touches its own elements' components and its lanes only, so it could run
// apart from the other chunks' as long as the partials are added in chunk order.
void SystemEmitter::chunked(const VectorOp& op, Value* elements,
                            const std::function<void(Value*, Value*)>& work) {
  llvm::Type* f64 = b_.getDoubleTy();
  constexpr unsigned kWidth = runtime::kSumLanes;
  auto* all_lanes = llvm::FixedVectorType::get(f64, kWidth);
  llvm::AllocaInst* lanes;
  {
    llvm::IRBuilder<> entry(&fn_->getEntryBlock(), fn_->getEntryBlock().begin());
    lanes = entry.CreateAlloca(llvm::ArrayType::get(f64, kWidth * op.sums.size()));
    lanes->setAlignment(llvm::Align(32));
  }
  Value* outer = lanes_;
  lanes_ = lanes;
  const auto chunk = static_cast<int64_t>(runtime::kSumChunk);
  Value* chunks = b_.CreateSDiv(b_.CreateAdd(elements, b_.getInt64(chunk - 1)), b_.getInt64(chunk));
  // An outlined op runs the chunks of its units and leaves each chunk's partials in the
  // partials array; the caller adds them to the sums in chunk order (emit_parallel.cpp).
  const auto [first, last] = unit_range(chunks, 1);
  loop(first, last, [&](Value* c) {
    Value* begin = b_.CreateMul(c, b_.getInt64(chunk));
    Value* next = b_.CreateAdd(begin, b_.getInt64(chunk));
    Value* end = b_.CreateSelect(b_.CreateICmpSLT(next, elements), next, elements);
    std::vector<Value*> totals;
    for (size_t k = 0; k < op.sums.size(); ++k) {
      b_.CreateAlignedStore(llvm::ConstantFP::get(all_lanes, 0.0), lane_at(k, b_.getInt64(0)),
                            llvm::Align(32));
      // The sum so far: its local holds each run's part while the chunk's work runs.
      totals.push_back(b_.CreateLoad(f64, locals_[op.sums[k]]));
    }
    work(begin, end);
    for (size_t k = 0; k < op.sums.size(); ++k) {
      Value* a = b_.CreateAlignedLoad(all_lanes, lane_at(k, b_.getInt64(0)), llvm::Align(32));
      for (unsigned w = kWidth / 2; w >= 1; w /= 2) {
        std::vector<int> low(w), high(w);
        for (unsigned i = 0; i < w; ++i) {
          low[i] = static_cast<int>(i);
          high[i] = static_cast<int>(i + w);
        }
        a = b_.CreateFAdd(b_.CreateShuffleVector(a, low), b_.CreateShuffleVector(a, high));
      }
      Value* partial = b_.CreateExtractElement(a, uint64_t{0});
      if (outlined_) {
        Value* at = b_.CreateAdd(b_.CreateMul(c, b_.getInt64(static_cast<int64_t>(op.sums.size()))),
                                 b_.getInt64(static_cast<int64_t>(k)));
        b_.CreateStore(partial, b_.CreateInBoundsGEP(f64, outlined_->partials, at));
        continue;
      }
      b_.CreateStore(b_.CreateFAdd(totals[k], partial), locals_[op.sums[k]]);
    }
  });
  lanes_ = outer;
}

// Lane `lane` (an i64) of sum k's accumulators in the chunk being emitted.
Value* SystemEmitter::lane_at(size_t k, Value* lane) {
  return b_.CreateInBoundsGEP(
      b_.getDoubleTy(), lanes_,
      b_.CreateAdd(b_.getInt64(static_cast<int64_t>(k * runtime::kSumLanes)), lane));
}

Value* SystemEmitter::load_component(int slot, Value* k) {
  const ArraySlot& a = slots_[static_cast<size_t>(slot)];
  Value* v = b_.CreateLoad(storage(a), b_.CreateInBoundsGEP(storage(a), arrays_[slot], k));
  return a.single ? b_.CreateFPExt(v, b_.getDoubleTy()) : v;
}

void SystemEmitter::store_component(int slot, Value* k, Value* v) {
  const ArraySlot& a = slots_[static_cast<size_t>(slot)];
  if (a.single) v = b_.CreateFPTrunc(v, b_.getFloatTy());
  b_.CreateStore(v, b_.CreateInBoundsGEP(storage(a), arrays_[slot], k));
}

// Row block r (an i64) of arrays[y] = matrix * arrays[x]; then the op's body for each
// component of the row, its sums' run part added to lane `lane` (null: no sums).
void SystemEmitter::spmv_row(const VectorOp& op, Value* r, Value* lane) {
  const int bs = op.block;
  llvm::Type* i64 = b_.getInt64Ty();
  llvm::Type* f64 = b_.getDoubleTy();
  // The row's bs sums are the lanes of one vector: block column j (stored contiguously,
  // the controller transposes the blocks) times x_j, summed over j lane by lane, is the
  // block's part, added to the row's sums (docs/arithmetic.md). The part needs no +0.0
  // start: a row sum starts at +0.0 and so is never -0.0, and a part that differs only
  // in the sign of a zero then adds the same.
  // Each column is read as one vector of `width` lanes (a power of two): a 3 x 3 block's
  // column j is loaded with the next block's first value (or the copy's padding, see
  // PrunedMatrix) in lane 3, which is computed and never read, so a load is one
  // instruction rather than three.
  const unsigned width = std::bit_ceil(static_cast<unsigned>(bs));
  auto* vec64 = llvm::FixedVectorType::get(f64, width);
  auto* vec32 = llvm::FixedVectorType::get(b_.getFloatTy(), width);
  const bool single = slots_[static_cast<size_t>(op.values)].single;
  const bool single_x = slots_[static_cast<size_t>(op.x)].single;
  // Under --float32 every product and addition of a row's sum rounds to binary32
  // (runtime::multiply): computed in binary32 where both factors are binary32 values (the
  // binary32 copy of the matrix, a binary32 vector), else in binary64 and rounded.
  const bool sums32 = st_.float32;
  auto* vec = sums32 ? vec32 : vec64;
  Value* sums;
  {
    llvm::IRBuilder<> entry(&fn_->getEntryBlock(), fn_->getEntryBlock().begin());
    sums = entry.CreateAlloca(vec);
  }
  b_.CreateStore(llvm::ConstantFP::get(vec, 0.0), sums);
  Value* lo = b_.CreateSExt(
      b_.CreateLoad(b_.getInt32Ty(), b_.CreateInBoundsGEP(b_.getInt32Ty(), arrays_[op.row_ptr], r)),
      i64);
  Value* hi = b_.CreateSExt(
      b_.CreateLoad(b_.getInt32Ty(), b_.CreateInBoundsGEP(b_.getInt32Ty(), arrays_[op.row_ptr],
                                                          b_.CreateAdd(r, b_.getInt64(1)))),
      i64);
  loop(lo, hi, [&](Value* k) {
    Value* col = b_.CreateSExt(
        b_.CreateLoad(b_.getInt32Ty(), b_.CreateInBoundsGEP(b_.getInt32Ty(), arrays_[op.cols], k)),
        i64);
    Value* blk = b_.CreateMul(k, b_.getInt64(bs * bs));
    Value* xc = b_.CreateMul(col, b_.getInt64(bs));
    Value* part = nullptr;
    for (int j = 0; j < bs; ++j) {
      Value* a;
      if (st_.matrices_in_place) {
        // The matrix's own blocks are row-major: column j is every bs-th value, and the
        // lanes past bs stay zero (their sums are never read).
        a = llvm::ConstantFP::get(vec64, 0.0);
        for (int i = 0; i < bs; ++i)
          a = b_.CreateInsertElement(
              a,
              b_.CreateLoad(f64, b_.CreateInBoundsGEP(f64, arrays_[op.values],
                                                      b_.CreateAdd(blk, b_.getInt64(i * bs + j)))),
              static_cast<uint64_t>(i));
      } else if (single) {
        // Under float32 the copy holds binary32 values: half the bytes.
        llvm::LoadInst* column =
            b_.CreateLoad(vec32, b_.CreateInBoundsGEP(b_.getFloatTy(), arrays_[op.values],
                                                      b_.CreateAdd(blk, b_.getInt64(j * bs))));
        column->setAlignment(llvm::Align(4));
        a = sums32 ? column : b_.CreateFPExt(column, vec64);
      } else {
        llvm::LoadInst* column = b_.CreateLoad(
            vec64,
            b_.CreateInBoundsGEP(f64, arrays_[op.values], b_.CreateAdd(blk, b_.getInt64(j * bs))));
        column->setAlignment(llvm::Align(8));
        a = column;
      }
      Value* x_at = b_.CreateAdd(xc, b_.getInt64(j));
      Value* term;
      if (sums32 && single && single_x && !st_.matrices_in_place) {
        Value* x = b_.CreateLoad(b_.getFloatTy(),
                                 b_.CreateInBoundsGEP(b_.getFloatTy(), arrays_[op.x], x_at));
        term = b_.CreateFMul(a, b_.CreateVectorSplat(width, x));
      } else {
        if (a->getType() != vec64) a = b_.CreateFPExt(a, vec64);
        term = b_.CreateFMul(a, b_.CreateVectorSplat(width, load_component(op.x, x_at)));
        if (sums32) term = b_.CreateFPTrunc(term, vec32);
      }
      part = part ? b_.CreateFAdd(part, term) : term;
    }
    b_.CreateStore(b_.CreateFAdd(b_.CreateLoad(vec, sums), part), sums);
  });
  Value* row = b_.CreateMul(r, b_.getInt64(bs));
  Value* total = b_.CreateLoad(vec, sums);
  const bool single_y = slots_[static_cast<size_t>(op.y)].single;
  for (int i = 0; i < bs; ++i) {
    Value* at = b_.CreateAdd(row, b_.getInt64(i));
    Value* sum = b_.CreateExtractElement(total, static_cast<uint64_t>(i));
    // A binary32 sum into a binary32 vector is stored as it is (no widening and narrowing
    // again, which LLVM does not fold through the extraction).
    if (sums32 && single_y)
      b_.CreateStore(sum, b_.CreateInBoundsGEP(b_.getFloatTy(), arrays_[op.y], at));
    else
      store_component(op.y, at, sums32 ? b_.CreateFPExt(sum, f64) : sum);
  }
  run_of(op, row, bs, lane);
}

// arrays[y] = matrix * arrays[x], row block by row block; then the op's body for each
// component of the row just computed.
void SystemEmitter::spmv(const VectorOp& op, const std::vector<Value*>& sizes) {
  if (products_in_pairs(op)) return spmv_pairs(op, sizes);
  if (op.sums.empty()) {
    const auto [lo, hi] = unit_range(sizes[op.rows], static_cast<int64_t>(runtime::kSumChunk));
    return loop(lo, hi, [&](Value* r) { spmv_row(op, r, nullptr); });
  }
  // A reduction fused into the product: a row block is one element of its sums.
  chunked(op, sizes[op.rows], [&](Value* begin, Value* end) {
    loop(begin, end, [&](Value* r) { spmv_row(op, r, lane_of(b_.CreateSub(r, begin))); });
  });
}

// Under --float32 an operator's value is rounded to binary32, so a local that an op sets to
// one (round32(...)), to a binary32 constant or to such a local holds a binary32 value until
// it is set again; the ops after it in the same list read it as one. Within one op, the
// locals it sets count as wide: the op decides them. A list starts with no local known: the
// loop's body, for one, is entered from its previous iteration as well.
bool SystemEmitter::holds_binary32(const Expr& e) const {
  switch (e.kind) {
    case ExprKind::Unary: return static_cast<UnOp>(e.op) == UnOp::Round32;
    case ExprKind::Const: return e.ty == Ty::F64 && runtime::is_binary32(e.f);
    case ExprKind::Local: return e.ty == Ty::F64 && binary32_local(e.slot);
    default: return false;
  }
}

void SystemEmitter::emit_ops(const std::vector<VectorOp>& ops, const std::vector<Value*>& sizes) {
  binary32_locals_.assign(local_types_.size(), false);
  std::function<void(const std::vector<Stmt>&)> forget = [&](const std::vector<Stmt>& body) {
    for (const Stmt& s : body) {
      if (s.kind == StmtKind::SetLocal) binary32_locals_[static_cast<size_t>(s.slot)] = false;
      forget(s.body);
      forget(s.orelse);
    }
  };
  for (const VectorOp& op : ops) {
    forget(op.body);
    guarded_op(op, sizes);
    if (op.kind != VectorOp::Kind::Scalar || op.guard >= 0) continue;
    for (const Stmt& s : op.body) {
      if (s.kind == StmtKind::SetLocal && local_types_[static_cast<size_t>(s.slot)] == Ty::F64) {
        binary32_locals_[static_cast<size_t>(s.slot)] = holds_binary32(*s.value);
      } else {
        forget(s.body);
        forget(s.orelse);
      }
    }
  }
  binary32_locals_.clear();
}

// An op in a branch of an `if` runs when its guard holds.
void SystemEmitter::guarded_op(const VectorOp& op, const std::vector<Value*>& sizes) {
  if (op.guard < 0) return parallel_op(op, sizes);
  auto* run = llvm::BasicBlock::Create(ctx_, "guarded", fn_);
  auto* join = llvm::BasicBlock::Create(ctx_, "guarded.done", fn_);
  b_.CreateCondBr(b_.CreateLoad(b_.getInt1Ty(), locals_[op.guard]), run, join);
  b_.SetInsertPoint(run);
  parallel_op(op, sizes);
  b_.CreateBr(join);
  b_.SetInsertPoint(join);
}

// Whether a pass with sums by runs can take four runs at a time in vectors: its statements
// store components of vectors at the visited component, or add a term to one of its sums, and
// read only components at the visited component, constants and other scalars.
bool SystemEmitter::pass_in_lanes(const VectorOp& op) const {
  if (kLanes != 4) return false;
  auto is_sum = [&](int slot) {
    return std::find(op.sums.begin(), op.sums.end(), slot) != op.sums.end();
  };
  std::function<bool(const Expr&)> lane_wise = [&](const Expr& e) {
    switch (e.kind) {
      case ExprKind::Const: return e.ty == Ty::F64;
      case ExprKind::Local: return e.ty == Ty::F64 && !is_sum(e.slot);
      case ExprKind::Load:
        return e.ty == Ty::F64 && slots_[static_cast<size_t>(e.slot)].components == 1 &&
               e.ops[0]->kind == ExprKind::Element;
      case ExprKind::Unary:
      case ExprKind::Binary:
      case ExprKind::Math:
        if (e.ty != Ty::F64) return false;
        for (const ExprRef& o : e.ops)
          if (!lane_wise(*o)) return false;
        return true;
      default: return false;
    }
  };
  for (const Stmt& s : op.body) {
    if (s.kind == StmtKind::Store) {
      const ArraySlot& a = slots_[static_cast<size_t>(s.slot)];
      if (a.ty != Ty::F64 || a.components != 1 || s.comp != 0 ||
          s.index->kind != ExprKind::Element || !lane_wise(*s.value))
        return false;
    } else if (s.kind == StmtKind::SetLocal && is_sum(s.slot)) {
      const Expr& v = *s.value;
      if (v.kind != ExprKind::Binary || static_cast<BinOp>(v.op) != BinOp::Add ||
          v.ops[0]->kind != ExprKind::Local || v.ops[0]->slot != s.slot || !lane_wise(*v.ops[1]))
        return false;
    } else {
      return false;
    }
  }
  return true;
}

// A lane-wise expression over the components first .. first + 3 (pass_in_lanes).
Value* SystemEmitter::pass_lanes(const Expr& e, Value* first) {
  llvm::Type* f64 = b_.getDoubleTy();
  auto* vec = llvm::FixedVectorType::get(f64, kLanes);
  switch (e.kind) {
    case ExprKind::Const: return llvm::ConstantFP::get(vec, e.f);
    case ExprKind::Local: {
      Value* v = b_.CreateLoad(f64, locals_[e.slot]);
      if (!binary32_local(e.slot)) return b_.CreateVectorSplat(kLanes, v);
      return b_.CreateFPExt(b_.CreateVectorSplat(kLanes, b_.CreateFPTrunc(v, b_.getFloatTy())),
                            vec);
    }
    case ExprKind::Load: {
      if (slots_[static_cast<size_t>(e.slot)].single) {  // binary32, widened exactly
        auto* vec32 = llvm::FixedVectorType::get(b_.getFloatTy(), kLanes);
        llvm::LoadInst* v = b_.CreateLoad(
            vec32,
            b_.CreateInBoundsGEP(b_.getFloatTy(), arrays_[static_cast<size_t>(e.slot)], first));
        v->setAlignment(llvm::Align(4));
        return b_.CreateFPExt(v, vec);
      }
      llvm::LoadInst* v = b_.CreateLoad(
          vec, b_.CreateInBoundsGEP(f64, arrays_[static_cast<size_t>(e.slot)], first));
      v->setAlignment(llvm::Align(8));
      return v;
    }
    default: {
      std::vector<Value*> args;
      for (const ExprRef& o : e.ops) args.push_back(pass_lanes(*o, first));
      return combine(e, args);
    }
  }
}

// Four runs of op.group components from component `first` (an i64): each statement for four
// components at a time, in the statements' order; then each run's part of each sum, its terms
// added in order (as run_of adds them), and the four parts added to the lanes `lane` ..
// `lane` + 3 as one vector.
void SystemEmitter::runs_in_lanes(const VectorOp& op, Value* first, Value* lane) {
  const int g = op.group;
  std::vector<std::vector<Value*>> terms(op.sums.size());
  for (int v = 0; v < g; ++v) {
    Value* at = b_.CreateAdd(first, b_.getInt64(kLanes * v));
    for (const Stmt& s : op.body) {
      if (s.kind == StmtKind::Store) {
        const bool single = slots_[static_cast<size_t>(s.slot)].single;
        Value* v = pass_lanes(*s.value, at);
        if (single) v = b_.CreateFPTrunc(v, llvm::FixedVectorType::get(b_.getFloatTy(), kLanes));
        llvm::StoreInst* st =
            b_.CreateStore(v, b_.CreateInBoundsGEP(single ? b_.getFloatTy() : b_.getDoubleTy(),
                                                   arrays_[static_cast<size_t>(s.slot)], at));
        st->setAlignment(llvm::Align(single ? 4 : 8));
        continue;
      }
      const size_t k =
          static_cast<size_t>(std::find(op.sums.begin(), op.sums.end(), s.slot) - op.sums.begin());
      terms[k].push_back(pass_lanes(*s.value->ops[1], at));
    }
  }
  auto* vec = llvm::FixedVectorType::get(b_.getDoubleTy(), kLanes);
  // The lanes are 32-byte aligned and `lane` is a multiple of four.
  const llvm::Align aligned(32);
  for (size_t k = 0; k < op.sums.size(); ++k) {
    // Every statement adds one term per component; with several statements for one sum the
    // component's terms follow one another.
    const size_t per = terms[k].size() / static_cast<size_t>(g);
    Value* parts = llvm::PoisonValue::get(vec);
    for (int run = 0; run < kLanes; ++run) {
      Value* part = nullptr;
      for (int c = run * g; c < (run + 1) * g; ++c)
        for (size_t t = 0; t < per; ++t) {
          Value* term = b_.CreateExtractElement(terms[k][static_cast<size_t>(c / kLanes) * per + t],
                                                static_cast<uint64_t>(c % kLanes));
          part = part ? b_.CreateFAdd(part, term) : term;
        }
      parts = b_.CreateInsertElement(parts, part, static_cast<uint64_t>(run));
    }
    Value* at = lane_at(k, lane);
    b_.CreateAlignedStore(b_.CreateFAdd(b_.CreateAlignedLoad(vec, at, aligned), parts), at,
                          aligned);
  }
}

// A run's part of a sum needs no +0.0 start: its lane starts at +0.0 and so is never -0.0, and
// a part that differs only in the sign of a zero then adds the same. The sum's local holds
// the part while the run's statements add to it.
void SystemEmitter::run_of(const VectorOp& op, Value* first, int group, Value* lane) {
  const bool runs = !op.sums.empty();
  if (runs) {
    for (int s : op.sums) b_.CreateStore(llvm::ConstantFP::get(b_.getDoubleTy(), -0.0), locals_[s]);
  }
  for (int i = 0; i < group; ++i) {
    element_wide_ = b_.CreateAdd(first, b_.getInt64(i));
    element_ = b_.CreateTrunc(element_wide_, b_.getInt32Ty());
    block(op.body);
  }
  element_wide_ = nullptr;
  if (runs) {
    for (size_t k = 0; k < op.sums.size(); ++k) {
      Value* part = b_.CreateLoad(b_.getDoubleTy(), locals_[op.sums[k]]);
      Value* at = lane_at(k, lane);
      b_.CreateStore(b_.CreateFAdd(b_.CreateLoad(b_.getDoubleTy(), at), part), at);
    }
  }
}

// The program's scalars back into `scalars` (doubles; ints and booleans converted exactly).
void SystemEmitter::write_scalars(Value* scalars) {
  llvm::Type* f64 = b_.getDoubleTy();
  for (int i = 0; i < st_.scalars; ++i) {
    const Ty t = local_types_[i];
    Value* v = b_.CreateLoad(type(t), locals_[i]);
    Value* d = t == Ty::F64 ? v : t == Ty::I32 ? b_.CreateSIToFP(v, f64) : b_.CreateUIToFP(v, f64);
    b_.CreateStore(d, b_.CreateConstInBoundsGEP1_64(f64, scalars, i));
  }
  // And the iterations the loop ran (SystemArgs::iterations).
  if (iterations_) b_.CreateStore(b_.CreateLoad(b_.getInt64Ty(), iterations_), iterations_out_);
}

// The while loop: its condition, then its ops, as long as the condition holds and no
// interrupt is pending.
void SystemEmitter::while_loop(const std::vector<Value*>& sizes, Value* scalars, Value* interrupt) {
  auto* head = llvm::BasicBlock::Create(ctx_, "while", fn_);
  auto* test = llvm::BasicBlock::Create(ctx_, "while.test", fn_);
  auto* body = llvm::BasicBlock::Create(ctx_, "while.body", fn_);
  auto* stop = llvm::BasicBlock::Create(ctx_, "while.interrupted", fn_);
  auto* done = llvm::BasicBlock::Create(ctx_, "while.done", fn_);
  b_.CreateBr(head);
  b_.SetInsertPoint(head);
  // Ctrl-C: a loop whose only exit is its condition (a solver that does not converge) must
  // stop when asked. The flag is read at the top of every iteration, where the vectors and
  // scalars are what a whole number of iterations leaves; the kernel hands them back there.
  // A relaxed atomic load: the handler (or another thread) sets it while the loop runs, and
  // it must be read again on each iteration, not hoisted out of the loop.
  llvm::LoadInst* flag = b_.CreateLoad(b_.getInt8Ty(), interrupt, "interrupt");
  flag->setAtomic(llvm::AtomicOrdering::Monotonic);
  flag->setAlignment(llvm::Align(1));
  b_.CreateCondBr(b_.CreateICmpEQ(flag, b_.getInt8(0)), test, stop,
                  llvm::MDBuilder(ctx_).createLikelyBranchWeights());
  b_.SetInsertPoint(stop);
  write_scalars(scalars);
  b_.CreateRet(b_.getInt32(kSystemInterrupted));
  b_.SetInsertPoint(test);
  b_.CreateCondBr(expr(*st_.condition), body, done);
  b_.SetInsertPoint(body);
  b_.CreateStore(b_.CreateAdd(b_.CreateLoad(b_.getInt64Ty(), iterations_), b_.getInt64(1)),
                 iterations_);
  emit_ops(st_.body, sizes);
  b_.CreateBr(head);
  b_.SetInsertPoint(done);
}

// The program's scalars in and out through `scalars`, the ops before the loop, the while loop
// and the ops after it in between.
llvm::Function* SystemEmitter::run(const std::string& name) {
  llvm::Type* ptr = b_.getPtrTy();
  auto* ft = llvm::FunctionType::get(b_.getInt32Ty(), {ptr, ptr, ptr, ptr, ptr, ptr}, false);
  fn_ = llvm::Function::Create(ft, llvm::Function::ExternalLinkage, name, m_);
  auto arg = fn_->arg_begin();
  Value *arrays = &*arg++, *scalars = &*arg++, *sizes_in = &*arg++, *interrupt = &*arg++;
  pool_ = &*arg++;
  iterations_out_ = &*arg;
  auto* entry = llvm::BasicBlock::Create(ctx_, "entry", fn_);
  b_.SetInsertPoint(entry);
  load_arrays(arrays);
  for (Ty t : local_types_) locals_.push_back(b_.CreateAlloca(type(t)));
  if (st_.condition) {
    iterations_ = b_.CreateAlloca(b_.getInt64Ty());
    b_.CreateStore(b_.getInt64(0), iterations_);
  }
  llvm::Type* f64 = b_.getDoubleTy();
  for (int i = 0; i < st_.scalars; ++i) {
    Value* d = b_.CreateLoad(f64, b_.CreateConstInBoundsGEP1_64(f64, scalars, i));
    const Ty t = local_types_[i];
    Value* v = t == Ty::F64   ? d
               : t == Ty::I32 ? b_.CreateFPToSI(d, b_.getInt32Ty())
                              : b_.CreateFCmpUNE(d, llvm::ConstantFP::get(f64, 0.0));
    b_.CreateStore(v, locals_[i]);
  }
  std::vector<Value*> sizes = load_sizes(sizes_in);
  prepare_parallel(arrays, sizes_in, sizes);
  emit_ops(st_.before, sizes);
  if (st_.condition) while_loop(sizes, scalars, interrupt);
  emit_ops(st_.after, sizes);
  write_scalars(scalars);
  b_.CreateRet(b_.getInt32(0));
  return fn_;
}

}  // namespace simit::jit::codegen
