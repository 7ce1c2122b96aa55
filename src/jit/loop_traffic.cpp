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

// The arrays one list of ops moves: each slot once per read and once per write.
TrafficPlan::Section section_of(const std::vector<VectorOp>& ops) {
  TrafficPlan::Section out;
  for (const VectorOp& op : ops) {
    if (op.kind == VectorOp::Kind::Scalar) continue;
    Touched t;
    stmt_touches(op.body, t);
    if (op.kind == VectorOp::Kind::SpMV) {
      for (int m : {op.values, op.cols, op.row_ptr}) {
        out.matrices.push_back(m);
        t.read.erase(m);
      }
      t.read.insert(op.x);
      t.written.insert(op.y);
      // The product's own row is read back from registers by the body, not from memory.
      t.read.erase(op.y);
    }
    out.vectors.insert(out.vectors.end(), t.read.begin(), t.read.end());
    out.vectors.insert(out.vectors.end(), t.written.begin(), t.written.end());
  }
  return out;
}

}  // namespace

TrafficPlan plan_traffic(const SystemTrace& t) {
  return {section_of(t.before), section_of(t.body), section_of(t.after)};
}

LoopTraffic TrafficPlan::bytes(std::span<const size_t> array_bytes) const {
  auto sum = [&](const std::vector<int>& slots) {
    int64_t total = 0;
    for (int s : slots)
      if (s >= 0 && static_cast<size_t>(s) < array_bytes.size())
        total += static_cast<int64_t>(array_bytes[static_cast<size_t>(s)]);
    return total;
  };
  LoopTraffic out;
  out.before = sum(before.matrices) + sum(before.vectors);
  out.matrices = sum(body.matrices);
  out.per_iteration = out.matrices + sum(body.vectors);
  out.after = sum(after.matrices) + sum(after.vectors);
  return out;
}

LoopTraffic loop_traffic(const SystemTrace& t, std::span<const size_t> array_bytes) {
  return plan_traffic(t).bytes(array_bytes);
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
