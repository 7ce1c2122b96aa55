// Loop IR expressions to LLVM IR, on scalars or on vectors of one element per lane
// (jit/llvm/emitter.h).
#include <llvm/IR/Constants.h>
#include <llvm/IR/IntrinsicInst.h>

#include "jit/llvm/emitter.h"

namespace simit::jit::codegen {

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
  auto* lanes = llvm::dyn_cast<llvm::FixedVectorType>(args[0]->getType());
  if (!lanes) return hooks_.math(b_, f, args);
  if (Value* all = hooks_.math_lanes(b_, f, args)) return all;
  // Lanes: the same library call once per lane.
  Value* out = llvm::PoisonValue::get(lanes);
  for (unsigned l = 0; l < lanes->getNumElements(); ++l) {
    std::vector<Value*> a;
    for (Value* v : args) a.push_back(b_.CreateExtractElement(v, l));
    out = b_.CreateInsertElement(out, hooks_.math(b_, f, a), l);
  }
  return out;
}

Value* widened_binary32(Value* v) {
  if (auto* ext = llvm::dyn_cast<llvm::FPExtInst>(v))
    if (ext->getSrcTy()->getScalarType()->isFloatTy()) return ext->getOperand(0);
  return nullptr;
}

namespace {

// v as the binary32 value it holds exactly (a widened binary32 value, or a constant that is
// one), or null.
Value* binary32_of(Value* v) {
  if (Value* narrow = widened_binary32(v)) return narrow;
  if (auto* c = llvm::dyn_cast<llvm::Constant>(v)) {
    auto* f = llvm::dyn_cast_or_null<llvm::ConstantFP>(c->getSplatValue());
    if (!f && v->getType()->isDoubleTy()) f = llvm::dyn_cast<llvm::ConstantFP>(c);
    if (!f) return nullptr;
    const double d = f->getValueAPF().convertToDouble();
    const float n = static_cast<float>(d);
    if (static_cast<double>(n) != d && d == d) return nullptr;
    llvm::Type* t = llvm::Type::getFloatTy(v->getContext());
    if (auto* vt = llvm::dyn_cast<llvm::FixedVectorType>(v->getType()))
      return llvm::ConstantVector::getSplat(vt->getElementCount(), llvm::ConstantFP::get(t, n));
    return llvm::ConstantFP::get(t, n);
  }
  return nullptr;
}

}  // namespace

// `--float32` rounds every operation's binary64 result to binary32. For + - * / and sqrt of
// binary32 operands that is exactly the binary32 operation's result (binary64 carries more
// than 2 * 24 + 2 bits, so the double rounding is innocuous), which is computed so instead:
// one instruction, without the two conversions, and the chain of operations stays binary32.
Value* Emitter::in_binary32(Value* x) {
  if (auto* op = llvm::dyn_cast<llvm::BinaryOperator>(x)) {
    switch (op->getOpcode()) {
      case llvm::Instruction::FAdd:
      case llvm::Instruction::FSub:
      case llvm::Instruction::FMul:
      case llvm::Instruction::FDiv: break;
      default: return nullptr;
    }
    Value* a = binary32_of(op->getOperand(0));
    Value* b = binary32_of(op->getOperand(1));
    if (!a || !b) return nullptr;
    return b_.CreateBinOp(op->getOpcode(), a, b);
  }
  if (auto* call = llvm::dyn_cast<llvm::IntrinsicInst>(x))
    if (call->getIntrinsicID() == llvm::Intrinsic::sqrt)
      if (Value* a = binary32_of(call->getArgOperand(0)))
        return b_.CreateUnaryIntrinsic(llvm::Intrinsic::sqrt, a);
  return nullptr;
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
          if (Value* narrow = in_binary32(x)) return b_.CreateFPExt(narrow, x->getType());
          return as_binary32(x);
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
  if (pre_) {
    if (Value* v = pre_->value(e)) return v;
  }
  switch (e.kind) {
    case ExprKind::Const:
      if (e.ty == Ty::F64) return llvm::ConstantFP::get(b_.getDoubleTy(), e.f);
      if (e.ty == Ty::I32) return b_.getInt32(static_cast<uint32_t>(e.i));
      return b_.getInt1(e.i != 0);
    case ExprKind::Scalar: {
      Value* d = scalars_[e.slot];
      // Under --float32 a map's float arguments are binary32 values (the controller runs a
      // call with a wider one interpreted): narrowed and widened again, exactly, so that
      // in_binary32 computes their operations in binary32.
      if (e.ty == Ty::F64 && float32_) return as_binary32(d);
      if (e.ty == Ty::F64) return d;
      if (e.ty == Ty::I32) return b_.CreateFPToSI(d, b_.getInt32Ty());
      return b_.CreateFCmpUNE(d, llvm::ConstantFP::get(b_.getDoubleTy(), 0.0));
    }
    case ExprKind::Element: return element_;
    case ExprKind::Endpoint: return endpoints_[e.slot];
    case ExprKind::Load: return load(e, expr(*e.ops[0]));
    case ExprKind::Local: {
      if (!locals_[e.slot]) return ssa_[e.slot];
      Value* v = b_.CreateLoad(type(e.ty), locals_[e.slot]);
      // Narrowed and widened again, exactly: in_binary32 then computes its operations in
      // binary32 (a compiled loop's step length times a binary32 vector, without widening
      // the vector).
      if (e.ty == Ty::F64 && binary32_local(e.slot)) v = as_binary32(v);
      return v;
    }
    case ExprKind::Scratch: return b_.CreateLoad(b_.getDoubleTy(), scratch_at(e.slot, *e.ops[0]));
    default: {
      std::vector<Value*> args;
      for (const ExprRef& o : e.ops) args.push_back(expr(*o));
      return combine(e, args);
    }
  }
}

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

Value* Emitter::scratch_at(int slot, const Expr& index) {
  return b_.CreateInBoundsGEP(b_.getDoubleTy(), scratch_[static_cast<size_t>(slot)],
                              b_.CreateSExt(expr(index), b_.getInt64Ty()));
}

llvm::AAMDNodes Emitter::alias(int slot) const {
  if (!inputs_) return llvm::AAMDNodes();
  const ArraySlot::Kind k = slots_[static_cast<size_t>(slot)].kind;
  const bool result =
      k == ArraySlot::Kind::Result || k == ArraySlot::Kind::Marks || k == ArraySlot::Kind::Deferred;
  return llvm::AAMDNodes(nullptr, nullptr, result ? results_ : inputs_,
                         result ? inputs_ : results_);
}

}  // namespace simit::jit::codegen
