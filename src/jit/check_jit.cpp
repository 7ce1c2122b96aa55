// --check-jit: each compiled call's results kept, the interpreter run on the same inputs, and
// the first result, field or variable that differs reported with its line and element.
#include <algorithm>
#include <chrono>
#include <cstring>
#include <functional>
#include <sstream>

#include "interp/exec_state.h"
#include "interp/runtime_error.h"
#include "interp/set_binding.h"
#include "jit/controller_state.h"
#include "jit/matrix_sum.h"
#include "jit/pruned_matrix.h"
#include "jit/specialise.h"
#include "jit/write_guard.h"
#include "runtime/system_ops.h"

namespace simit::jit {

namespace ast = frontend::ast;
using interp::Value;

namespace {

// The element of a matrix result whose write made block `pos`: the first element whose
// per-element table names it.
int element_of_block(const runtime::MatrixPattern& p, int32_t pos) {
  const runtime::AssemblyIndex& a = p.assembly();
  for (size_t i = 0; i < a.table.size(); ++i)
    if (a.table[i] == pos) return static_cast<int>(i / a.pairs());
  return -1;
}

}  // namespace

// Equal bits, or zeros of either sign (a folded product by a zero, jit/zero_fold.h).
bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0 || (a == 0.0 && b == 0.0);
}

