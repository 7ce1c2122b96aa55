// The CPU code generator: loop IR to LLVM IR, optimised for the host and linked through one
// ORC session, one resource tracker per kernel (dropping a kernel frees its code).
#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <functional>
#include <mutex>
#include <unordered_map>
#include <unordered_set>

#include <llvm/ExecutionEngine/Orc/ExecutionUtils.h>
#include <llvm/ExecutionEngine/Orc/JITTargetMachineBuilder.h>
#include <llvm/ExecutionEngine/Orc/LLJIT.h>
#include <llvm/IR/IRBuilder.h>
#include <llvm/IR/LLVMContext.h>
#include <llvm/IR/MDBuilder.h>
#include <llvm/IR/Module.h>
#include <llvm/IR/Verifier.h>
#include <llvm/Passes/PassBuilder.h>
#include <llvm/Support/TargetSelect.h>
#include <llvm/Support/raw_ostream.h>
#include <llvm/Target/TargetMachine.h>

#include "jit/backend.h"
#include "jit/tunables.h"

namespace simit::jit {

namespace {

using llvm::IRBuilder;
using llvm::Value;

std::string message_of(llvm::Error e) { return llvm::toString(std::move(e)); }

// The one ORC session of the process: its code lives as long as the kernels that own it.
class Session {
 public:
  static Session* get(std::string& error) {
    static std::once_flag once;
    static std::unique_ptr<Session> session;
    static std::string failure;
    std::call_once(once, [] {
      llvm::InitializeNativeTarget();
      llvm::InitializeNativeTargetAsmPrinter();
      auto s = std::unique_ptr<Session>(new Session());
      failure = s->start();
      if (failure.empty()) session = std::move(s);
    });
    error = failure;
    return session.get();
  }

  llvm::orc::LLJIT& jit() { return *jit_; }
  llvm::TargetMachine& target() { return *tm_; }

 private:
  std::string start() {
    auto jtmb = llvm::orc::JITTargetMachineBuilder::detectHost();
    if (!jtmb) return message_of(jtmb.takeError());
    // The arithmetic contract: no fused multiply-add, whatever the host offers.
    jtmb->getOptions().AllowFPOpFusion = llvm::FPOpFusion::Strict;
    jtmb->getFeatures().AddFeature("fma", false);
    jtmb->getFeatures().AddFeature("avx512f", false);
    jtmb->setCodeGenOptLevel(llvm::CodeGenOptLevel::Aggressive);
    auto tm = jtmb->createTargetMachine();
    if (!tm) return message_of(tm.takeError());
    tm_ = std::move(*tm);
    auto jit = llvm::orc::LLJITBuilder().setJITTargetMachineBuilder(*jtmb).create();
    if (!jit) return message_of(jit.takeError());
    jit_ = std::move(*jit);
    auto gen = llvm::orc::DynamicLibrarySearchGenerator::GetForCurrentProcess(
        jit_->getDataLayout().getGlobalPrefix());
    if (!gen) return message_of(gen.takeError());
    jit_->getMainJITDylib().addGenerator(std::move(*gen));
    return "";
  }

  std::unique_ptr<llvm::orc::LLJIT> jit_;
  std::unique_ptr<llvm::TargetMachine> tm_;
};

class CpuKernel : public Kernel {
 public:
  explicit CpuKernel(llvm::orc::ResourceTrackerSP rt) : rt_(std::move(rt)) {}
  void* address = nullptr;
  ~CpuKernel() override {
    if (rt_) llvm::consumeError(rt_->remove());
  }

 private:
  llvm::orc::ResourceTrackerSP rt_;
};

// Emits one trace as a function of the KernelFn signature, or a system trace as a SystemFn.
class Emitter {
 public:
  Emitter(const Trace& t, llvm::Module& m, const HostCalls& host)
      : t_(&t),
        slots_(t.arrays),
        local_types_(t.locals),
        m_(m),
        ctx_(m.getContext()),
        b_(ctx_),
        host_(host) {}
  Emitter(const SystemTrace& t, llvm::Module& m)
      : st_(&t), slots_(t.arrays), local_types_(t.locals), m_(m), ctx_(m.getContext()), b_(ctx_) {}

  llvm::Function* run(const std::string& name);
  llvm::Function* run_system(const std::string& name);

 private:
  llvm::Type* type(Ty t) {
    switch (t) {
      case Ty::F64: return b_.getDoubleTy();
      case Ty::I32: return b_.getInt32Ty();
      case Ty::Bool: return b_.getInt1Ty();
    }
    return nullptr;
  }
  llvm::Type* storage(const ArraySlot& a) {
    if (a.ty == Ty::F64) return a.single ? b_.getFloatTy() : b_.getDoubleTy();
    if (a.ty == Ty::I32) return b_.getInt32Ty();
    return b_.getInt8Ty();
  }
  // Address of component `comp` of element `index` of array `slot`.
  Value* address(int slot, Value* index, int comp) {
    const ArraySlot& a = slots_[slot];
    // The visited element as the i64 it was computed from: LLVM then sees that a pass reads
    // the component a product has just stored (and keeps it in a register).
    Value* i = index == element_ && element_wide_ ? element_wide_
                                                  : b_.CreateSExt(index, b_.getInt64Ty());
    Value* at = b_.CreateAdd(b_.CreateMul(i, b_.getInt64(a.components)), b_.getInt64(comp));
    return b_.CreateInBoundsGEP(storage(a), arrays_[slot], at);
  }
  Value* math(const Expr& e, const std::vector<Value*>& args);
  llvm::Type* like(llvm::Type* scalar, Value* like);
  Value* combine(const Expr& e, const std::vector<Value*>& args);
  Value* expr(const Expr& e);
  Value* load(const Expr& e, Value* index);
  // Element e's index and its endpoints become the values Element and Endpoint read.
  void visit(Value* e);
  // Lanes (a map kernel computing kLanes elements at once; see lanes_fit).
  void run_lanes(Value* first, Value* end);
  Value* lanes(const Expr& e);
  Value* lanes_uncached(const Expr& e);
  void lanes_block(const std::vector<Stmt>& body);
  void count_roots(const std::vector<Stmt>& body);
  void spill(const Expr& e);
  Value* load_root(Ty t, int index);
  void flush_pending(int first);
  void block(const std::vector<Stmt>& body);
  void stmt(const Stmt& s);
  // for (i = begin; i < end; ++i) body(i), i an i32 (or i64 when wide).
  void loop(Value* begin, Value* end, const std::function<void(Value*)>& body);
  void vector_op(const VectorOp& op, const std::vector<Value*>& sizes);
  // Unless `ok` (expected true), the kernel returns error + 1 with the element in *failed.
  void fail_unless(Value* ok, int error, const char* what) {
    auto* fail = llvm::BasicBlock::Create(ctx_, std::string(what) + ".fail", fn_);
    auto* cont = llvm::BasicBlock::Create(ctx_, std::string(what) + ".ok", fn_);
    b_.CreateCondBr(ok, cont, fail, llvm::MDBuilder(ctx_).createLikelyBranchWeights());
    b_.SetInsertPoint(fail);
    b_.CreateStore(element_, failed_);
    b_.CreateRet(b_.getInt32(error + 1));
    b_.SetInsertPoint(cont);
  }
  // The op's body for the `group` components of one run starting at `first` (an i64), its
  // sums taken over the run alone and then added to their totals.
  void run_of(const VectorOp& op, Value* first, int group);
  bool pass_in_lanes(const VectorOp& op) const;
  Value* pass_lanes(const Expr& e, Value* first);
  void runs_in_lanes(const VectorOp& op, Value* first);
  void load_arrays(Value* arrays);

