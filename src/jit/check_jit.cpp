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

// Where component c of a value with `block` components per element of `set` lies, for a
// message about a set a scene renumbered: "component 1 at element 12 of set 'verts'" (12 the
// element's mesh number; no component for one per element).
std::string mesh_place(const runtime::Set& set, size_t c, size_t block) {
  const int element = static_cast<int>(c / block);
  return (block > 1 ? "component " + std::to_string(c % block) + " " : std::string()) +
         "at element " + std::to_string(set.mesh_number(element)) + " of " + set.describe();
}

// The set a value's elements are: `v` bound to a set (the variable an index set names).
const runtime::Set* bound_set(const Value& v) {
  return v.kind() == Value::Kind::Set && v.binding() ? v.binding()->set : nullptr;
}

// The set (of `elements` elements) whose elements are the blocks of a vector of `type`: the
// one its dimension's variable (an extern, a parameter or a generic) holds, as `value` reads it.
const runtime::Set* vector_set(const frontend::Type& type, size_t elements,
                               const std::function<const Value*(const ast::Variable&)>& value) {
  if (type.order() != 1 || type.dims[0].kind == frontend::IndexSet::Kind::Fixed ||
      !type.dims[0].var)
    return nullptr;
  const Value* v = value(*type.dims[0].var);
  const runtime::Set* set = v ? bound_set(*v) : nullptr;
  return set && static_cast<size_t>(set->size()) == elements ? set : nullptr;
}

// The set whose elements are the blocks of a site's vector result of `type` (`elements`
// blocks): the extern its type names, or the one a generic of the mapped function is bound to
// by the site; else the one set of that size among the target and its endpoint sets.
const runtime::Set* result_set(const interp::SiteCall& call, const frontend::Type& type,
                               size_t elements) {
  const ast::FuncDecl& f = *call.plan.func;
  auto global = [&](const ast::Variable& var) -> const Value* {
    return var.kind == ast::Variable::Kind::Extern ? &call.interpreter.global(var) : nullptr;
  };
  auto value = [&](const ast::Variable& var) -> const Value* {
    if (var.kind == ast::Variable::Kind::Extern) return global(var);
    const std::vector<frontend::IndexSet>& bound = call.plan.site->bindings;
    for (size_t k = 0; k < f.generics.size() && k < bound.size(); ++k)
      if (f.generics[k].var == &var && bound[k].var) return global(*bound[k].var);
    return nullptr;
  };
  if (const runtime::Set* set = vector_set(type, elements, value)) return set;
  const runtime::Set* found = nullptr;
  for (int m = 0; m <= call.target.arity(); ++m) {
    const runtime::Set& s = runtime::member_set(call.target, m);
    if (static_cast<size_t>(s.size()) != elements) continue;
    if (found && found != &s) return nullptr;  // two sets of that size: no telling which
    found = &s;
  }
  return found;
}

