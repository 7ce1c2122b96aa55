// write_deciders and WriteGuard (jit/write_guard.h): a dependence pass over the loop IR.
#include "jit/write_guard.h"

#include <algorithm>
#include <cstring>
#include <set>
#include <unordered_map>

namespace simit::jit {

namespace {

// Inputs as numbers: an array slot a is a, a scalar slot s is -1 - s.
using Inputs = std::set<int>;

class Deciders {
 public:
  explicit Deciders(const Trace& t) : t_(t), locals_(t.locals.size()), scratch_(t.scratch.size()) {}

  Inputs run() {
    // Locals assigned in branches may be read before a later assignment adds to what they
    // depend on: repeat until nothing grows (twice for straight-line traces).
    do {
      grew_ = false;
      memo_.clear();
      walk(t_.body, {});
    } while (grew_);
    return deciders_;
  }

 private:
  const Inputs& of(const Expr& e) {
    auto [it, fresh] = memo_.try_emplace(&e);
    if (!fresh) return it->second;
    Inputs in;
    if (e.kind == ExprKind::Load) in.insert(e.slot);
    if (e.kind == ExprKind::Scalar) in.insert(-1 - e.slot);
    if (e.kind == ExprKind::Local) in = locals_[static_cast<size_t>(e.slot)];
    // A scratch array's component depends on everything put into the array.
    if (e.kind == ExprKind::Scratch) in = scratch_[static_cast<size_t>(e.slot)];
    for (const ExprRef& op : e.ops) {
      const Inputs& o = of(*op);
      in.insert(o.begin(), o.end());
    }
    Inputs& out = memo_[&e];
    out = std::move(in);
    return out;
  }

  void add(Inputs& to, const Inputs& from) {
    const size_t before = to.size();
    to.insert(from.begin(), from.end());
    if (to.size() != before) grew_ = true;
  }

  void walk(const std::vector<Stmt>& body, const Inputs& control) {
    for (const Stmt& s : body) {
      switch (s.kind) {
        case StmtKind::SetLocal:
          add(locals_[static_cast<size_t>(s.slot)], of(*s.value));
          add(locals_[static_cast<size_t>(s.slot)], control);
          break;
        case StmtKind::Assemble:
          if (s.pair >= 0) deciders_.insert(control.begin(), control.end());
          break;
        case StmtKind::If: {
          Inputs inner = control;
          const Inputs& c = of(*s.value);
          inner.insert(c.begin(), c.end());
          walk(s.body, inner);
          walk(s.orelse, inner);
          break;
        }
        case StmtKind::Decompose: {
          Inputs in = control;
          for (const ExprRef& a : s.args) {
            const Inputs& o = of(*a);
            in.insert(o.begin(), o.end());
          }
          for (int out : s.outs) add(locals_[static_cast<size_t>(out)], in);
          break;
        }
        case StmtKind::Put:
          add(scratch_[static_cast<size_t>(s.slot)], of(*s.value));
          add(scratch_[static_cast<size_t>(s.slot)], of(*s.index));
          add(scratch_[static_cast<size_t>(s.slot)], control);
          break;
        case StmtKind::For: walk(s.body, control); break;  // trip counts are constants
        case StmtKind::Store:
        case StmtKind::Check: break;
      }
    }
  }

  const Trace& t_;
  std::vector<Inputs> locals_, scratch_;
  std::unordered_map<const Expr*, Inputs> memo_;
  Inputs deciders_;
  bool grew_ = false;
};

const runtime::Field& field_of(const ArraySlot& a, const runtime::Set& target) {
  return runtime::member_set(target, a.member).field(a.index);
}

uint64_t bits(double v) {
  uint64_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

}  // namespace

WriteDeciders write_deciders(const Trace& t) {
  WriteDeciders d;
  for (int in : Deciders(t).run()) {
    if (in < 0) {
      d.scalars.push_back(-1 - in);
      continue;
    }
    const ArraySlot& a = t.arrays[static_cast<size_t>(in)];
    if (a.kind == ArraySlot::Kind::Field) {
      d.fields.push_back(in);
    } else if (d.unguardable.empty()) {
      d.unguardable = "the writes depend on '" + a.name + "', which has no write version";
    }
  }
  return d;
}

void WriteGuard::record(const WriteDeciders& d, const Trace& t, const runtime::Set& target,
                        const std::vector<double>& scalars) {
  versions_.clear();
  bits_.clear();
  for (int f : d.fields)
    versions_.push_back(field_of(t.arrays[static_cast<size_t>(f)], target).write_version());
  for (int s : d.scalars) bits_.push_back(bits(scalars[static_cast<size_t>(s)]));
}

bool WriteGuard::holds(const WriteDeciders& d, const Trace& t, const runtime::Set& target,
                       const std::vector<double>& scalars) const {
  if (versions_.size() != d.fields.size() || bits_.size() != d.scalars.size()) return false;
  for (size_t i = 0; i < d.fields.size(); ++i)
    if (field_of(t.arrays[static_cast<size_t>(d.fields[i])], target).write_version() !=
        versions_[i])
      return false;
  for (size_t i = 0; i < d.scalars.size(); ++i)
    if (bits(scalars[static_cast<size_t>(d.scalars[i])]) != bits_[i]) return false;
  return true;
}

}  // namespace simit::jit
