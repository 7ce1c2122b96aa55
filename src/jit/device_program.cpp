// A system trace cut into device steps (jit/device_program.h).
#include "jit/device_program.h"

#include <algorithm>
#include <memory>
#include <stdexcept>

#include "jit/target.h"
#include "runtime/blocked_sum.h"

namespace simit::jit {

namespace {

bool decomposes(const std::vector<Stmt>& body) {
  for (const Stmt& s : body)
    if (s.kind == StmtKind::Decompose || decomposes(s.body) || decomposes(s.orelse)) return true;
  return false;
}

// Why an op's units could not run apart: a check (which unit's failure would be reported
// depends on the order), a decomposition (a runtime call), or a program scalar set by every
// unit (which value stays depends on the order); "" when they can.
std::string units_refusal(const VectorOp& op, const std::vector<Stmt>& body, int scalars) {
  for (const Stmt& s : body) {
    if (s.kind == StmtKind::Check) return "a pass or product checks a value";
    if (s.kind == StmtKind::Decompose) return "a pass or product calls a decomposition";
    if (s.kind == StmtKind::SetLocal && s.slot < scalars &&
        std::find(op.sums.begin(), op.sums.end(), s.slot) == op.sums.end())
      return "a pass or product sets a program scalar";
    if (std::string why = units_refusal(op, s.body, scalars); !why.empty()) return why;
    if (std::string why = units_refusal(op, s.orelse, scalars); !why.empty()) return why;
  }
  return "";
}

int64_t chunks_of(int64_t elements) {
  const auto c = static_cast<int64_t>(runtime::kSumChunk);
  return (std::max<int64_t>(elements, 0) + c - 1) / c;
}

void plan_ops(const std::vector<VectorOp>& ops, bool in_loop, std::vector<DeviceStep>& out) {
  for (const VectorOp& op : ops) {
    DeviceStep s;
    s.op = &op;
    s.in_loop = in_loop;
    switch (op.kind) {
      case VectorOp::Kind::Scalar: s.kind = DeviceStep::Kind::Serial; break;
      case VectorOp::Kind::Pass:
        s.size = op.length;
        s.kind = op.sums.empty() ? DeviceStep::Kind::Each : DeviceStep::Kind::Lanes;
        s.group = op.sums.empty() ? 1 : op.group;
        break;
      case VectorOp::Kind::SpMV:
        s.size = op.rows;
        s.kind = op.sums.empty() ? DeviceStep::Kind::Rows : DeviceStep::Kind::Lanes;
        break;
    }
    s.sums = static_cast<int>(op.sums.size());
    out.push_back(s);
    if (s.kind != DeviceStep::Kind::Lanes) continue;
    s.kind = DeviceStep::Kind::Tree;
    out.push_back(s);
    s.kind = DeviceStep::Kind::Combine;
    out.push_back(s);
  }
}

bool one_thread(const DeviceStep& s) {
  return s.kind == DeviceStep::Kind::Serial || s.kind == DeviceStep::Kind::Condition ||
         s.kind == DeviceStep::Kind::Combine;
}

// Whether statements set only temporaries (locals past the program's scalars): no store, no
// check, no program scalar.
bool sets_only_temporaries(const std::vector<Stmt>& body, int scalars) {
  for (const Stmt& s : body) {
    if (s.kind == StmtKind::If) {
      if (!sets_only_temporaries(s.body, scalars) || !sets_only_temporaries(s.orelse, scalars))
        return false;
      continue;
    }
    if (s.kind != StmtKind::SetLocal || s.slot < scalars) return false;
  }
  return true;
}

// Neighbouring one-thread steps as the parts of one Thread step.
std::vector<DeviceStep> merged(const std::vector<DeviceStep>& steps, bool in_loop) {
  std::vector<DeviceStep> out;
  for (const DeviceStep& s : steps) {
    if (!one_thread(s)) {
      out.push_back(s);
      continue;
    }
    if (out.empty() || out.back().kind != DeviceStep::Kind::Thread) {
      DeviceStep t;
      t.kind = DeviceStep::Kind::Thread;
      t.in_loop = in_loop;
      out.push_back(t);
    }
    out.back().parts.push_back(s);
  }
  return out;
}

}  // namespace

int64_t DeviceProgram::units(const DeviceStep& step, const std::vector<int64_t>& sizes) const {
  const int64_t n = step.size >= 0 ? sizes[static_cast<size_t>(step.size)] : 0;
  switch (step.kind) {
    case DeviceStep::Kind::Thread:
    case DeviceStep::Kind::Serial:
    case DeviceStep::Kind::Condition:
    case DeviceStep::Kind::Combine: return 1;
    case DeviceStep::Kind::Each:
    case DeviceStep::Kind::Rows: return std::max<int64_t>(n, 0);
    case DeviceStep::Kind::Lanes:
      return chunks_of(n / step.group) * static_cast<int64_t>(runtime::kSumLanes);
    case DeviceStep::Kind::Tree: return chunks_of(n / step.group);
  }
  return 0;
}

int64_t DeviceProgram::lane_doubles(const std::vector<int64_t>& sizes) const {
  int64_t most = 1;
  for (const DeviceStep* s : all())
    if (s->kind == DeviceStep::Kind::Lanes) most = std::max(most, units(*s, sizes) * s->sums);
  return most;
}

int64_t DeviceProgram::partial_doubles(const std::vector<int64_t>& sizes) const {
  int64_t most = 1;
  for (const DeviceStep* s : all())
    if (s->kind == DeviceStep::Kind::Tree) most = std::max(most, units(*s, sizes) * s->sums);
  return most;
}

std::vector<const DeviceStep*> DeviceProgram::all() const {
  std::vector<const DeviceStep*> out;
  for (const auto* list : {&before, &loop, &after})
    for (const DeviceStep& s : *list) out.push_back(&s);
  return out;
}

std::string device_refusal(const SystemTrace& t) {
  for (const auto* ops : {&t.before, &t.body, &t.after})
    for (const VectorOp& op : *ops) {
      if (op.kind == VectorOp::Kind::Scalar) {
        if (decomposes(op.body)) return "a scalar statement calls a decomposition";
        continue;
      }
      if (std::string why = units_refusal(op, op.body, t.scalars); !why.empty()) return why;
    }
  return "";
}

DeviceProgram plan_device_program(const SystemTrace& t) {
  DeviceProgram p;
  p.locals = static_cast<int>(t.locals.size());
  p.scalars = t.scalars;
  p.local_types = t.locals;
  std::vector<DeviceStep> before, body, after;
  plan_ops(t.before, false, before);
  if (t.condition) {
    p.has_loop = true;
    plan_ops(t.body, true, body);
    // The body's leading one-thread steps that set only temporaries move in front of the
    // condition's launch (see DeviceProgram).
    size_t lead = 0;
    while (lead < body.size() && one_thread(body[lead]) &&
           (body[lead].kind == DeviceStep::Kind::Serial
                ? sets_only_temporaries(body[lead].op->body, t.scalars)
                : std::all_of(body[lead].op->sums.begin(), body[lead].op->sums.end(),
                              [&](int l) { return l >= t.scalars; })))
      ++lead;
    DeviceStep c;
    c.kind = DeviceStep::Kind::Condition;
    std::vector<DeviceStep> loop(body.begin() + static_cast<std::ptrdiff_t>(lead), body.end());
    loop.push_back(c);
    before.push_back(c);
    for (size_t i = 0; i < lead; ++i) {
      loop.push_back(body[i]);
      before.push_back(body[i]);
    }
    for (DeviceStep& s : loop) s.in_loop = true;
    p.loop = merged(loop, true);
  }
  p.before = merged(before, false);
  plan_ops(t.after, false, after);
  p.after = merged(after, false);
  return p;
}

std::shared_ptr<const DeviceProgram> detached_device_program(const SystemTrace& t) {
  auto p = std::make_shared<DeviceProgram>(plan_device_program(t));
  for (auto* list : {&p->before, &p->loop, &p->after})
    for (DeviceStep& s : *list) {
      s.op = nullptr;
      for (DeviceStep& part : s.parts) part.op = nullptr;
    }
  return p;
}

void Kernel::run_step(int32_t, int64_t*, int64_t, int64_t) const {
  throw std::logic_error("this kernel is not a device program whose code runs on the host");
}

std::string device_step_name(const std::string& prefix, size_t index) {
  return prefix + "_step" + std::to_string(index);
}

}  // namespace simit::jit
