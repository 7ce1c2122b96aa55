// A device program's steps (jit/device_program.h) as functions over ranges of units, emitted
// alike for every target: the GPU wraps each in a kernel of one unit per thread, the CPU
// (the emulated GPU) calls them over all their units. Every step reads the context array:
// it returns at once when an error was reported, or, inside the loop, when the stop word is
// set; it loads the locals from the context, and a one-thread step (a Thread of parts)
// stores them back.
#include <memory>

#include "jit/llvm/emitter.h"
#include "runtime/blocked_sum.h"

namespace simit::jit::codegen {

namespace {

// The target's hooks, but a failed check is reported in the context's error word (the
// step's first argument) rather than through the target's failure report.
class StepHooks final : public TargetHooks {
 public:
  explicit StepHooks(TargetHooks& target) : t_(target) {}
  MapEntry map_kernel(llvm::Module& m, const std::string& name) override {
    return t_.map_kernel(m, name);
  }
  void elements(MapEmitter& k, const MapEntry& entry) override { t_.elements(k, entry); }
  llvm::Value* math(llvm::IRBuilder<>& b, MathFn f,
                    const std::vector<llvm::Value*>& args) override {
    return t_.math(b, f, args);
  }
  void assemble(llvm::IRBuilder<>& b, llvm::Value* at, llvm::Value* value,
                const llvm::AAMDNodes& aa, llvm::Value* round32) override {
    t_.assemble(b, at, value, aa, round32);
  }
  void fail(llvm::IRBuilder<>& b, int error, llvm::Value*) override {
    llvm::Value* context = b.GetInsertBlock()->getParent()->getArg(0);
    b.CreateStore(b.getInt64(error + 1),
                  b.CreateConstInBoundsGEP1_64(b.getInt64Ty(), context, kCtxError));
    b.CreateRetVoid();
  }
  llvm::FunctionCallee runtime_call(llvm::IRBuilder<>& b, const char* name,
                                    llvm::FunctionType* type) override {
    return t_.runtime_call(b, name, type);
  }

