// The tracer's calls (jit/trace/tracer.h): intrinsics unrolled into components, the
// decompositions as calls into the runtime, and user functions inlined.
#include "jit/trace/tracer.h"

namespace simit::jit::trace_detail {

// det of the submatrix (rows x cols) of the n x n matrix a, by cofactor expansion along its
// first row, as runtime/dense_linalg.cpp computes it.
ExprRef Tracer::det(const std::vector<ExprRef>& a, int n, const std::vector<int>& rows,
                    const std::vector<int>& cols) {
  const size_t m = rows.size();
  if (m == 1) return a[static_cast<size_t>(rows[0]) * n + cols[0]];
  ExprRef sum = fconst(0.0);
  for (size_t j = 0; j < m; ++j) {
    std::vector<int> sub;
    for (size_t c = 0; c < m; ++c)
      if (c != j) sub.push_back(cols[c]);
    ExprRef minor = det(a, n, std::vector<int>(rows.begin() + 1, rows.end()), sub);
    if (j % 2) minor = build_.unary(UnOp::Neg, Ty::F64, minor);
    sum = build_.binary(
        BinOp::Add, Ty::F64, sum,
        build_.binary(BinOp::Mul, Ty::F64, a[static_cast<size_t>(rows[0]) * n + cols[j]], minor));
  }
  return sum;
}

Sym Tracer::eval_intrinsic(const ast::Call& c) {
  using frontend::Intrinsic;
  if (c.intrinsic == Intrinsic::ProjectSpd || c.intrinsic == Intrinsic::ProjectSpdAbs)
    return decompose(c)[0];
  std::vector<Sym> a;
  for (const auto& arg : c.args) {
    a.push_back(settle(eval(*arg), c.span));
    if (a.back().kind != Sym::Kind::Tensor) give_up(c.span, AbortReason::IntrinsicOfNonTensor);
    if (a.back().blocked())
      give_up(c.span, AbortReason::IntrinsicOfBlocked, frontend::intrinsic_name(c.intrinsic));
  }
  auto f1 = [&](MathFn f) {
    if (!a[0].scalar() || a[0].ty != Ty::F64) give_up(c.span, AbortReason::MathOfNonFloat);
    return scalar(Ty::F64, build_.math(f, {a[0].c[0]}, c.span));
  };
  auto f2 = [&](MathFn f) {
    if (!a[0].scalar() || !a[1].scalar() || a[0].ty != Ty::F64 || a[1].ty != Ty::F64)
      give_up(c.span, AbortReason::MathOfNonFloat);
    return scalar(Ty::F64, build_.math(f, {a[0].c[0], a[1].c[0]}, c.span));
  };
  auto dot = [&](const Sym& x, const Sym& y) {
    if (x.ty != Ty::F64 || y.ty != Ty::F64 || x.size() != y.size())
      give_up(c.span, AbortReason::IntrinsicOperands, "dot");
    ExprRef s = fconst(0.0);
    for (size_t i = 0; i < x.size(); ++i) s = sum_add(s, sum_mul(x.c[i], y.c[i], c.span), c.span);
    return s;
  };
  auto square = [&](const Sym& m) {
    if (m.dims.size() != 2 || m.dims[0] != m.dims[1] || m.dims[0] < 2 || m.dims[0] > 4 ||
        m.ty != Ty::F64)
      give_up(c.span, AbortReason::DetOrInvShape);
    return m.dims[0];
  };
  Sym v;
  switch (c.intrinsic) {
    case Intrinsic::Mod:
      if (!a[0].scalar() || !a[1].scalar() || a[0].ty != Ty::I32 || a[1].ty != Ty::I32)
        give_up(c.span, AbortReason::ModOfNonIntegers);
      check_divisors(a[1], "mod by zero", c.span);
      v = scalar(Ty::I32, build_.binary(BinOp::Mod, Ty::I32, a[0].c[0], a[1].c[0], c.span));
      break;
    case Intrinsic::Sin: v = f1(MathFn::Sin); break;
    case Intrinsic::Cos: v = f1(MathFn::Cos); break;
    case Intrinsic::Tan: v = f1(MathFn::Tan); break;
    case Intrinsic::Asin: v = f1(MathFn::Asin); break;
    case Intrinsic::Acos: v = f1(MathFn::Acos); break;
    case Intrinsic::Sqrt: v = f1(MathFn::Sqrt); break;
    case Intrinsic::Cbrt: v = f1(MathFn::Cbrt); break;
    case Intrinsic::Log: v = f1(MathFn::Log); break;
    case Intrinsic::Exp: v = f1(MathFn::Exp); break;
    case Intrinsic::Abs: v = f1(MathFn::Abs); break;
    case Intrinsic::Atan2: v = f2(MathFn::Atan2); break;
    case Intrinsic::Pow: v = f2(MathFn::Pow); break;
    case Intrinsic::Max: v = f2(MathFn::Max); break;
    case Intrinsic::Min: v = f2(MathFn::Min); break;
    case Intrinsic::Dot: v = scalar(Ty::F64, dot(a[0], a[1])); break;
    case Intrinsic::Norm:
      v = scalar(Ty::F64, build_.math(MathFn::Sqrt, {dot(a[0], a[0])}, c.span));
      break;
    case Intrinsic::Cross: {
      if (a[0].size() != 3 || a[1].size() != 3 || a[0].ty != Ty::F64)
        give_up(c.span, AbortReason::IntrinsicOperands, "cross");
      const auto& x = a[0].c;
      const auto& y = a[1].c;
      auto term = [&](int i, int j, int k, int l) {
        return build_.binary(BinOp::Sub, Ty::F64,
                             build_.binary(BinOp::Mul, Ty::F64, x[i], y[j], c.span),
                             build_.binary(BinOp::Mul, Ty::F64, x[k], y[l], c.span), c.span);
      };
      v = tensor(Ty::F64, {3}, {term(1, 2, 2, 1), term(2, 0, 0, 2), term(0, 1, 1, 0)});
      break;
    }
    case Intrinsic::Det:
    case Intrinsic::Det2:
    case Intrinsic::Det4: {
      const int n = square(a[0]);
      std::vector<int> all(n);
      for (int i = 0; i < n; ++i) all[i] = i;
      v = scalar(Ty::F64, det(a[0].c, n, all, all));
      break;
    }
    case Intrinsic::Inv:
    case Intrinsic::Inv2:
    case Intrinsic::Inv4: {
      const int n = square(a[0]);
      std::vector<int> all(n);
      for (int i = 0; i < n; ++i) all[i] = i;
      const ExprRef d = settle(det(a[0].c, n, all, all), c.span);
      // The interpreter's singular-matrix error: the controller re-runs the site to report it.
      emit_check(build_.compare(CmpOp::Ne, d, fconst(0.0), c.span),
                 "inverse of a singular matrix (determinant is 0)", c.span);
      std::vector<ExprRef> out(static_cast<size_t>(n) * n);
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          std::vector<int> rows, cols;
          for (int r = 0; r < n; ++r)
            if (r != i) rows.push_back(r);
          for (int q = 0; q < n; ++q)
            if (q != j) cols.push_back(q);
          ExprRef cof = det(a[0].c, n, rows, cols);
          if ((i + j) % 2) cof = build_.unary(UnOp::Neg, Ty::F64, cof);
          out[static_cast<size_t>(j) * n + i] = build_.binary(BinOp::Div, Ty::F64, cof, d, c.span);
        }
      v = tensor(Ty::F64, {n, n}, std::move(out));
      break;
    }
    default: give_up(c.span, AbortReason::Intrinsic, frontend::intrinsic_name(c.intrinsic));
  }
  return finite(round(std::move(v), c.span), c.span);
}

