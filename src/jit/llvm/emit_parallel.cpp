// A solver loop's passes and products on threads: each op is outlined into
//   void op(const int64_t* context, int64_t first_unit, int64_t end_unit)
// which runs the op's units [first_unit, end_unit) exactly as the inline op runs them, and the
// kernel calls the runtime's simit_jit_parallel_for(pool, op, context, units), which splits
// the units among the pool's threads (jit/thread_pool.h). An op's sums leave one partial per
// chunk in the partials array, and the kernel adds them to the sums in chunk order, as the
// inline op does (docs/arithmetic.md, "Sums"): the bits do not depend on the split.
//
// The context holds the kernel's arrays, its sizes, the partials array, and a copy of every
// local (the outlined op reads the scalars it needs from it; the locals it sets are the
// per-component temporaries and the sums' run parts, which no later op reads).
#include <algorithm>

#include "jit/llvm/emitter.h"
#include "runtime/blocked_sum.h"

namespace simit::jit::codegen {

namespace {

constexpr int kContextHead = 3;  // arrays, sizes, partials; then the locals

// Whether statements only compute (no check that leaves the kernel, no decomposition) and set
// only locals that are not the program's scalars.
bool computes_only(const std::vector<Stmt>& body, int scalars) {
  for (const Stmt& s : body) {
    if (s.kind == StmtKind::Check || s.kind == StmtKind::Decompose) return false;
    if (s.kind == StmtKind::SetLocal && s.slot < scalars) return false;
    if (!computes_only(s.body, scalars) || !computes_only(s.orelse, scalars)) return false;
  }
  return true;
}

}  // namespace

std::vector<Value*> SystemEmitter::load_sizes(Value* sizes_in) {
  std::vector<Value*> sizes;
  for (size_t i = 0; i < st_.sizes.size(); ++i)
    sizes.push_back(b_.CreateLoad(b_.getInt64Ty(),
                                  b_.CreateConstInBoundsGEP1_64(b_.getInt64Ty(), sizes_in, i)));
  return sizes;
}

std::pair<Value*, Value*> SystemEmitter::unit_range(Value* n, int64_t unit) {
  if (!outlined_) return {b_.getInt64(0), n};
  Value* lo = b_.CreateMul(outlined_->begin, b_.getInt64(unit));
  Value* hi = b_.CreateMul(outlined_->end, b_.getInt64(unit));
  return {b_.CreateSelect(b_.CreateICmpSLT(lo, n), lo, n),
          b_.CreateSelect(b_.CreateICmpSLT(hi, n), hi, n)};
}

bool SystemEmitter::outlinable(const VectorOp& op) const {
  if (op.kind == VectorOp::Kind::Scalar) return false;
  // The sums are the op's only results in locals; everything else it sets is a temporary.
  std::vector<Stmt> rest;
  for (const Stmt& s : op.body)
    if (!(s.kind == StmtKind::SetLocal &&
          std::find(op.sums.begin(), op.sums.end(), s.slot) != op.sums.end()))
      rest.push_back(s);
  return computes_only(rest, st_.scalars);
}

// The context and the partials array, once in the kernel's entry block: the partials hold
// one value per chunk and sum for the largest size any op runs over.
void SystemEmitter::prepare_parallel(Value* arrays, Value* sizes_in,
                                     const std::vector<Value*>& sizes) {
  if (!hooks_.parallel_passes()) return;
  size_t sums = 0;
  for (const auto* list : {&st_.before, &st_.body, &st_.after})
    for (const VectorOp& op : *list) sums = std::max(sums, op.sums.size());
  llvm::Type* i64 = b_.getInt64Ty();
  context_ = b_.CreateAlloca(
      i64,
      b_.getInt32(static_cast<uint32_t>(kContextHead + static_cast<int>(local_types_.size()))));
  b_.CreateStore(arrays, b_.CreateConstInBoundsGEP1_64(i64, context_, 0));
  b_.CreateStore(sizes_in, b_.CreateConstInBoundsGEP1_64(i64, context_, 1));
  if (sums > 0) {
    Value* most = b_.getInt64(1);
    for (Value* s : sizes) most = b_.CreateSelect(b_.CreateICmpSGT(s, most), s, most);
    Value* chunks = b_.CreateAdd(
        b_.CreateSDiv(most, b_.getInt64(static_cast<int64_t>(runtime::kSumChunk))), b_.getInt64(1));
    partials_ = b_.CreateAlloca(b_.getDoubleTy(),
                                b_.CreateMul(chunks, b_.getInt64(static_cast<int64_t>(sums))));
    b_.CreateStore(partials_, b_.CreateConstInBoundsGEP1_64(i64, context_, 2));
  }
}

// A pass without sums runs in units of the components that a chunk of the loop's sums over
// the same vectors covers (kSumChunk runs of their group; a product's rows when the loop has
// no sums, kSumChunk rows of `block` components), so that thread t's range of every pass is
// the same components and finds them in its own cache; kPassUnit when nothing says.
int64_t SystemEmitter::pass_unit(const VectorOp& op) const {
  const auto chunk = static_cast<int64_t>(runtime::kSumChunk);
  int64_t block = 0;
  for (const auto* list : {&st_.before, &st_.body, &st_.after})
    for (const VectorOp& other : *list) {
      if (other.kind == VectorOp::Kind::Pass && !other.sums.empty() && other.length == op.length)
        return chunk * other.group;
      if (other.kind == VectorOp::Kind::SpMV && block == 0) block = other.block;
    }
  return block > 0 ? chunk * block : kPassUnit;
}

Value* SystemEmitter::units_of(const VectorOp& op, const std::vector<Value*>& sizes) {
  auto ceil_div = [&](Value* n, int64_t d) {
    return b_.CreateSDiv(b_.CreateAdd(n, b_.getInt64(d - 1)), b_.getInt64(d));
  };
  const auto chunk = static_cast<int64_t>(runtime::kSumChunk);
  if (op.kind == VectorOp::Kind::SpMV) return ceil_div(sizes[op.rows], chunk);
  if (op.sums.empty()) return ceil_div(sizes[op.length], pass_unit(op));
  return ceil_div(b_.CreateSDiv(sizes[op.length], b_.getInt64(op.group)), chunk);
}

// The op as a function of its own, emitted with this emitter's state switched to it.
llvm::Function* SystemEmitter::outline(const VectorOp& op) {
  llvm::Type* ptr = b_.getPtrTy();
  llvm::Type* i64 = b_.getInt64Ty();
  auto* ft = llvm::FunctionType::get(b_.getVoidTy(), {ptr, i64, i64}, false);
  auto* f = llvm::Function::Create(ft, llvm::Function::InternalLinkage,
                                   fn_->getName() + ".op" + std::to_string(outlined_ops_++), m_);
  f->addParamAttr(0, llvm::Attribute::NoAlias);
  llvm::Function* saved_fn = fn_;
  llvm::BasicBlock* saved_block = b_.GetInsertBlock();
  std::vector<Value*> saved_arrays = std::move(arrays_), saved_locals = std::move(locals_);
  Value *saved_element = element_, *saved_wide = element_wide_, *saved_lanes = lanes_;
  arrays_.clear();
  locals_.clear();
  fn_ = f;
  auto arg = f->arg_begin();
  Value* context = &*arg++;
  Outlined o;
  o.begin = &*arg++;
  o.end = &*arg;
  b_.SetInsertPoint(llvm::BasicBlock::Create(ctx_, "entry", f));
  load_arrays(b_.CreateLoad(ptr, b_.CreateConstInBoundsGEP1_64(i64, context, 0)));
  const std::vector<Value*> sizes =
      load_sizes(b_.CreateLoad(ptr, b_.CreateConstInBoundsGEP1_64(i64, context, 1)));
  o.partials = b_.CreateLoad(ptr, b_.CreateConstInBoundsGEP1_64(i64, context, 2));
  for (size_t i = 0; i < local_types_.size(); ++i) {
    llvm::Type* t = type(local_types_[i]);
    locals_.push_back(b_.CreateAlloca(t));
    b_.CreateStore(b_.CreateLoad(t, b_.CreateConstInBoundsGEP1_64(i64, context, kContextHead + i)),
                   locals_.back());
  }
  outlined_ = &o;
  vector_op(op, sizes);
  b_.CreateRetVoid();
  outlined_ = nullptr;
  fn_ = saved_fn;
  arrays_ = std::move(saved_arrays);
  locals_ = std::move(saved_locals);
  element_ = saved_element;
  element_wide_ = saved_wide;
  lanes_ = saved_lanes;
  b_.SetInsertPoint(saved_block);
  return f;
}

// The op outlined and run on the pool; its sums then take the chunks' partials in order.
void SystemEmitter::parallel_op(const VectorOp& op, const std::vector<Value*>& sizes) {
  if (!hooks_.parallel_passes() || !context_ || !outlinable(op)) return vector_op(op, sizes);
  llvm::Type* i64 = b_.getInt64Ty();
  llvm::Type* f64 = b_.getDoubleTy();
  llvm::Function* f = outline(op);
  for (size_t i = 0; i < local_types_.size(); ++i)
    b_.CreateStore(b_.CreateLoad(type(local_types_[i]), locals_[i]),
                   b_.CreateConstInBoundsGEP1_64(i64, context_, kContextHead + i));
  Value* units = units_of(op, sizes);
  // void simit_jit_parallel_for(void* pool, void (*op)(const int64_t*, int64_t, int64_t),
  //                             const int64_t* context, int64_t units) (jit/thread_pool.h)
  llvm::Type* ptr = b_.getPtrTy();
  auto* ft = llvm::FunctionType::get(b_.getVoidTy(), {ptr, ptr, ptr, i64}, false);
  b_.CreateCall(hooks_.runtime_call(b_, "simit_jit_parallel_for", ft), {pool_, f, context_, units});
  if (op.sums.empty()) return;
  const auto n = static_cast<int64_t>(op.sums.size());
  loop(b_.getInt64(0), units, [&](Value* c) {
    for (int64_t k = 0; k < n; ++k) {
      Value* at = b_.CreateAdd(b_.CreateMul(c, b_.getInt64(n)), b_.getInt64(k));
      Value* partial = b_.CreateLoad(f64, b_.CreateInBoundsGEP(f64, partials_, at));
      Value* sum = locals_[static_cast<size_t>(op.sums[static_cast<size_t>(k)])];
      b_.CreateStore(b_.CreateFAdd(b_.CreateLoad(f64, sum), partial), sum);
    }
  });
}

}  // namespace simit::jit::codegen
