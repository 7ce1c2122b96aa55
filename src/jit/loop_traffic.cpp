// Counts the bytes a system trace's passes and products move (jit/loop_traffic.h).
#include "jit/loop_traffic.h"

#include "jit/controller_state.h"

#include <cstdio>
#include <set>
#include <vector>

namespace simit::jit {

namespace {

struct Touched {
  std::set<int> read, written;
};

void expr_reads(const Expr& e, Touched& t) {
  if (e.kind == ExprKind::Load) t.read.insert(e.slot);
  for (const ExprRef& o : e.ops)
    if (o) expr_reads(*o, t);
}

void stmt_touches(const std::vector<Stmt>& body, Touched& t) {
  for (const Stmt& s : body) {
    if (s.kind == StmtKind::Store) t.written.insert(s.slot);
    for (const ExprRef* e : {&s.index, &s.value})
      if (*e) expr_reads(**e, t);
    for (const ExprRef& a : s.args)
      if (a) expr_reads(*a, t);
    stmt_touches(s.body, t);
    stmt_touches(s.orelse, t);
  }
}

struct Bytes {
  int64_t all = 0, matrices = 0;
};

Bytes ops_bytes(const std::vector<VectorOp>& ops, std::span<const size_t> array_bytes) {
  auto size = [&](int slot) {
    return slot >= 0 && static_cast<size_t>(slot) < array_bytes.size()
               ? static_cast<int64_t>(array_bytes[static_cast<size_t>(slot)])
               : int64_t{0};
  };
  Bytes b;
  for (const VectorOp& op : ops) {
    if (op.kind == VectorOp::Kind::Scalar) continue;
    Touched t;
    stmt_touches(op.body, t);
    if (op.kind == VectorOp::Kind::SpMV) {
      for (int m : {op.values, op.cols, op.row_ptr}) {
        b.matrices += size(m);
        t.read.erase(m);
      }
      b.all += size(op.values) + size(op.cols) + size(op.row_ptr);
      t.read.insert(op.x);
      t.written.insert(op.y);
      // The product's own row is read back from registers by the body, not from memory.
      t.read.erase(op.y);
    }
    for (int s : t.read) b.all += size(s);
    for (int s : t.written) b.all += size(s);
  }
  return b;
}

}  // namespace

LoopTraffic loop_traffic(const SystemTrace& t, std::span<const size_t> array_bytes) {
  LoopTraffic out;
  out.before = ops_bytes(t.before, array_bytes).all;
  const Bytes body = ops_bytes(t.body, array_bytes);
  out.per_iteration = body.all;
  out.matrices = body.matrices;
  out.after = ops_bytes(t.after, array_bytes).all;
  return out;
}

void TrafficCount::add(const LoopTraffic& t, int64_t call_iterations, double kernel_ms) {
  if (call_iterations <= 0) return;
  last = t;
  iterations += call_iterations;
  bytes += t.before + call_iterations * t.per_iteration + t.after;
  ms += kernel_ms;
}

std::string TrafficCount::note() const {
  if (iterations <= 0 || ms <= 0.0) return "";
  char text[200];
  std::snprintf(text, sizeof text,
                "; an iteration moves %s (its matrices %s); %lld iterations at %.1f GB/s",
                bytes_text(last.per_iteration).c_str(), bytes_text(last.matrices).c_str(),
                static_cast<long long>(iterations), static_cast<double>(bytes) / (ms * 1e6));
  return text;
}

}  // namespace simit::jit