// svd, eig, polar, project_spd: a call into the runtime's decompositions (the interpreter's
// own code, so the bits agree), with its results in new locals.
std::vector<Sym> Tracer::decompose(const ast::Call& c) {
  using frontend::Intrinsic;
  Decomposition d;
  switch (c.intrinsic) {
    case Intrinsic::Svd: d = Decomposition::Svd; break;
    case Intrinsic::Eig: d = Decomposition::Eig; break;
    case Intrinsic::Polar: d = Decomposition::Polar; break;
    case Intrinsic::ProjectSpd: d = Decomposition::ProjectSpd; break;
    case Intrinsic::ProjectSpdAbs: d = Decomposition::ProjectSpdAbs; break;
    default: give_up(c.span, AbortReason::SeveralResultsNotDecomposition);
  }
  if (c.args.size() != 1) give_up(c.span, AbortReason::DecompositionArguments);
  Sym given = settle(eval(*c.args[0]), c.span);
  if (given.kind != Sym::Kind::Tensor || given.ty != Ty::F64 || given.dims.size() != 2)
    give_up(c.span, AbortReason::DecompositionValue);
  // project_spd decomposes a blocked matrix in its unblocked form (runtime/decompositions.h);
  // the others take unblocked matrices only.
  const bool blocked = given.blocked();
  if (blocked && (!has_logical_form(given) ||
                  (d != Decomposition::ProjectSpd && d != Decomposition::ProjectSpdAbs)))
    give_up(c.span, AbortReason::DecompositionBlocked);
  const Sym a = blocked ? unblocked(given) : given;
  if (a.dims[0] != a.dims[1]) give_up(c.span, AbortReason::DecompositionNotSquare);
  const int n = a.dims[0];
  trace_.errors.push_back(
      {c.span, std::string(frontend::intrinsic_name(c.intrinsic)) + " needs a symmetric matrix"});
  Stmt s;
  if (build_.fold()) ZeroFold::require_exact(a.c, "a decomposition");
  s.kind = StmtKind::Decompose;
  s.fn = static_cast<int>(d);
  s.n = n;
  s.args = a.c;
  s.error = static_cast<int>(trace_.errors.size() - 1);
  s.span = c.span;
  std::vector<Sym> out;
  for (int count : decomposition_results(d, n)) {
    std::vector<ExprRef> comps;
    for (int k = 0; k < count; ++k) {
      const int l = new_local(Ty::F64, false);
      s.outs.push_back(l);
      comps.push_back(read_local(l));
    }
    out.push_back(round(tensor(Ty::F64, count == n ? std::vector<int>{n} : std::vector<int>{n, n},
                               std::move(comps)),
                        c.span));
  }
  emit(std::move(s));
  if (blocked) out[0] = reblocked(out[0], given.dims, given.block);
  for (Sym& r : out) r = finite(std::move(r), c.span);
  return out;
}