std::string number(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

// --check-jit on a site: run the kernel, keep what it computed, put the fields back as they
// were and let the interpreter run the site on the same inputs; site_done compares.
bool TraceController::check_site(Entry& e, interp::SiteCall& call) {
  const Trace& t = *e.traced.trace;
  auto p = std::make_unique<Pending>();
  p->at = call.plan.site;
  p->name = e.stats.site;
  p->trace = &t;
  std::vector<std::pair<int, std::vector<std::byte>>> before;
  for (size_t i = 0; i < t.arrays.size(); ++i) {
    const ArraySlot& a = t.arrays[i];
    if (a.kind != ArraySlot::Kind::Field || !a.written) continue;
    const runtime::Field& f = runtime::member_set(call.target, a.member).field(a.index);
    const size_t bytes = static_cast<size_t>(call.target.size()) * f.element_bytes();
    before.emplace_back(static_cast<int>(i), std::vector<std::byte>(f.bytes(), f.bytes() + bytes));
  }
  if (!run_kernel(e, call)) return false;  // an error: the interpreter reports it
  ++e.stats.calls;
  if (options_.corrupt_for_test && !call.results.empty()) {
    Value& r = call.results[0];
    double* v = r.kind() == Value::Kind::Matrix ? r.matrix()->values()
                : r.is_tensor()                 ? r.tensor().mutable_floats()
                                                : nullptr;
    if (v) {
      uint64_t bits;
      std::memcpy(&bits, v, sizeof bits);
      bits ^= 1;
      std::memcpy(v, &bits, sizeof bits);
    }
  }
  p->specialised.resize(call.results.size());
  for (size_t i = 0; i < call.results.size(); ++i) {
    Value& r = call.results[i];
    if (r.kind() == Value::Kind::Matrix) {
      if (r.matrix()->shared_pattern() != call.plan.results[i].pattern) {
        // The interpreter assembles on the full pattern: it makes that matrix itself, and
        // the compiled one is kept whole.
        p->results.emplace_back();
        p->specialised[i] = std::move(r);
        r = Value::of_matrix(nullptr);
        continue;
      }
      const double* v = r.matrix()->values();
      p->results.emplace_back(v, v + r.matrix()->value_count());
    } else if (r.is_tensor() && r.tensor().kind() == runtime::ComponentKind::Float) {
      p->results.emplace_back(r.tensor().floats(), r.tensor().floats() + r.tensor().size());
    } else {
      p->results.emplace_back();
    }
  }
  for (auto& [slot, bytes] : before) {
    const ArraySlot& a = t.arrays[slot];
    runtime::Field& f =
        const_cast<runtime::Set&>(runtime::member_set(call.target, a.member)).field(a.index);
    p->fields.emplace_back(slot, std::vector<std::byte>(f.bytes(), f.bytes() + bytes.size()));
    std::memcpy(f.bytes(), bytes.data(), bytes.size());
  }
  zero_results(call);
  pending_ = std::move(p);
  return false;
}

void TraceController::site_done(interp::SiteCall& call) {
  if (!pending_ || pending_->at != call.plan.site) return;
  const std::unique_ptr<Pending> p = std::move(pending_);
  const ast::FuncDecl& f = *call.plan.func;
  auto differ = [&](const std::string& what, int element, const runtime::Set& set, double interp,
                    double jit) {
    throw interp::RuntimeError(
        call.at,
        "--check-jit: the compiled " + p->name + " differs from the interpreter in " + what +
            (element >= 0 ? " at element " + std::to_string(element) + " of " + set.describe()
                          : "") +
            ": interpreted " + number(interp) + ", compiled " + number(jit));
  };
  for (size_t r = 0; r < call.results.size() && r < p->results.size(); ++r) {
    const Value& v = call.results[r];
    const std::vector<double>& jit = p->results[r];
    const double* in = v.kind() == Value::Kind::Matrix ? v.matrix()->values()
                       : v.is_tensor()                 ? v.tensor().floats()
                                                       : nullptr;
    if (!in) continue;
    if (r < p->specialised.size() && !p->specialised[r].empty()) {
      // The compiled matrix holds the blocks written; every other block of the interpreter's
      // must be zero.
      const runtime::SystemMatrix& full = *v.matrix();
      const runtime::MatrixPattern& fp = full.pattern();
      const runtime::MatrixPattern& sp = p->specialised[r].matrix()->pattern();
      const double* compiled = std::as_const(*p->specialised[r].matrix()).values();
      const size_t bs = static_cast<size_t>(full.block_size());
      for (int row = 0; row < fp.rows(); ++row)
        for (int32_t k = fp.row_ptr()[row]; k < fp.row_ptr()[row + 1]; ++k) {
          const int32_t at = sp.find(row, fp.col_idx()[k]);
          for (size_t c = 0; c < bs; ++c) {
            const double iv = in[static_cast<size_t>(k) * bs + c];
            const double jv = at < 0 ? 0.0 : compiled[static_cast<size_t>(at) * bs + c];
            if (same_bits(iv, jv)) continue;
            differ("result '" + f.results[r].name + "' component " +
                       std::to_string(static_cast<size_t>(k) * bs + c) + " (block " +
                       std::to_string(k) + (at < 0 ? ", left out of the specialised pattern" : "") +
                       ")",
                   element_of_block(fp, k), call.target, iv, jv);
          }
        }
      call.results[r] = std::move(p->specialised[r]);
      continue;
    }
    for (size_t c = 0; c < jit.size(); ++c) {
      if (same_bits(in[c], jit[c])) continue;
      const std::string what = "result '" + f.results[r].name + "' component " + std::to_string(c);
      if (v.kind() == Value::Kind::Matrix) {
        const int32_t pos = static_cast<int32_t>(c / static_cast<size_t>(v.matrix()->block_size()));
        differ(what + " (block " + std::to_string(pos) + ")",
               element_of_block(v.matrix()->pattern(), pos), call.target, in[c], jit[c]);
      }
      const size_t block = v.tensor().shape().block_size();
      differ(what + " (entry " + std::to_string(c / block) + " of the vector)", -1, call.target,
             in[c], jit[c]);
    }
  }
  for (const auto& [slot, bytes] : p->fields) {
    const ArraySlot& a = p->trace->arrays[slot];
    const runtime::Set& set = runtime::member_set(call.target, a.member);
    const runtime::Field& fld = set.field(a.index);
    if (std::memcmp(fld.bytes(), bytes.data(), bytes.size()) == 0) continue;
    const size_t per = fld.element_bytes();
    for (size_t at = 0; at < bytes.size(); ++at)
      if (fld.bytes()[at] != bytes[at]) {
        const int element = static_cast<int>(at / per);
        double iv = 0.0, jv = 0.0;
        if (a.ty == Ty::F64 && !a.single) {
          const size_t c = at / sizeof(double);
          std::memcpy(&iv, fld.bytes() + c * sizeof(double), sizeof iv);
          std::memcpy(&jv, bytes.data() + c * sizeof(double), sizeof jv);
        }
        differ("field '" + fld.name() + "'", element, set, iv, jv);
      }
  }
}

// --check-jit on a loop: the same, with the variables the loop writes kept (as shared
// copies: the kernel's writes copy them first) and put back for the interpreter.
// --check-jit on a loop or a run: run the kernel, keep what it computed, put the variables
// back as they were and let the interpreter run the statements; statement_done compares
// after the last one. Nothing is offered meanwhile (a run's loop would check itself).
// False when the kernel reached an error statement (and put the variables back).
bool TraceController::check_system(LoopEntry& e, interp::ExecState& in) {
  const SystemBinding& b = e.traced.binding;
  const SystemTrace& t = *e.traced.trace;
  Saved before = save_loop_variables(b, t, e.writes_scalar, in);
  // Written fields, as they were (a run that writes one holds no error statement).
  std::vector<Pending::RunField> fields;
  for (size_t i = 0; i < b.arrays.size(); ++i) {
    if (!t.arrays[i].written || b.arrays[i].part != SystemBinding::Array::Part::Field) continue;
    const runtime::Field& f = bound_field(b.arrays[i], in);
    const size_t n =
        static_cast<size_t>(in.variable(*b.arrays[i].var).binding()->set->size()) * f.components();
    fields.push_back(Pending::RunField{&f, t.arrays[i].name, field_values(f, n)});
  }
  if (!run_loop_kernel(e, in)) return false;  // an error: the interpreter reports it
  auto p = std::make_unique<Pending>();
  p->at = e.run.back();
  p->name = e.stats.site;
  for (auto& [var, value] : before) {
    p->variables.emplace_back(var, in.variable(*var));
    in.variable(*var) = std::move(value);
  }
  for (Pending::RunField& f : fields) {
    runtime::Field& field = const_cast<runtime::Field&>(*f.field);
    std::vector<double> compiled = field_values(field, f.values.size());
    set_field_values(field, f.values);
    f.values = std::move(compiled);
    p->run_fields.push_back(std::move(f));
  }
  pending_ = std::move(p);
  if (e.run.size() > 1 || !e.run.front()->is<ast::While>()) checking_run_ = e.run.back();
  return true;
}

void TraceController::statement_done(const ast::Stmt& stmt, interp::ExecState& in) {
  if (!pending_ || pending_->at != &stmt) return;
  checking_run_ = nullptr;
  const std::unique_ptr<Pending> p = std::move(pending_);
  for (const Pending::RunField& f : p->run_fields) {
    const std::vector<double> got = field_values(*f.field, f.values.size());
    const size_t per = std::max<size_t>(f.field->components(), 1);
    for (size_t c = 0; c < f.values.size(); ++c)
      if (!same_bits(got[c], f.values[c]))
        throw interp::RuntimeError(
            stmt.span,
            "--check-jit: the compiled " + p->name + " differs from the interpreter in '" + f.name +
                "' component " + std::to_string(c) + " (element " + std::to_string(c / per) +
                "): interpreted " + number(got[c]) + ", compiled " + number(f.values[c]));
  }
  for (const auto& [var, jit] : p->variables) {
    const Value& got = in.variable(*var);
    auto differ = [&](const std::string& where, double a, double b) {
      throw interp::RuntimeError(stmt.span, "--check-jit: the compiled " + p->name +
                                                " differs from the interpreter in '" + var->name +
                                                "'" + where + ": interpreted " + number(a) +
                                                ", compiled " + number(b));
    };
    if (got.is_tensor() && jit.is_tensor()) {
      const runtime::Tensor &a = got.tensor(), &b = jit.tensor();
      if (a.kind() != runtime::ComponentKind::Float || a.size() != b.size()) continue;
      const size_t block = a.shape().block_size();
      for (size_t c = 0; c < a.size(); ++c)
        if (!same_bits(a.floats()[c], b.floats()[c]))
          differ(" component " + std::to_string(c) + " (element " + std::to_string(c / block) + ")",
                 a.floats()[c], b.floats()[c]);
    } else if (got.kind() == Value::Kind::Float && jit.kind() == Value::Kind::Float) {
      if (!same_bits(got.as_float(), jit.as_float())) differ("", got.as_float(), jit.as_float());
    } else if (got.kind() == Value::Kind::Int && jit.kind() == Value::Kind::Int) {
      if (got.as_int() != jit.as_int()) differ("", got.as_int(), jit.as_int());
    }
  }
}

}  // namespace simit::jit
