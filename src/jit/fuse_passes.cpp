// Fusion of a system trace's vector ops: scalar statements move up past passes that do not
// concern them, passes move up to a loop they can join, a reduction over a product's result
// joins the product's row loop, and adjacent passes over vectors of one length become one
// loop. A CG iteration ends as three loops: the product with p'Ap, the x and r updates with
// r'r, the p update; a preconditioned one as four (the second product with r'z, and r'r
// with the p update).
#include <algorithm>
#include <set>

#include "jit/loop_ir.h"

namespace simit::jit {

namespace {

struct Uses {
  std::set<int> reads, writes;  // locals
  std::set<int> array_reads, array_writes;
};

void expr_uses(const Expr& e, Uses& u) {
  if (e.kind == ExprKind::Local) u.reads.insert(e.slot);
  if (e.kind == ExprKind::Load) u.array_reads.insert(e.slot);
  for (const ExprRef& o : e.ops) expr_uses(*o, u);
}

void block_uses(const std::vector<Stmt>& body, Uses& u) {
  for (const Stmt& s : body) {
    if (s.value) expr_uses(*s.value, u);
    if (s.index) expr_uses(*s.index, u);
    if (s.kind == StmtKind::SetLocal) u.writes.insert(s.slot);
    if (s.kind == StmtKind::Store) u.array_writes.insert(s.slot);
    block_uses(s.body, u);
    block_uses(s.orelse, u);
  }
}

Uses uses_of(const VectorOp& op) {
  Uses u;
  block_uses(op.body, u);
  if (op.guard >= 0) u.reads.insert(op.guard);
  if (op.kind == VectorOp::Kind::SpMV) {
    u.array_reads.insert({op.row_ptr, op.cols, op.values, op.x});
    u.array_writes.insert(op.y);
  }
  return u;
}

bool meets(const std::set<int>& a, const std::set<int>& b) {
  for (int x : a)
    if (b.count(x)) return true;
  return false;
}

// A scalar op and a loop before it are independent: neither writes what the other touches.
bool independent(const Uses& scalar, const Uses& loop) {
  return !meets(scalar.writes, loop.reads) && !meets(scalar.writes, loop.writes) &&
         !meets(scalar.reads, loop.writes) && scalar.array_reads.empty() &&
         scalar.array_writes.empty();
}

// A pass runs as well before an op as after it: neither writes what the other touches.
bool commutes(const Uses& pass, const Uses& op) {
  return !meets(pass.writes, op.reads) && !meets(pass.writes, op.writes) &&
         !meets(pass.reads, op.writes) && !meets(pass.array_writes, op.array_reads) &&
         !meets(pass.array_writes, op.array_writes) && !meets(pass.array_reads, op.array_writes);
}

// Whether a pass can join the loop `last` (over the same length, under the same guard): it
// reads no local the loop writes (a reduction's sum is only complete after its loop); into a
// product's row loop goes only a pass that writes no array the loop reads (the rows after
// the current one still read the product's operand, and the fused body reads at the visited
// component only); and sums keep their runs: a pass with sums joins only a loop of the same
// runs. Arrays are read and written at the visited component only, so a pass may read what
// the loop writes.
bool can_join(const VectorOp& last, const VectorOp& op) {
  if (op.kind != VectorOp::Kind::Pass || last.kind == VectorOp::Kind::Scalar ||
      last.length != op.length || last.guard != op.guard)
    return false;
  const Uses prev = uses_of(last), cur = uses_of(op);
  const bool into_product = last.kind == VectorOp::Kind::SpMV;
  const bool runs_agree = op.sums.empty() || op.group == last.group ||
                          (last.sums.empty() && last.kind == VectorOp::Kind::Pass);
  return !meets(cur.reads, prev.writes) &&
         (!into_product || !meets(cur.array_writes, prev.array_reads)) && runs_agree;
}

}  // namespace

int fuse_passes(SystemTrace& t) {
  return fuse_passes(t.before) + fuse_passes(t.body) + fuse_passes(t.after);
}

int fuse_passes(std::vector<VectorOp>& ops) {
  const size_t before = ops.size();
  // 1. Scalar ops move up past independent loops, and merge with the scalar op they reach.
  for (size_t i = 1; i < ops.size(); ++i) {
    if (ops[i].kind != VectorOp::Kind::Scalar) continue;
    size_t j = i;
    const Uses su = uses_of(ops[j]);
    while (j > 0 && ops[j - 1].kind != VectorOp::Kind::Scalar &&
           independent(su, uses_of(ops[j - 1]))) {
      std::swap(ops[j - 1], ops[j]);
      --j;
    }
    if (j > 0 && ops[j - 1].kind == VectorOp::Kind::Scalar && ops[j - 1].guard == ops[j].guard) {
      for (Stmt& s : ops[j].body) ops[j - 1].body.push_back(std::move(s));
      ops.erase(ops.begin() + static_cast<long>(j));
      i = j - 1;
    }
  }
  // 2. A pass moves up past ops it does not depend on to a loop it can join: r'r at the end
  //    of a preconditioned CG joins the pass that updates r.
  for (size_t i = 1; i < ops.size(); ++i) {
    if (ops[i].kind != VectorOp::Kind::Pass) continue;
    const Uses pu = uses_of(ops[i]);
    for (size_t j = i; j > 0; --j) {
      const VectorOp& q = ops[j - 1];
      if (q.kind != VectorOp::Kind::Scalar && can_join(q, ops[i])) {
        std::rotate(ops.begin() + static_cast<long>(j), ops.begin() + static_cast<long>(i),
                    ops.begin() + static_cast<long>(i) + 1);
        break;
      }
      if (!commutes(pu, uses_of(q))) break;
    }
  }
  // 3. Adjacent loops that can join become one, as do adjacent scalar ops under one guard.
  std::vector<VectorOp> out;
  for (VectorOp& op : ops) {
    if (!out.empty() && op.kind == VectorOp::Kind::Scalar &&
        out.back().kind == VectorOp::Kind::Scalar && out.back().guard == op.guard) {
      for (Stmt& s : op.body) out.back().body.push_back(std::move(s));
      continue;
    }
    if (!out.empty() && can_join(out.back(), op)) {
      VectorOp& last = out.back();
      if (!op.sums.empty()) last.group = op.group;
      for (int s : op.sums) last.sums.push_back(s);
      for (Stmt& s : op.body) last.body.push_back(std::move(s));
      continue;
    }
    out.push_back(std::move(op));
  }
  ops = std::move(out);
  return static_cast<int>(before - ops.size());
}

}  // namespace simit::jit