Sym Tracer::eval_call(const ast::Call& c) {
  if (c.intrinsic != frontend::Intrinsic::None) return eval_intrinsic(c);
  std::vector<Sym> r = call_user(c);
  if (r.empty()) return {};
  return r[0];
}

std::vector<Sym> Tracer::call_user(const ast::Call& c) {
  const ast::FuncDecl& f = *c.func;
  if (f.is_extern || !f.generics.empty()) give_up(c.span, AbortReason::ExternOrGenericCall);
  if (++inline_depth_ > kMaxInlineDepth) give_up(c.span, AbortReason::InlineTooDeep);
  std::vector<Sym> args;
  for (const auto& a : c.args) args.push_back(settle(eval(*a), c.span));
  Frame callee;
  for (size_t i = 0; i < f.params.size() && i < args.size(); ++i) {
    const ast::Param& p = f.params[i];
    if (p.inout && args[i].kind == Sym::Kind::Tensor)
      give_up(c.span, AbortReason::InoutTensorArgument);
    callee.vars[p.var] = p.var->type ? as_declared(args[i], *p.var->type, c.span) : args[i];
    callee.bound_at[p.var] = static_cast<int>(blocks_.size());
  }
  for (const ast::Param& r : f.results) {
    callee.vars[r.var] = zero_of(*r.var->type, r.span);
    callee.bound_at[r.var] = static_cast<int>(blocks_.size());
  }
  // Loads cached by the caller stay valid: the callee reads the same arrays.
  frames_.push_back(std::move(callee));
  const size_t errors_before = trace_.errors.size();
  exec_block(f.body);
  // A check failing in the callee reports the call stack the interpreter would.
  for (size_t i = errors_before; i < trace_.errors.size(); ++i)
    trace_.errors[i].frames.emplace_back(f.name, c.span);
  std::vector<Sym> out;
  for (const ast::Param& r : f.results) out.push_back(frame().vars[r.var]);
  frames_.pop_back();
  --inline_depth_;
  return out;
}

}  // namespace simit::jit::trace_detail