// Flips the lowest bit of a double (--check-jit's test of itself, JitOptions::corrupt_for_test).
void flip_lowest_bit(double& v) {
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  bits ^= 1;
  std::memcpy(&v, &bits, sizeof bits);
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
  if (options_.corrupt_for_test) {
    // The first result's first value, or for a site without results (an apply) the lowest
    // bit of the first written field's array.
    Value* r = call.results.empty() ? nullptr : &call.results[0];
    double* v = !r                                 ? nullptr
                : r->kind() == Value::Kind::Matrix ? r->matrix()->values()
                : r->is_tensor()                   ? r->tensor().mutable_floats()
                                                   : nullptr;
    if (v) {
      flip_lowest_bit(*v);
    } else if (!r && !before.empty() && !before.front().second.empty()) {
      const ArraySlot& a = t.arrays[static_cast<size_t>(before.front().first)];
      runtime::Field& f =
          const_cast<runtime::Set&>(runtime::member_set(call.target, a.member)).field(a.index);
      f.bytes()[0] ^= std::byte{1};
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
  // `element` of `set` is named by its mesh number (the element itself without mesh numbers).
  auto differ = [&](const std::string& what, int element, const runtime::Set& set, double interp,
                    double jit) {
    throw interp::RuntimeError(
        call.at, "--check-jit: the compiled " + p->name + " differs from the interpreter in " +
                     what +
                     (element >= 0 ? " at element " + std::to_string(set.mesh_number(element)) +
                                         " of " + set.describe()
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
      const runtime::Set* set =
          f.results[r].var && f.results[r].var->type
              ? result_set(call, *f.results[r].var->type, v.tensor().size() / block)
              : nullptr;
      if (set && set->has_mesh_numbers())
        differ("result '" + f.results[r].name + "' " + mesh_place(*set, c, block), -1, *set, in[c],
               jit[c]);
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
  if (options_.corrupt_for_test) {
    // The first written field's first value, else the first written float vector's.
    auto floats = [](Value& v) {
      return v.is_tensor() && v.tensor().kind() == runtime::ComponentKind::Float &&
             v.tensor().size() > 0;
    };
    if (!p->run_fields.empty() && !p->run_fields.front().values.empty())
      flip_lowest_bit(p->run_fields.front().values.front());
    else
      for (auto& [var, value] : p->variables)
        if (floats(value)) {
          flip_lowest_bit(value.tensor().mutable_floats()[0]);
          break;
        }
  }
  pending_ = std::move(p);
  if (e.run.size() > 1 || !e.run.front()->is<ast::While>()) checking_run_ = e.run.back();
  return true;
}

void TraceController::statement_done(const ast::Stmt& stmt, interp::ExecState& in) {
  if (!pending_ || pending_->at != &stmt) return;
  checking_run_ = nullptr;
  const std::unique_ptr<Pending> p = std::move(pending_);
  // The set whose field `field` is, among those the compiled runs ending at this statement
  // bind (looked for only when a field differs).
  auto field_set = [&](const runtime::Field& field) -> const runtime::Set* {
    for (const auto* states : {&loops_, &runs_, &alone_})
      for (const auto& [key, state] : *states)
        for (const std::unique_ptr<LoopEntry>& e : state->entries) {
          if (e->run.empty() || e->run.back() != &stmt) continue;
          for (const SystemBinding::Array& a : e->traced.binding.arrays) {
            if (a.part != SystemBinding::Array::Part::Field || !a.var) continue;
            if (const runtime::Set* set = bound_set(in.variable(*a.var)))
              for (int k = 0; k < set->field_count(); ++k)
                if (&set->field(k) == &field) return set;
          }
        }
    return nullptr;
  };
  // Where component c of a value with `block` components per element of `set` lies: by the
  // mesh's numbers where the set has them.
  auto place = [](const runtime::Set* set, size_t c, size_t block) {
    if (set && set->has_mesh_numbers()) return mesh_place(*set, c, block);
    return "component " + std::to_string(c) + " (element " + std::to_string(c / block) + ")";
  };
  for (const Pending::RunField& f : p->run_fields) {
    const std::vector<double> got = field_values(*f.field, f.values.size());
    const size_t per = std::max<size_t>(f.field->components(), 1);
    for (size_t c = 0; c < f.values.size(); ++c)
      if (!same_bits(got[c], f.values[c]))
        throw interp::RuntimeError(stmt.span, "--check-jit: the compiled " + p->name +
                                                  " differs from the interpreter in '" + f.name +
                                                  "' " + place(field_set(*f.field), c, per) +
                                                  ": interpreted " + number(got[c]) +
                                                  ", compiled " + number(f.values[c]));
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
      auto value = [&](const ast::Variable& v) -> const Value* { return &in.variable(v); };
      for (size_t c = 0; c < a.size(); ++c)
        if (!same_bits(a.floats()[c], b.floats()[c]))
          differ(" " + place(var->type ? vector_set(*var->type, a.size() / block, value) : nullptr,
                             c, block),
                 a.floats()[c], b.floats()[c]);
    } else if (got.kind() == Value::Kind::Float && jit.kind() == Value::Kind::Float) {
      if (!same_bits(got.as_float(), jit.as_float())) differ("", got.as_float(), jit.as_float());
    } else if (got.kind() == Value::Kind::Int && jit.kind() == Value::Kind::Int) {
      if (got.as_int() != jit.as_int()) differ("", got.as_int(), jit.as_int());
    }
  }
}

}  // namespace simit::jit