 private:
  TargetHooks& t_;
};

}  // namespace

std::unique_ptr<TargetHooks> device_step_hooks(TargetHooks& target) {
  return std::make_unique<StepHooks>(target);
}

std::vector<llvm::Function*> SystemEmitter::device_steps(const DeviceProgram& p,
                                                         const std::string& prefix) {
  std::vector<llvm::Function*> out;
  for (const DeviceStep* s : p.all())
    out.push_back(device_step(*s, device_step_name(prefix, out.size())));
  return out;
}

llvm::Function* SystemEmitter::device_step(const DeviceStep& s, const std::string& name) {
  llvm::Type* ptr = b_.getPtrTy();
  llvm::Type* i64 = b_.getInt64Ty();
  auto* ft = llvm::FunctionType::get(b_.getVoidTy(), {ptr, i64, i64}, false);
  fn_ = llvm::Function::Create(ft, llvm::Function::InternalLinkage, name, m_);
  auto arg = fn_->arg_begin();
  Value* context = &*arg++;
  Value* first = &*arg++;
  Value* end = &*arg;
  arrays_.clear();
  locals_.clear();
  element_ = element_wide_ = lanes_ = nullptr;
  auto* entry = llvm::BasicBlock::Create(ctx_, "entry", fn_);
  auto* leave = llvm::BasicBlock::Create(ctx_, "leave", fn_);
  auto* run = llvm::BasicBlock::Create(ctx_, "run", fn_);
  b_.SetInsertPoint(leave);
  b_.CreateRetVoid();
  b_.SetInsertPoint(entry);
  // The locals' slots in the entry block (an alloca elsewhere is dynamic: a GPU cannot).
  for (Ty t : local_types_) locals_.push_back(b_.CreateAlloca(type(t)));
  auto word = [&](int w) { return b_.CreateConstInBoundsGEP1_64(i64, context, w); };
  // An error reported by an earlier step ends the program; a stopped loop skips its steps.
  Value* go = b_.CreateICmpEQ(b_.CreateLoad(i64, word(kCtxError)), b_.getInt64(0));
  if (s.in_loop)
    go = b_.CreateAnd(go, b_.CreateICmpEQ(b_.CreateLoad(i64, word(kCtxStop)), b_.getInt64(0)));
  b_.CreateCondBr(go, run, leave);
  b_.SetInsertPoint(run);
  load_arrays(b_.CreateLoad(ptr, word(kCtxArrays)));
  const std::vector<Value*> sizes = load_sizes(b_.CreateLoad(ptr, word(kCtxSizes)));
  for (size_t i = 0; i < local_types_.size(); ++i)
    b_.CreateStore(b_.CreateLoad(type(local_types_[i]), word(kContextHead + static_cast<int>(i))),
                   locals_[i]);
  // An op under a guard (a branch of an `if`) runs when it holds: a Thread's parts each on
  // their own.
  auto guarded = [&](const DeviceStep& step, llvm::BasicBlock* otherwise) {
    if (!step.op || step.op->guard < 0) return;
    auto* run_op = llvm::BasicBlock::Create(ctx_, "guarded", fn_);
    b_.CreateCondBr(b_.CreateLoad(b_.getInt1Ty(), locals_[step.op->guard]), run_op, otherwise);
    b_.SetInsertPoint(run_op);
  };
  if (s.kind != DeviceStep::Kind::Thread) {
    guarded(s, leave);
    device_units(s, first, end, sizes);
    b_.CreateBr(leave);
    return fn_;
  }
  // The parts in order, then the locals back into the context (the next steps read them). A
  // condition that fails sets the stop word and skips the parts after it.
  auto* finish = llvm::BasicBlock::Create(ctx_, "finish", fn_);
  for (const DeviceStep& part : s.parts) {
    auto* next = llvm::BasicBlock::Create(ctx_, "part.done", fn_);
    guarded(part, next);
    switch (part.kind) {
      case DeviceStep::Kind::Serial: block(part.op->body); break;
      case DeviceStep::Kind::Condition: {
        auto* stop = llvm::BasicBlock::Create(ctx_, "stop", fn_);
        b_.CreateCondBr(expr(*st_.condition), next, stop);
        b_.SetInsertPoint(stop);
        b_.CreateStore(b_.getInt64(1), word(kCtxStop));
        b_.CreateBr(finish);
        b_.SetInsertPoint(next);
        continue;
      }
      case DeviceStep::Kind::Combine: combine_sums(part, sizes); break;
      default: break;  // a Thread holds one-thread parts only
    }
    b_.CreateBr(next);
    b_.SetInsertPoint(next);
  }
  b_.CreateBr(finish);
  b_.SetInsertPoint(finish);
  for (size_t i = 0; i < local_types_.size(); ++i)
    b_.CreateStore(b_.CreateLoad(type(local_types_[i]), locals_[i]),
                   word(kContextHead + static_cast<int>(i)));
  b_.CreateBr(leave);
  return fn_;
}

// s = s + P_0 + P_1 + ...: each of the op's sums plus its chunks' partials in chunk order.
void SystemEmitter::combine_sums(const DeviceStep& s, const std::vector<Value*>& sizes) {
  Value* partials = b_.CreateLoad(
      b_.getPtrTy(), b_.CreateConstInBoundsGEP1_64(b_.getInt64Ty(), fn_->getArg(0), kCtxPartials));
  const int64_t n = s.sums;
  Value* elements = b_.CreateSDiv(sizes[static_cast<size_t>(s.size)], b_.getInt64(s.group));
  const auto chunk = static_cast<int64_t>(runtime::kSumChunk);
  Value* chunks = b_.CreateSDiv(b_.CreateAdd(elements, b_.getInt64(chunk - 1)), b_.getInt64(chunk));
  loop(b_.getInt64(0), chunks, [&](Value* c) {
    for (int64_t k = 0; k < n; ++k) {
      Value* at = b_.CreateAdd(b_.CreateMul(c, b_.getInt64(n)), b_.getInt64(k));
      Value* partial =
          b_.CreateLoad(b_.getDoubleTy(), b_.CreateInBoundsGEP(b_.getDoubleTy(), partials, at));
      Value* sum = locals_[static_cast<size_t>(s.op->sums[static_cast<size_t>(k)])];
      b_.CreateStore(b_.CreateFAdd(b_.CreateLoad(b_.getDoubleTy(), sum), partial), sum);
    }
  });
}

// The units [first, end) of a step that has many (clamped to the step's count).
void SystemEmitter::device_units(const DeviceStep& s, Value* first, Value* end,
                                 const std::vector<Value*>& sizes) {
  llvm::Type* f64 = b_.getDoubleTy();
  const VectorOp& op = *s.op;
  const int64_t lanes = static_cast<int64_t>(runtime::kSumLanes);
  const auto chunk = static_cast<int64_t>(runtime::kSumChunk);
  Value* n = sizes[static_cast<size_t>(s.size)];
  Value* elements = b_.CreateSDiv(n, b_.getInt64(s.group));
  Value* chunks = b_.CreateSDiv(b_.CreateAdd(elements, b_.getInt64(chunk - 1)), b_.getInt64(chunk));
  auto clamp = [&](Value* v, Value* most) {
    return b_.CreateSelect(b_.CreateICmpSLT(v, most), v, most);
  };
  const int64_t sums = s.sums;
  switch (s.kind) {
    case DeviceStep::Kind::Each:
      return loop(clamp(first, n), clamp(end, n), [&](Value* k) {
        element_wide_ = k;
        element_ = b_.CreateTrunc(k, b_.getInt32Ty());
        block(op.body);
        element_wide_ = nullptr;
      });
    case DeviceStep::Kind::Rows:
      return loop(clamp(first, n), clamp(end, n), [&](Value* r) { spmv_row(op, r, nullptr); });
    case DeviceStep::Kind::Lanes: {
      // Unit u: lane u % 32 of chunk u / 32, whose elements are the chunk's e with
      // (e - first element) % 32 equal to the lane, added in increasing order to an
      // accumulator that starts at +0.0 (runtime/blocked_sum.h).
      {
        llvm::IRBuilder<> at_entry(&fn_->getEntryBlock(), fn_->getEntryBlock().begin());
        lanes_ = at_entry.CreateAlloca(llvm::ArrayType::get(f64, lanes * sums));
      }
      Value* out = b_.CreateLoad(
          b_.getPtrTy(), b_.CreateConstInBoundsGEP1_64(b_.getInt64Ty(), fn_->getArg(0), kCtxLanes));
      Value* units = b_.CreateMul(chunks, b_.getInt64(lanes));
      loop(clamp(first, units), clamp(end, units), [&](Value* u) {
        for (int64_t k = 0; k < sums; ++k)
          b_.CreateStore(llvm::ConstantFP::get(f64, 0.0),
                         lane_at(static_cast<size_t>(k), b_.getInt64(0)));
        Value* c = b_.CreateSDiv(u, b_.getInt64(lanes));
        Value* begin = b_.CreateMul(c, b_.getInt64(chunk));
        Value* stop = clamp(b_.CreateAdd(begin, b_.getInt64(chunk)), elements);
        Value* e0 = b_.CreateAdd(begin, b_.CreateSRem(u, b_.getInt64(lanes)));
        LoopShape by_lane;
        by_lane.step = static_cast<int>(lanes);
        loop(
            e0, stop,
            [&](Value* e) {
              if (op.kind == VectorOp::Kind::SpMV)
                spmv_row(op, e, b_.getInt64(0));
              else
                run_of(op, b_.CreateMul(e, b_.getInt64(op.group)), op.group, b_.getInt64(0));
            },
            by_lane);
        for (int64_t k = 0; k < sums; ++k)
          b_.CreateStore(
              b_.CreateLoad(f64, lane_at(static_cast<size_t>(k), b_.getInt64(0))),
              b_.CreateInBoundsGEP(
                  f64, out, b_.CreateAdd(b_.CreateMul(u, b_.getInt64(sums)), b_.getInt64(k))));
      });
      lanes_ = nullptr;
      return;
    }
    case DeviceStep::Kind::Tree: {
      // Chunk c's partial of each sum: the halving tree over its lanes' values.
      Value* in = b_.CreateLoad(
          b_.getPtrTy(), b_.CreateConstInBoundsGEP1_64(b_.getInt64Ty(), fn_->getArg(0), kCtxLanes));
      Value* out = b_.CreateLoad(b_.getPtrTy(), b_.CreateConstInBoundsGEP1_64(
                                                    b_.getInt64Ty(), fn_->getArg(0), kCtxPartials));
      return loop(clamp(first, chunks), clamp(end, chunks), [&](Value* c) {
        for (int64_t k = 0; k < sums; ++k) {
          std::vector<Value*> a;
          for (int64_t l = 0; l < lanes; ++l) {
            Value* at = b_.CreateAdd(
                b_.CreateMul(b_.CreateAdd(b_.CreateMul(c, b_.getInt64(lanes)), b_.getInt64(l)),
                             b_.getInt64(sums)),
                b_.getInt64(k));
            a.push_back(b_.CreateLoad(f64, b_.CreateInBoundsGEP(f64, in, at)));
          }
          for (int64_t w = lanes / 2; w >= 1; w /= 2)
            for (int64_t i = 0; i < w; ++i)
              a[static_cast<size_t>(i)] =
                  b_.CreateFAdd(a[static_cast<size_t>(i)], a[static_cast<size_t>(i + w)]);
          b_.CreateStore(a[0], b_.CreateInBoundsGEP(f64, out,
                                                    b_.CreateAdd(b_.CreateMul(c, b_.getInt64(sums)),
                                                                 b_.getInt64(k))));
        }
      });
    }
    default: return;
  }
}

}  // namespace simit::jit::codegen