  void decompose(const Stmt& s);
  Value* assemble_base(const Stmt& s);
  void assemble(const Stmt* s, int n);
  int assemble_run(const std::vector<Stmt>& body, size_t i);
  Value* root_address(int row);

  const Trace* t_ = nullptr;
  const SystemTrace* st_ = nullptr;
  const std::vector<ArraySlot>& slots_;
  const std::vector<Ty>& local_types_;
  llvm::Module& m_;
  llvm::LLVMContext& ctx_;
  IRBuilder<> b_;
  llvm::Function* fn_ = nullptr;
  std::vector<Value*> arrays_, scalars_, locals_, endpoints_;
  std::vector<Value*> ssa_;  // values of the locals set once
  Value* element_ = nullptr;
  Value* element_wide_ = nullptr;  // element_ as an i64, where a pass computed it so
  Value* failed_ = nullptr;
  Value* endpoint_table_ = nullptr;
  // Lanes: each expression's value for every lane (memoised by node: traces share nodes),
  // the locals', and each lane's element and endpoints.
  std::unordered_map<const Expr*, Value*> vmemo_;
  std::vector<Value*> vlocal_, element_lane_;
  std::vector<std::vector<Value*>> endpoint_lane_;
  // The values the element-by-element statements read (conditions, written values), stored
  // per lane in one buffer per type: root -> its row.
  std::unordered_map<const Expr*, int> roots_;
  std::unordered_set<const Expr*> spilled_;
  int root_rows_[3] = {0, 0, 0};
  Value* root_buffer_[3] = {nullptr, nullptr, nullptr};
  Value* lane_ = nullptr;  // the lane whose statements are being emitted (i64), or null
  uint64_t root_stride_ = 0;     // float rows per lane in the buffer (a multiple of 4)
  std::vector<Value*> pending_;  // float roots computed, not yet stored
  HostCalls host_;
  // A map that writes only its results: result memory and everything it reads are disjoint,
  // and saying so lets LLVM keep table entries and field values in registers across the
  // result writes (alias.scope / noalias metadata; null when the trace writes fields).
  llvm::MDNode *inputs_ = nullptr, *results_ = nullptr;
  void tag(llvm::Instruction* i, int slot) {
    if (!inputs_) return;
    const bool result = slots_[static_cast<size_t>(slot)].kind == ArraySlot::Kind::Result;
    i->setMetadata(llvm::LLVMContext::MD_alias_scope, result ? results_ : inputs_);
    i->setMetadata(llvm::LLVMContext::MD_noalias, result ? inputs_ : results_);
  }
};

Value* Emitter::math(const Expr& e, const std::vector<Value*>& args) {
  const auto f = static_cast<MathFn>(e.op);
  switch (f) {
    case MathFn::Sqrt: return b_.CreateUnaryIntrinsic(llvm::Intrinsic::sqrt, args[0]);
    case MathFn::Abs: return b_.CreateUnaryIntrinsic(llvm::Intrinsic::fabs, args[0]);
    case MathFn::Max:
    case MathFn::Min: {
      // fmax / fmin as glibc computes them: a NaN operand yields the other one; otherwise
      // x > y ? x : y (x < y for fmin), so equal operands (+0, -0) give y.
      Value *x = args[0], *y = args[1];
      Value* pick = f == MathFn::Max ? b_.CreateFCmpOGT(x, y) : b_.CreateFCmpOLT(x, y);
      Value* v = b_.CreateSelect(pick, x, y);
      v = b_.CreateSelect(b_.CreateFCmpUNO(y, y), x, v);
      return b_.CreateSelect(b_.CreateFCmpUNO(x, x), y, v);
    }
    default: break;
  }
  std::vector<llvm::Type*> params(args.size(), b_.getDoubleTy());
  auto* ft = llvm::FunctionType::get(b_.getDoubleTy(), params, false);
  llvm::FunctionCallee callee = m_.getOrInsertFunction(math_name(f), ft);
  if (auto* fn = llvm::dyn_cast<llvm::Function>(callee.getCallee())) {
    fn->setDoesNotThrow();
    fn->setDoesNotAccessMemory();  // errno is never read back
  }
  auto call = [&](const std::vector<Value*>& a) {
    llvm::CallInst* c = b_.CreateCall(callee, a);
    // The C library's result, not LLVM's idea of it: no folding into other operations.
    c->addFnAttr(llvm::Attribute::NoBuiltin);
    return c;
  };
  if (!args[0]->getType()->isVectorTy()) return call(args);
  // Lanes: the same library call once per lane.
  Value* out = llvm::PoisonValue::get(args[0]->getType());
  for (unsigned l = 0; l < static_cast<unsigned>(kLanes); ++l) {
    std::vector<Value*> a;
    for (Value* v : args) a.push_back(b_.CreateExtractElement(v, l));
    out = b_.CreateInsertElement(out, call(a), l);
  }
  return out;
}

// `scalar` with as many lanes as `like` has (none for a scalar).
llvm::Type* Emitter::like(llvm::Type* scalar, Value* like) {
  if (auto* v = llvm::dyn_cast<llvm::FixedVectorType>(like->getType()))
    return llvm::FixedVectorType::get(scalar, v->getNumElements());
  return scalar;
}

// The operators on evaluated operands: scalars, or vectors of one element per lane.
Value* Emitter::combine(const Expr& e, const std::vector<Value*>& args) {
  switch (e.kind) {
    case ExprKind::Unary: {
      Value* x = args[0];
      switch (static_cast<UnOp>(e.op)) {
        case UnOp::Neg:
          return e.ty == Ty::F64 ? b_.CreateFNeg(x)
                                 : b_.CreateSub(llvm::Constant::getNullValue(x->getType()), x);
        case UnOp::Not: return b_.CreateNot(x);
        case UnOp::Round32:
          return b_.CreateFPExt(b_.CreateFPTrunc(x, like(b_.getFloatTy(), x)),
                                like(b_.getDoubleTy(), x));
        case UnOp::ToF64: return b_.CreateSIToFP(x, like(b_.getDoubleTy(), x));
      }
      return x;
    }
    case ExprKind::Binary: {
      Value *x = args[0], *y = args[1];
      const bool f = e.ty == Ty::F64;
      switch (static_cast<BinOp>(e.op)) {
        case BinOp::Add: return f ? b_.CreateFAdd(x, y) : b_.CreateAdd(x, y);
        case BinOp::Sub: return f ? b_.CreateFSub(x, y) : b_.CreateSub(x, y);
        case BinOp::Mul: return f ? b_.CreateFMul(x, y) : b_.CreateMul(x, y);
        case BinOp::Div: return b_.CreateFDiv(x, y);
        case BinOp::And: return b_.CreateAnd(x, y);
        case BinOp::Or: return b_.CreateOr(x, y);
        case BinOp::Xor: return b_.CreateXor(x, y);
      }
      return x;
    }
    case ExprKind::Compare: {
      using P = llvm::CmpInst::Predicate;
      static const P fp[] = {P::FCMP_OEQ, P::FCMP_UNE, P::FCMP_OLT,
                             P::FCMP_OGT, P::FCMP_OLE, P::FCMP_OGE};
      static const P ip[] = {P::ICMP_EQ,  P::ICMP_NE,  P::ICMP_SLT,
                             P::ICMP_SGT, P::ICMP_SLE, P::ICMP_SGE};
      if (e.ops[0]->ty == Ty::F64) return b_.CreateFCmp(fp[e.op], args[0], args[1]);
      return b_.CreateICmp(ip[e.op], args[0], args[1]);
    }
    case ExprKind::Select: return b_.CreateSelect(args[0], args[1], args[2]);
    case ExprKind::Math: return math(e, args);
    default: return nullptr;
  }
}

Value* Emitter::expr(const Expr& e) {
  if (lane_) {
    auto root = roots_.find(&e);
    if (root != roots_.end()) return load_root(e.ty, root->second);
  }
  switch (e.kind) {
    case ExprKind::Const:
      if (e.ty == Ty::F64) return llvm::ConstantFP::get(b_.getDoubleTy(), e.f);
      if (e.ty == Ty::I32) return b_.getInt32(static_cast<uint32_t>(e.i));
      return b_.getInt1(e.i != 0);
    case ExprKind::Scalar: {
      Value* d = scalars_[e.slot];
      if (e.ty == Ty::F64) return d;
      if (e.ty == Ty::I32) return b_.CreateFPToSI(d, b_.getInt32Ty());
      return b_.CreateFCmpUNE(d, llvm::ConstantFP::get(b_.getDoubleTy(), 0.0));
    }
    case ExprKind::Element: return element_;
    case ExprKind::Endpoint: return endpoints_[e.slot];
    case ExprKind::Load: return load(e, expr(*e.ops[0]));
    case ExprKind::Local:
      if (!locals_[e.slot]) return ssa_[e.slot];
      return b_.CreateLoad(type(e.ty), locals_[e.slot]);
    default: {
      std::vector<Value*> args;
      for (const ExprRef& o : e.ops) args.push_back(expr(*o));
      return combine(e, args);
    }
  }
}

// Component e.comp of array e.slot at the (scalar) element index.
Value* Emitter::load(const Expr& e, Value* index) {
  const ArraySlot& a = slots_[e.slot];
  llvm::LoadInst* v = b_.CreateLoad(storage(a), address(e.slot, index, e.comp));
  tag(v, e.slot);
  if (a.ty == Ty::F64 && a.single) return b_.CreateFPExt(v, b_.getDoubleTy());
  if (a.ty == Ty::Bool) return b_.CreateICmpNE(v, b_.getInt8(0));
  return v;
}

void Emitter::stmt(const Stmt& s) {
  switch (s.kind) {
    case StmtKind::SetLocal:
      if (lane_) return;  // computed for every lane already (Emitter::lanes_block)
      if (!locals_[s.slot]) {
        ssa_[s.slot] = expr(*s.value);
        return;
      }
      b_.CreateStore(expr(*s.value), locals_[s.slot]);
      return;
    case StmtKind::Store: {
      const ArraySlot& a = slots_[s.slot];
      Value* v = expr(*s.value);
      if (a.ty == Ty::F64 && a.single) v = b_.CreateFPTrunc(v, b_.getFloatTy());
      if (a.ty == Ty::Bool) v = b_.CreateZExt(v, b_.getInt8Ty());
      b_.CreateStore(v, address(s.slot, expr(*s.index), s.comp));
      return;
    }
    case StmtKind::Assemble: return assemble(&s, 1);
    case StmtKind::If: {
      Value* c = expr(*s.value);
      auto* then_bb = llvm::BasicBlock::Create(ctx_, "then", fn_);
      auto* else_bb = llvm::BasicBlock::Create(ctx_, "else", fn_);
      auto* join = llvm::BasicBlock::Create(ctx_, "join", fn_);
      b_.CreateCondBr(c, then_bb, else_bb);
      b_.SetInsertPoint(then_bb);
      block(s.body);
      b_.CreateBr(join);
      b_.SetInsertPoint(else_bb);
      block(s.orelse);
      b_.CreateBr(join);
      b_.SetInsertPoint(join);
      return;
    }
    case StmtKind::Decompose: return decompose(s);
    case StmtKind::Check: return fail_unless(expr(*s.value), s.error, "check");
  }
}

// Where the element's block (or vector element) of an Assemble statement starts.
Value* Emitter::assemble_base(const Stmt& s) {
  if (s.pair < 0) return address(s.slot, expr(*s.index), 0);
  // The block's position in the matrix comes from the pattern's per-element table.
  const int result = slots_[s.slot].index;
  int table = -1;
  for (size_t i = 0; i < slots_.size(); ++i)
    if (slots_[i].kind == ArraySlot::Kind::Table && slots_[i].index == result)
      table = static_cast<int>(i);
  llvm::LoadInst* pos = b_.CreateLoad(b_.getInt32Ty(), address(table, element_, s.pair));
  tag(pos, table);
  // -1: the block was left out of the pattern the controller specialised to.
  if (t_->outside_error >= 0)
    fail_unless(b_.CreateICmpSGE(pos, b_.getInt32(0)), t_->outside_error, "outside");
  return address(s.slot, pos, 0);
}

// Statements s[0 .. n-1]: components s[0].comp, s[0].comp + 1, ... of one block, whose values
// lie side by side in the lanes' buffer when n > 1 (see assemble_run): one base address, and
// the additions up to four components at a time (lane by lane, the same additions).
void Emitter::assemble(const Stmt* s, int n) {
  Value* base = assemble_base(s[0]);
  llvm::Type* f64 = b_.getDoubleTy();
  for (int k = 0; k < n;) {
    const int width = n - k >= 4 ? 4 : n - k >= 2 ? 2 : 1;
    Value* at = b_.CreateConstInBoundsGEP1_64(f64, base, static_cast<uint64_t>(s[0].comp + k));
    Value* v;
    llvm::Type* ty = f64;
    if (width == 1) {
      v = expr(*s[k].value);
    } else {
      ty = llvm::FixedVectorType::get(f64, static_cast<unsigned>(width));
      v = b_.CreateAlignedLoad(ty, root_address(roots_.at(s[k].value.get())), llvm::Align(8));
    }
    if (t_->reduce) {
      llvm::LoadInst* old = b_.CreateAlignedLoad(ty, at, llvm::Align(8));
      tag(old, s[0].slot);
      v = b_.CreateFAdd(old, v);
    }
    tag(b_.CreateAlignedStore(v, at, llvm::Align(8)), s[0].slot);
    k += width;
  }
}

// How many statements from body[i] on add neighbouring components of one block from
// neighbouring rows of the lanes' buffer (1 outside lanes).
int Emitter::assemble_run(const std::vector<Stmt>& body, size_t i) {
  const Stmt& first = body[i];
  if (!lane_ || first.value->ty != Ty::F64 || !roots_.count(first.value.get())) return 1;
  const int row = roots_.at(first.value.get());
  auto same_place = [&](const Stmt& s) {
    if (s.kind != StmtKind::Assemble || s.slot != first.slot || s.pair != first.pair) return false;
    if (s.pair >= 0) return true;
    const Expr &a = *s.index, &b = *first.index;
    return &a == &b || ((a.kind == ExprKind::Endpoint || a.kind == ExprKind::Element) &&
                        a.kind == b.kind && a.slot == b.slot);
  };
  int n = 1;
  while (i + static_cast<size_t>(n) < body.size()) {
    const Stmt& s = body[i + static_cast<size_t>(n)];
    if (!same_place(s) || s.comp != first.comp + n || s.value->ty != Ty::F64) break;
    auto r = roots_.find(s.value.get());
    if (r == roots_.end() || r->second != row + n) break;
    ++n;
  }
  return n;
}

// The runtime's decomposition through its address: the argument and the results pass through
// stack arrays; a non-zero return is the check that failed.
void Emitter::decompose(const Stmt& s) {
  llvm::Type* f64 = b_.getDoubleTy();
  llvm::Type* i32 = b_.getInt32Ty();
  llvm::IRBuilder<> entry(&fn_->getEntryBlock(), fn_->getEntryBlock().begin());
  Value* in = entry.CreateAlloca(f64, b_.getInt32(static_cast<uint32_t>(s.args.size())));
  Value* out = entry.CreateAlloca(f64, b_.getInt32(static_cast<uint32_t>(s.outs.size())));
  for (size_t i = 0; i < s.args.size(); ++i)
    b_.CreateStore(expr(*s.args[i]), b_.CreateConstInBoundsGEP1_64(f64, in, i));
  auto* ft = llvm::FunctionType::get(i32, {i32, i32, i32, b_.getPtrTy(), b_.getPtrTy()}, false);
  Value* callee =
      b_.CreateIntToPtr(b_.getInt64(reinterpret_cast<uint64_t>(host_.decompose)), b_.getPtrTy());
  Value* rc = b_.CreateCall(
      ft, callee,
      {b_.getInt32(s.fn), b_.getInt32(s.n), b_.getInt32(t_ && t_->float32 ? 1 : 0), in, out});
  fail_unless(b_.CreateICmpEQ(rc, b_.getInt32(0)), s.error, "decompose");
  for (size_t i = 0; i < s.outs.size(); ++i) {
    Value* v = b_.CreateLoad(f64, b_.CreateConstInBoundsGEP1_64(f64, out, i));
    const int l = s.outs[i];
    if (locals_[l])
      b_.CreateStore(v, locals_[l]);
    else
      ssa_[l] = v;
  }
}

// Whether a map kernel can compute kLanes elements at once: every value is then an SSA local
// or an expression of them, evaluated for all lanes with the same IEEE operations lane by
// lane (library calls once per lane), and everything that acts (the assembly writes, the
// branches, the checks) runs afterwards element by element in order, so the results, the
// order of every reduction and the first failing element are the one-element kernel's.
// Reads are speculative across branches: loads of fields and arguments at the element's own
// endpoints are always in range, and no operation traps.
bool lanes_fit(const Trace& t) {
  if (kLanes <= 1 || t.writes_fields || t.local_mutable.size() < t.locals.size()) return false;
  for (bool m : t.local_mutable)
    if (m) return false;
  std::function<bool(const std::vector<Stmt>&)> fits = [&](const std::vector<Stmt>& body) {
    for (const Stmt& s : body) {
      if (s.kind == StmtKind::Store || s.kind == StmtKind::Decompose) return false;
      if (s.kind == StmtKind::If && !(fits(s.body) && fits(s.orelse))) return false;
    }
    return true;
  };
  return fits(t.body);
}

// Values the element-by-element statements compute themselves rather than read back.
bool trivial(const Expr& e) {
  return e.kind == ExprKind::Const || e.kind == ExprKind::Scalar ||
         e.kind == ExprKind::Element || e.kind == ExprKind::Endpoint;
}
int ty_index(Ty t) { return static_cast<int>(t); }

void Emitter::visit(Value* e) {
  element_ = e;
  endpoints_.clear();
  if (t_->arity == 0) return;
  Value* base = b_.CreateMul(b_.CreateSExt(e, b_.getInt64Ty()), b_.getInt64(t_->arity));
  for (int k = 0; k < t_->arity; ++k)
    endpoints_.push_back(b_.CreateLoad(
        b_.getInt32Ty(),
        b_.CreateInBoundsGEP(b_.getInt32Ty(), endpoint_table_, b_.CreateAdd(base, b_.getInt64(k)))));
}

// The statements' roots, each given its row in its type's buffer.
void Emitter::count_roots(const std::vector<Stmt>& body) {
  auto root = [&](const ExprRef& e) {
    if (!e || trivial(*e) || roots_.count(e.get())) return;
    roots_[e.get()] = root_rows_[ty_index(e->ty)]++;
  };
  for (const Stmt& s : body) {
    switch (s.kind) {
      case StmtKind::Assemble: root(s.value), root(s.index); break;
      case StmtKind::Check: root(s.value); break;
      case StmtKind::If:
        root(s.value);
        count_roots(s.body);
        count_roots(s.orelse);
        break;
      default: break;
    }
  }
}

// Elements first .. first + kLanes - 1 (those past `end` compute element end - 1 again, and
// their statements do not run): every value for all lanes, then the statements lane by lane.
void Emitter::run_lanes(Value* first, Value* end) {
  llvm::Type* i32 = b_.getInt32Ty();
  Value* last = b_.CreateSub(end, b_.getInt32(1));
  element_lane_.clear();
  endpoint_lane_.assign(static_cast<size_t>(t_->arity), {});
  for (int l = 0; l < kLanes; ++l) {
    Value* e = b_.CreateAdd(first, b_.getInt32(static_cast<uint32_t>(l)));
    if (l > 0) e = b_.CreateSelect(b_.CreateICmpSLT(e, end), e, last);
    visit(e);
    element_lane_.push_back(e);
    for (int k = 0; k < t_->arity; ++k) endpoint_lane_[static_cast<size_t>(k)].push_back(endpoints_[k]);
  }
  vmemo_.clear();
  spilled_.clear();
  vlocal_.assign(local_types_.size(), nullptr);
  lanes_block(t_->body);
  if (!pending_.empty()) flush_pending(root_rows_[0] - static_cast<int>(pending_.size()));
  Value* left = b_.CreateSub(end, first);
  Value* count = b_.CreateSelect(b_.CreateICmpSLT(left, b_.getInt32(kLanes)), left,
                                 b_.getInt32(kLanes));
  loop(llvm::ConstantInt::get(i32, 0), count, [&](Value* l) {
    lane_ = b_.CreateSExt(l, b_.getInt64Ty());
    visit(b_.CreateAdd(first, l));
    block(t_->body);
    lane_ = nullptr;
  });
}

void Emitter::lanes_block(const std::vector<Stmt>& body) {
  for (const Stmt& s : body) {
    switch (s.kind) {
      case StmtKind::SetLocal: vlocal_[s.slot] = lanes(*s.value); break;
      case StmtKind::Assemble:
        spill(*s.value);
        if (s.index) spill(*s.index);
        break;
      case StmtKind::Check: spill(*s.value); break;
      case StmtKind::If:
        spill(*s.value);
        lanes_block(s.body);
        lanes_block(s.orelse);
        break;
      default: break;  // Store, Decompose: not in a trace that runs in lanes
    }
  }
}

// A root's value for every lane goes to the buffer. Integers and truth values lie row by
// row (row * kLanes + lane); floats lie lane by lane (lane * stride + row), so that one
// element's block is contiguous and its additions take four components at a time: each four
// rows are transposed in registers before they are stored.
void Emitter::spill(const Expr& e) {
  if (trivial(e) || !spilled_.insert(&e).second) return;
  Value* v = lanes(e);
  const int t = ty_index(e.ty);
  if (e.ty == Ty::F64) {
    pending_.push_back(v);
    if (kLanes == 4 && pending_.size() == 4) flush_pending(roots_.at(&e) - 3);
    return;
  }
  if (e.ty == Ty::Bool) v = b_.CreateZExt(v, llvm::FixedVectorType::get(b_.getInt8Ty(), kLanes));
  llvm::Type* elem = e.ty == Ty::I32 ? b_.getInt32Ty() : b_.getInt8Ty();
  Value* at = b_.CreateConstInBoundsGEP1_64(elem, root_buffer_[t],
                                            static_cast<uint64_t>(roots_.at(&e)) * kLanes);
  b_.CreateAlignedStore(v, at, llvm::Align(8));
}

// Stores the pending float rows first, first + 1, ...: four of them transposed (one vector
// per lane), fewer component by component.
void Emitter::flush_pending(int first) {
  llvm::Type* f64 = b_.getDoubleTy();
  auto at = [&](int lane, int row) {
    return b_.CreateConstInBoundsGEP1_64(
        f64, root_buffer_[0], static_cast<uint64_t>(lane) * root_stride_ + static_cast<uint64_t>(row));
  };
  if (pending_.size() == 4 && kLanes == 4) {
    Value *v0 = pending_[0], *v1 = pending_[1], *v2 = pending_[2], *v3 = pending_[3];
    Value* a = b_.CreateShuffleVector(v0, v1, {0, 4, 2, 6});
    Value* b = b_.CreateShuffleVector(v0, v1, {1, 5, 3, 7});
    Value* c = b_.CreateShuffleVector(v2, v3, {0, 4, 2, 6});
    Value* d = b_.CreateShuffleVector(v2, v3, {1, 5, 3, 7});
    Value* lane[4] = {b_.CreateShuffleVector(a, c, {0, 1, 4, 5}),
                      b_.CreateShuffleVector(b, d, {0, 1, 4, 5}),
                      b_.CreateShuffleVector(a, c, {2, 3, 6, 7}),
                      b_.CreateShuffleVector(b, d, {2, 3, 6, 7})};
    for (int l = 0; l < 4; ++l) b_.CreateAlignedStore(lane[l], at(l, first), llvm::Align(8));
  } else {
    for (size_t r = 0; r < pending_.size(); ++r)
      for (int l = 0; l < kLanes; ++l)
        b_.CreateStore(b_.CreateExtractElement(pending_[r], static_cast<uint64_t>(l)),
                       at(l, first + static_cast<int>(r)));
  }
  pending_.clear();
}

Value* Emitter::root_address(int row) {
  return b_.CreateInBoundsGEP(
      b_.getDoubleTy(), root_buffer_[0],
      b_.CreateAdd(b_.CreateMul(lane_, b_.getInt64(root_stride_)), b_.getInt64(static_cast<uint64_t>(row))));
}

Value* Emitter::load_root(Ty t, int row) {
  if (t == Ty::F64) return b_.CreateLoad(b_.getDoubleTy(), root_address(row));
  llvm::Type* elem = t == Ty::I32 ? b_.getInt32Ty() : b_.getInt8Ty();
  Value* at = b_.CreateInBoundsGEP(
      elem, root_buffer_[ty_index(t)],
      b_.CreateAdd(b_.getInt64(static_cast<uint64_t>(row) * kLanes), lane_));
  Value* v = b_.CreateLoad(elem, at);
  return t == Ty::Bool ? b_.CreateICmpNE(v, b_.getInt8(0)) : v;
}

Value* Emitter::lanes(const Expr& e) {
  auto it = vmemo_.find(&e);
  if (it != vmemo_.end()) return it->second;
  Value* v = lanes_uncached(e);
  vmemo_.emplace(&e, v);
  return v;
}

Value* Emitter::lanes_uncached(const Expr& e) {
  auto gather = [&](const std::vector<Value*>& per_lane) {
    Value* v = llvm::PoisonValue::get(llvm::FixedVectorType::get(per_lane[0]->getType(), kLanes));
    for (int l = 0; l < kLanes; ++l)
      v = b_.CreateInsertElement(v, per_lane[static_cast<size_t>(l)], static_cast<uint64_t>(l));
    return v;
  };
  switch (e.kind) {
    case ExprKind::Const:
    case ExprKind::Scalar: return b_.CreateVectorSplat(kLanes, expr(e));
    case ExprKind::Element: return gather(element_lane_);
    case ExprKind::Endpoint: return gather(endpoint_lane_[static_cast<size_t>(e.slot)]);
    case ExprKind::Load: {
      const Expr& at = *e.ops[0];
      std::vector<Value*> index, values;
      if (at.kind == ExprKind::Element) {
        index = element_lane_;
      } else if (at.kind == ExprKind::Endpoint) {
        index = endpoint_lane_[static_cast<size_t>(at.slot)];
      } else {
        Value* v = lanes(at);
        for (int l = 0; l < kLanes; ++l) index.push_back(b_.CreateExtractElement(v, l));
      }
      for (Value* i : index) values.push_back(load(e, i));
      return gather(values);
    }
    case ExprKind::Local: return vlocal_[static_cast<size_t>(e.slot)];
    default: {
      std::vector<Value*> args;
      for (const ExprRef& o : e.ops) args.push_back(lanes(*o));
      return combine(e, args);
    }
  }
}


void Emitter::block(const std::vector<Stmt>& body) {
  for (size_t i = 0; i < body.size();) {
    const int n = body[i].kind == StmtKind::Assemble ? assemble_run(body, i) : 1;
    if (n > 1)
      assemble(&body[i], n);
    else
      stmt(body[i]);
    i += static_cast<size_t>(n);
  }
}

llvm::Function* Emitter::run(const std::string& name) {
  llvm::Type* ptr = b_.getPtrTy();
  auto* ft = llvm::FunctionType::get(b_.getInt32Ty(),
                                     {ptr, ptr, ptr, b_.getInt32Ty(), b_.getInt32Ty(), ptr}, false);
  fn_ = llvm::Function::Create(ft, llvm::Function::ExternalLinkage, name, m_);
  auto arg = fn_->arg_begin();
  Value *arrays = &*arg++, *scalars = &*arg++, *endpoints = &*arg++;
  Value *begin = &*arg++, *end = &*arg++;
  failed_ = &*arg;
  for (int i = 0; i < 3; ++i) fn_->addParamAttr(i, llvm::Attribute::NoAlias);

  auto* entry = llvm::BasicBlock::Create(ctx_, "entry", fn_);
  b_.SetInsertPoint(entry);
  if (!t_->writes_fields) {
    llvm::MDBuilder md(ctx_);
    llvm::MDNode* domain = md.createAnonymousAliasScopeDomain("arrays");
    inputs_ = llvm::MDNode::get(ctx_, {md.createAnonymousAliasScope(domain, "inputs")});
    results_ = llvm::MDNode::get(ctx_, {md.createAnonymousAliasScope(domain, "results")});
  }
  // Everything invariant over the elements is read once, before the loop.
  for (size_t i = 0; i < slots_.size(); ++i)
    arrays_.push_back(
        b_.CreateLoad(ptr, b_.CreateConstInBoundsGEP1_64(ptr, arrays, i), slots_[i].name));
  for (size_t i = 0; i < t_->scalars.size(); ++i)
    scalars_.push_back(b_.CreateLoad(b_.getDoubleTy(),
                                     b_.CreateConstInBoundsGEP1_64(b_.getDoubleTy(), scalars, i)));
  // Locals set once are SSA values; the others (assigned in branches) live in stack slots.
  ssa_.assign(local_types_.size(), nullptr);
  for (size_t i = 0; i < local_types_.size(); ++i) {
    const bool slot = i >= t_->local_mutable.size() || t_->local_mutable[i];
    locals_.push_back(slot ? b_.CreateAlloca(type(local_types_[i])) : nullptr);
  }

  auto* head = llvm::BasicBlock::Create(ctx_, "element", fn_);
  auto* body = llvm::BasicBlock::Create(ctx_, "body", fn_);
  auto* done = llvm::BasicBlock::Create(ctx_, "done", fn_);
  b_.CreateBr(head);
  b_.SetInsertPoint(head);
  llvm::PHINode* e = b_.CreatePHI(b_.getInt32Ty(), 2, "e");
  e->addIncoming(begin, entry);
  b_.CreateCondBr(b_.CreateICmpSLT(e, end), body, done);
  b_.SetInsertPoint(body);
  endpoint_table_ = endpoints;
  const bool in_lanes = lanes_fit(*t_);
  if (in_lanes) {
    count_roots(t_->body);
    llvm::IRBuilder<> at_entry(entry, entry->begin());
    llvm::Type* types[3] = {b_.getDoubleTy(), b_.getInt32Ty(), b_.getInt8Ty()};
    root_stride_ = static_cast<uint64_t>((root_rows_[0] + 3) / 4 * 4);
    for (int t = 0; t < 3; ++t) {
      if (root_rows_[t] == 0) continue;
      const int rows = t == 0 ? static_cast<int>(root_stride_) : root_rows_[t];
      llvm::AllocaInst* a = at_entry.CreateAlloca(
          types[t], b_.getInt32(static_cast<uint32_t>(rows * kLanes)));
      a->setAlignment(llvm::Align(32));
      root_buffer_[t] = a;
    }
    run_lanes(e, end);
  } else {
    visit(e);
    block(t_->body);
  }
  Value* next = b_.CreateAdd(e, b_.getInt32(in_lanes ? kLanes : 1));
  e->addIncoming(next, b_.GetInsertBlock());
  b_.CreateBr(head);
  b_.SetInsertPoint(done);
  b_.CreateRet(b_.getInt32(0));
  return fn_;
}

void Emitter::load_arrays(Value* arrays) {
  llvm::Type* ptr = b_.getPtrTy();
  for (size_t i = 0; i < slots_.size(); ++i)
    arrays_.push_back(
        b_.CreateLoad(ptr, b_.CreateConstInBoundsGEP1_64(ptr, arrays, i), slots_[i].name));
}

void Emitter::loop(Value* begin, Value* end, const std::function<void(Value*)>& body) {
  llvm::BasicBlock* pre = b_.GetInsertBlock();
  auto* head = llvm::BasicBlock::Create(ctx_, "loop", fn_);
  auto* inside = llvm::BasicBlock::Create(ctx_, "loop.body", fn_);
  auto* done = llvm::BasicBlock::Create(ctx_, "loop.done", fn_);
  b_.CreateBr(head);
  b_.SetInsertPoint(head);
  llvm::PHINode* i = b_.CreatePHI(begin->getType(), 2);
  i->addIncoming(begin, pre);
  b_.CreateCondBr(b_.CreateICmpSLT(i, end), inside, done);
  b_.SetInsertPoint(inside);
  body(i);
  i->addIncoming(b_.CreateAdd(i, llvm::ConstantInt::get(begin->getType(), 1)), b_.GetInsertBlock());
  b_.CreateBr(head);
  b_.SetInsertPoint(done);
}

// One op of a system trace. A product runs row block by row block: each component's sum
// over the row's blocks in pattern order, then the fused body for each component of the row.
void Emitter::vector_op(const VectorOp& op, const std::vector<Value*>& sizes) {
  switch (op.kind) {
    case VectorOp::Kind::Scalar: return block(op.body);
    case VectorOp::Kind::Pass:
      if (op.group > 1 && !op.sums.empty()) {
        Value* runs = b_.CreateSDiv(sizes[op.length], b_.getInt64(op.group));
        Value* begin = b_.getInt64(0);
        if (pass_in_lanes(op)) {
          // Four runs at a time in vectors; the runs left over one by one.
          Value* quads = b_.CreateSDiv(runs, b_.getInt64(kLanes));
          loop(begin, quads, [&](Value* q) {
            runs_in_lanes(op, b_.CreateMul(q, b_.getInt64(kLanes * op.group)));
          });
          begin = b_.CreateMul(quads, b_.getInt64(kLanes));
        }
        return loop(begin, runs, [&](Value* e) {
          run_of(op, b_.CreateMul(e, b_.getInt64(op.group)), op.group);
        });
      }
      return loop(b_.getInt32(0), b_.CreateTrunc(sizes[op.length], b_.getInt32Ty()), [&](Value* k) {
        element_ = k;
        block(op.body);
      });
    case VectorOp::Kind::SpMV: {
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
      auto* vec = llvm::FixedVectorType::get(f64, width);
      Value* sums;
      {
        llvm::IRBuilder<> entry(&fn_->getEntryBlock(), fn_->getEntryBlock().begin());
        sums = entry.CreateAlloca(vec);
      }
      loop(b_.getInt64(0), sizes[op.rows], [&](Value* r) {
        b_.CreateStore(llvm::ConstantFP::get(vec, 0.0), sums);
        Value* lo = b_.CreateSExt(
            b_.CreateLoad(b_.getInt32Ty(),
                          b_.CreateInBoundsGEP(b_.getInt32Ty(), arrays_[op.row_ptr], r)),
            i64);
        Value* hi =
            b_.CreateSExt(b_.CreateLoad(b_.getInt32Ty(),
                                        b_.CreateInBoundsGEP(b_.getInt32Ty(), arrays_[op.row_ptr],
                                                             b_.CreateAdd(r, b_.getInt64(1)))),
                          i64);
        loop(lo, hi, [&](Value* k) {
          Value* col = b_.CreateSExt(
              b_.CreateLoad(b_.getInt32Ty(),
                            b_.CreateInBoundsGEP(b_.getInt32Ty(), arrays_[op.cols], k)),
              i64);
          Value* blk = b_.CreateMul(k, b_.getInt64(bs * bs));
          Value* xc = b_.CreateMul(col, b_.getInt64(bs));
          Value* part = nullptr;
          for (int j = 0; j < bs; ++j) {
            llvm::LoadInst* a =
                b_.CreateLoad(vec, b_.CreateInBoundsGEP(f64, arrays_[op.values],
                                                        b_.CreateAdd(blk, b_.getInt64(j * bs))));
            a->setAlignment(llvm::Align(8));
            Value* x = b_.CreateLoad(
                f64, b_.CreateInBoundsGEP(f64, arrays_[op.x], b_.CreateAdd(xc, b_.getInt64(j))));
            Value* term = b_.CreateFMul(a, b_.CreateVectorSplat(width, x));
            part = part ? b_.CreateFAdd(part, term) : term;
          }
          b_.CreateStore(b_.CreateFAdd(b_.CreateLoad(vec, sums), part), sums);
        });
        Value* row = b_.CreateMul(r, b_.getInt64(bs));
        Value* total = b_.CreateLoad(vec, sums);
        for (int i = 0; i < bs; ++i)
          b_.CreateStore(
              b_.CreateExtractElement(total, static_cast<uint64_t>(i)),
              b_.CreateInBoundsGEP(f64, arrays_[op.y], b_.CreateAdd(row, b_.getInt64(i))));
        run_of(op, row, bs);
      });
      return;
    }
  }
}

// Whether a pass with sums by runs can take four runs at a time in vectors: its statements
// store components of vectors at the visited component, or add a term to one of its sums, and
// read only components at the visited component, constants and other scalars.
bool Emitter::pass_in_lanes(const VectorOp& op) const {
  if (kLanes != 4) return false;
  auto is_sum = [&](int slot) {
    return std::find(op.sums.begin(), op.sums.end(), slot) != op.sums.end();
  };
  std::function<bool(const Expr&)> lane_wise = [&](const Expr& e) {
    switch (e.kind) {
      case ExprKind::Const: return e.ty == Ty::F64;
      case ExprKind::Local: return e.ty == Ty::F64 && !is_sum(e.slot);
      case ExprKind::Load:
        return e.ty == Ty::F64 && !slots_[static_cast<size_t>(e.slot)].single &&
               slots_[static_cast<size_t>(e.slot)].components == 1 &&
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
      if (a.ty != Ty::F64 || a.single || a.components != 1 || s.comp != 0 ||
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
Value* Emitter::pass_lanes(const Expr& e, Value* first) {
  llvm::Type* f64 = b_.getDoubleTy();
  auto* vec = llvm::FixedVectorType::get(f64, kLanes);
  switch (e.kind) {
    case ExprKind::Const: return llvm::ConstantFP::get(vec, e.f);
    case ExprKind::Local: return b_.CreateVectorSplat(kLanes, b_.CreateLoad(f64, locals_[e.slot]));
    case ExprKind::Load: {
      llvm::LoadInst* v =
          b_.CreateLoad(vec, b_.CreateInBoundsGEP(f64, arrays_[static_cast<size_t>(e.slot)], first));
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
// added in order, and the parts added to the sum run by run: the order run_of adds them in.
void Emitter::runs_in_lanes(const VectorOp& op, Value* first) {
  const int g = op.group;
  std::vector<std::vector<Value*>> terms(op.sums.size());
  for (int v = 0; v < g; ++v) {
    Value* at = b_.CreateAdd(first, b_.getInt64(kLanes * v));
    for (const Stmt& s : op.body) {
      if (s.kind == StmtKind::Store) {
        llvm::StoreInst* st = b_.CreateStore(
            pass_lanes(*s.value, at),
            b_.CreateInBoundsGEP(b_.getDoubleTy(), arrays_[static_cast<size_t>(s.slot)], at));
        st->setAlignment(llvm::Align(8));
        continue;
      }
      const size_t k = static_cast<size_t>(
          std::find(op.sums.begin(), op.sums.end(), s.slot) - op.sums.begin());
      terms[k].push_back(pass_lanes(*s.value->ops[1], at));
    }
  }
  for (size_t k = 0; k < op.sums.size(); ++k) {
    // Every statement adds one term per component; with several statements for one sum the
    // component's terms follow one another.
    const size_t per = terms[k].size() / static_cast<size_t>(g);
    Value* total = b_.CreateLoad(b_.getDoubleTy(), locals_[op.sums[k]]);
    for (int run = 0; run < kLanes; ++run) {
      Value* part = nullptr;
      for (int c = run * g; c < (run + 1) * g; ++c)
        for (size_t t = 0; t < per; ++t) {
          Value* term = b_.CreateExtractElement(
              terms[k][static_cast<size_t>(c / kLanes) * per + t], static_cast<uint64_t>(c % kLanes));
          part = part ? b_.CreateFAdd(part, term) : term;
        }
      total = b_.CreateFAdd(total, part);
    }
    b_.CreateStore(total, locals_[op.sums[k]]);
  }
}

// A sum's run part needs no +0.0 start either: its total starts at +0.0 (see the product).
void Emitter::run_of(const VectorOp& op, Value* first, int group) {
  std::vector<Value*> totals;
  const bool runs = group > 1 && !op.sums.empty();
  if (runs) {
    for (int s : op.sums) {
      totals.push_back(b_.CreateLoad(b_.getDoubleTy(), locals_[s]));
      b_.CreateStore(llvm::ConstantFP::get(b_.getDoubleTy(), -0.0), locals_[s]);
    }
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
      b_.CreateStore(b_.CreateFAdd(totals[k], part), locals_[op.sums[k]]);
    }
  }
}

// int32_t fn(void* const* arrays, double* scalars, const int64_t* sizes): the program's
// scalars in and out through `scalars`, the while loop in between.
llvm::Function* Emitter::run_system(const std::string& name) {
  llvm::Type* ptr = b_.getPtrTy();
  auto* ft = llvm::FunctionType::get(b_.getInt32Ty(), {ptr, ptr, ptr}, false);
  fn_ = llvm::Function::Create(ft, llvm::Function::ExternalLinkage, name, m_);
  auto arg = fn_->arg_begin();
  Value *arrays = &*arg++, *scalars = &*arg++, *sizes_in = &*arg;
  auto* entry = llvm::BasicBlock::Create(ctx_, "entry", fn_);
  b_.SetInsertPoint(entry);
  load_arrays(arrays);
  for (Ty t : local_types_) locals_.push_back(b_.CreateAlloca(type(t)));
  llvm::Type* f64 = b_.getDoubleTy();
  for (int i = 0; i < st_->scalars; ++i) {
    Value* d = b_.CreateLoad(f64, b_.CreateConstInBoundsGEP1_64(f64, scalars, i));
    const Ty t = local_types_[i];
    Value* v = t == Ty::F64   ? d
               : t == Ty::I32 ? b_.CreateFPToSI(d, b_.getInt32Ty())
                              : b_.CreateFCmpUNE(d, llvm::ConstantFP::get(f64, 0.0));
    b_.CreateStore(v, locals_[i]);
  }
  std::vector<Value*> sizes;
  for (size_t i = 0; i < st_->sizes.size(); ++i)
    sizes.push_back(b_.CreateLoad(b_.getInt64Ty(),
                                  b_.CreateConstInBoundsGEP1_64(b_.getInt64Ty(), sizes_in, i)));
  auto* head = llvm::BasicBlock::Create(ctx_, "while", fn_);
  auto* body = llvm::BasicBlock::Create(ctx_, "while.body", fn_);
  auto* done = llvm::BasicBlock::Create(ctx_, "while.done", fn_);
  b_.CreateBr(head);
  b_.SetInsertPoint(head);
  b_.CreateCondBr(expr(*st_->condition), body, done);
  b_.SetInsertPoint(body);
  for (const VectorOp& op : st_->body) vector_op(op, sizes);
  b_.CreateBr(head);
  b_.SetInsertPoint(done);
  for (int i = 0; i < st_->scalars; ++i) {
    const Ty t = local_types_[i];
    Value* v = b_.CreateLoad(type(t), locals_[i]);
    Value* d = t == Ty::F64 ? v : t == Ty::I32 ? b_.CreateSIToFP(v, f64) : b_.CreateUIToFP(v, f64);
    b_.CreateStore(d, b_.CreateConstInBoundsGEP1_64(f64, scalars, i));
  }
  b_.CreateRet(b_.getInt32(0));
  return fn_;
}

void optimise(llvm::Module& m, llvm::TargetMachine& tm, int level_number) {
  llvm::LoopAnalysisManager lam;
  llvm::FunctionAnalysisManager fam;
  llvm::CGSCCAnalysisManager cgam;
  llvm::ModuleAnalysisManager mam;
  // As clang at -O2: the loop and SLP vectorizers on (lane-wise IEEE operations, no
  // reassociation: the bits do not change).
  llvm::PipelineTuningOptions tuning;
  tuning.LoopVectorization = level_number >= 2;
  tuning.SLPVectorization = level_number >= 2;
  llvm::PassBuilder pb(&tm, tuning);
  pb.registerModuleAnalyses(mam);
  pb.registerCGSCCAnalyses(cgam);
  pb.registerFunctionAnalyses(fam);
  pb.registerLoopAnalyses(lam);
  pb.crossRegisterProxies(lam, fam, cgam, mam);
  const llvm::OptimizationLevel level = level_number >= 3   ? llvm::OptimizationLevel::O3
                                        : level_number == 2 ? llvm::OptimizationLevel::O2
                                                            : llvm::OptimizationLevel::O1;
  llvm::ModulePassManager mpm = pb.buildPerModuleDefaultPipeline(level);
  mpm.run(m, mam);
}

class CpuBackend : public Backend {
 public:
  CpuBackend(Session& s, const HostCalls& host) : s_(s), host_(host) {}

  std::unique_ptr<Kernel> compile(const Trace& trace, bool keep_ir, std::string& error) override {
    const bool large = node_count(trace) > kLargeTrace;
    const int level = !large              ? kOptLevel
                      : lanes_fit(trace) ? kLargeLanesTraceOptLevel
                                         : kLargeTraceOptLevel;
    auto k = build(level, keep_ir, error, [&](llvm::Module& m, const std::string& name) {
      return Emitter(trace, m, host_).run(name);
    });
    if (k) {
      k->fn = reinterpret_cast<KernelFn>(k->address);
      k->lanes = lanes_fit(trace) ? kLanes : 1;
    }
    return k;
  }
  std::unique_ptr<Kernel> compile(const SystemTrace& trace, bool keep_ir,
                                  std::string& error) override {
    auto k = build(kOptLevel, keep_ir, error, [&](llvm::Module& m, const std::string& name) {
      return Emitter(trace, m).run_system(name);
    });
    if (k) k->system = reinterpret_cast<SystemFn>(k->address);
    return k;
  }

 private:
  // Emits a function into a new module, optimises it for the host and links it.
  std::unique_ptr<CpuKernel> build(
      int level, bool keep_ir, std::string& error,
      const std::function<llvm::Function*(llvm::Module&, const std::string&)>& emit) {
    const auto start = std::chrono::steady_clock::now();
    static std::atomic<int> serial{0};
    const std::string name = "simit_kernel_" + std::to_string(serial++);
    auto ctx = std::make_unique<llvm::LLVMContext>();
    auto mod = std::make_unique<llvm::Module>(name, *ctx);
    mod->setDataLayout(s_.jit().getDataLayout());
    mod->setTargetTriple(s_.target().getTargetTriple().str());
    llvm::Function* fn = emit(*mod, name);
    fn->addFnAttr("target-cpu", s_.target().getTargetCPU());
    fn->addFnAttr("target-features", s_.target().getTargetFeatureString());
    std::string broken;
    llvm::raw_string_ostream bs(broken);
    if (llvm::verifyModule(*mod, &bs)) {
      error = "LLVM rejected the generated code: " + bs.str();
      return nullptr;
    }
    if (level > 0) optimise(*mod, s_.target(), level);
    std::string ir;
    if (keep_ir) {
      llvm::raw_string_ostream os(ir);
      mod->print(os, nullptr);
    }
    auto rt = s_.jit().getMainJITDylib().createResourceTracker();
    if (llvm::Error e =
            s_.jit().addIRModule(rt, llvm::orc::ThreadSafeModule(std::move(mod), std::move(ctx)))) {
      error = message_of(std::move(e));
      return nullptr;
    }
    auto sym = s_.jit().lookup(name);
    if (!sym) {
      error = message_of(sym.takeError());
      llvm::consumeError(rt->remove());
      return nullptr;
    }
    auto k = std::make_unique<CpuKernel>(rt);
    k->address = sym->toPtr<void*>();
    k->llvm_ir = std::move(ir);
    k->compile_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return k;
  }

 private:
  Session& s_;
  HostCalls host_;
};

}  // namespace

std::unique_ptr<Backend> make_cpu_backend(const HostCalls& host, std::string& error) {
  Session* s = Session::get(error);
  if (!s) return nullptr;
  return std::make_unique<CpuBackend>(*s, host);
}

}  // namespace simit::jit
