// Map and apply kernels: the loop over the elements, expressions and statements one element
// at a time, and the assembly writes (jit/cpu/emitter.h).
#include <llvm/IR/MDBuilder.h>

#include "jit/cpu/emitter.h"

namespace simit::jit::cpu {

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

// x / y or mod(x, y) on int32 (scalars or lanes) without a trap: a divisor of 0 or -1 is
// replaced by 1 (the kernel's check fails first on 0, so that value is never used); by -1 the
// quotient is the wrapping negation and the remainder 0, as the interpreter computes them.
Value* Emitter::int_divide(Value* x, Value* y, bool remainder) {
  llvm::Type* t = y->getType();
  Value* minus_one = b_.CreateICmpEQ(y, llvm::ConstantInt::getSigned(t, -1));
  Value* bad = b_.CreateOr(b_.CreateICmpEQ(y, llvm::ConstantInt::get(t, 0)), minus_one);
  Value* safe = b_.CreateSelect(bad, llvm::ConstantInt::get(t, 1), y);
  if (remainder)
    return b_.CreateSelect(minus_one, llvm::ConstantInt::get(t, 0), b_.CreateSRem(x, safe));
  return b_.CreateSelect(minus_one, b_.CreateSub(llvm::ConstantInt::get(t, 0), x),
                         b_.CreateSDiv(x, safe));
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
        case BinOp::Div: return f ? b_.CreateFDiv(x, y) : int_divide(x, y, false);
        case BinOp::Mod: return int_divide(x, y, true);
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
    case ExprKind::Scratch: return b_.CreateLoad(b_.getDoubleTy(), scratch_at(e.slot, *e.ops[0]));
    default: {
      std::vector<Value*> args;
      for (const ExprRef& o : e.ops) args.push_back(expr(*o));
      return combine(e, args);
    }
  }
}

// Component e.comp (plus ops[1], a loop's counter, where given) of array e.slot at the
// (scalar) element index.
Value* Emitter::load(const Expr& e, Value* index) {
  const ArraySlot& a = slots_[e.slot];
  Value* comp = b_.getInt64(e.comp);
  if (e.ops.size() > 1) comp = b_.CreateAdd(comp, b_.CreateSExt(expr(*e.ops[1]), b_.getInt64Ty()));
  llvm::LoadInst* v = b_.CreateLoad(storage(a), address(e.slot, index, comp));
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
    case StmtKind::Put: b_.CreateStore(expr(*s.value), scratch_at(s.slot, *s.index)); return;
    case StmtKind::For:
      loop(b_.getInt32(0), b_.getInt32(static_cast<uint32_t>(s.n)), [&](Value* i) {
        ssa_[s.slot] = i;
        block(s.body);
      });
      return;
  }
}

Value* Emitter::scratch_at(int slot, const Expr& index) {
  return b_.CreateInBoundsGEP(b_.getDoubleTy(), scratch_[static_cast<size_t>(slot)],
                              b_.CreateSExt(expr(index), b_.getInt64Ty()));
}

// Where the element's block (or vector element) of an Assemble statement starts.
Value* Emitter::assemble_base(const Stmt& s) {
  if (s.pair < 0) return address(s.slot, expr(*s.index), 0);
  // The block's position in the matrix comes from the pattern's per-element table.
  const int result = slots_[s.slot].index;
  int table = -1, marks = -1;
  for (size_t i = 0; i < slots_.size(); ++i) {
    if (slots_[i].index != result) continue;
    if (slots_[i].kind == ArraySlot::Kind::Table) table = static_cast<int>(i);
    if (slots_[i].kind == ArraySlot::Kind::Marks) marks = static_cast<int>(i);
  }
  llvm::LoadInst* pos = b_.CreateLoad(b_.getInt32Ty(), address(table, element_, s.pair));
  tag(pos, table);
  if (marks >= 0) mark(marks, pos);
  return address(s.slot, pos, 0);
}

// While the controller records the blocks a call writes (jit/write_guard.h), `marks` is an
// array of a byte per block and each write sets its block's; otherwise it is null.
void Emitter::mark(int marks, Value* pos) {
  auto* set = llvm::BasicBlock::Create(ctx_, "mark", fn_);
  auto* cont = llvm::BasicBlock::Create(ctx_, "marked", fn_);
  b_.CreateCondBr(b_.CreateIsNotNull(arrays_[marks]), set, cont);
  b_.SetInsertPoint(set);
  tag(b_.CreateStore(b_.getInt8(1), address(marks, pos, 0)), marks);
  b_.CreateBr(cont);
  b_.SetInsertPoint(cont);
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
  load_arrays(arrays);
  for (size_t i = 0; i < t_->scalars.size(); ++i)
    scalars_.push_back(b_.CreateLoad(b_.getDoubleTy(),
                                     b_.CreateConstInBoundsGEP1_64(b_.getDoubleTy(), scalars, i)));
  // Locals set once are SSA values; the others (assigned in branches) live in stack slots.
  ssa_.assign(local_types_.size(), nullptr);
  for (size_t i = 0; i < local_types_.size(); ++i) {
    const bool slot = i >= t_->local_mutable.size() || t_->local_mutable[i];
    locals_.push_back(slot ? b_.CreateAlloca(type(local_types_[i])) : nullptr);
  }
  for (int n : t_->scratch) {
    llvm::AllocaInst* a = b_.CreateAlloca(b_.getDoubleTy(), b_.getInt32(static_cast<uint32_t>(n)));
    a->setAlignment(llvm::Align(32));
    scratch_.push_back(a);
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
    allocate_roots();
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

}  // namespace simit::jit::cpu
