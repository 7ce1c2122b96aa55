// The defer-assembly pass (jit/defer_assembly.h).
#include "jit/defer_assembly.h"

#include <map>
#include <set>
#include <tuple>

#include "jit/executor.h"

namespace simit::jit {

namespace {

// The member a vector write's index names: 0 the element, k + 1 endpoint k; -1 otherwise.
int member_of(const ExprRef& index) {
  if (!index) return -1;
  if (index->kind == ExprKind::Element) return 0;
  if (index->kind == ExprKind::Endpoint) return index->slot + 1;
  return -1;
}

struct Scan {
  const Trace& t;
  std::string why;
  // Each (result, pair or member, component) written, and the members written per vector result.
  std::set<std::tuple<int, int, int, int>> written;
  std::map<int, std::set<int>> vector_members;

  void block(const std::vector<Stmt>& body) {
    for (const Stmt& s : body) {
      if (!why.empty()) return;
      if (s.kind == StmtKind::Store && member_of(s.index) != 0)
        why = "a field is stored at another element";
      if (s.kind == StmtKind::Assemble) assemble(s);
      block(s.body);
      block(s.orelse);
    }
  }
  void assemble(const Stmt& s) {
    const ArraySlot& a = t.arrays[static_cast<size_t>(s.slot)];
    if (a.kind != ArraySlot::Kind::Result) {
      why = "an assembly write outside a result";
      return;
    }
    int where = s.pair;
    if (s.pair < 0) {
      where = member_of(s.index);
      if (where < 0) {
        why = "a vector written at an index that is not a member of the element";
        return;
      }
      vector_members[a.index].insert(where);
    }
    // Both branches of an `if` count: a component written on either is written once.
    if (!written.insert({a.index, s.pair < 0 ? 1 : 0, where, s.comp}).second)
      why = "a block component written twice in one call";
  }
};

void set_members(std::vector<Stmt>& body) {
  for (Stmt& s : body) {
    if (s.kind == StmtKind::Assemble && s.pair < 0) s.member = member_of(s.index);
    set_members(s.body);
    set_members(s.orelse);
  }
}

}  // namespace

std::string defer_assembly(Trace& t) {
  if (!t.reduce) return "its writes overwrite (no reduce +)";
  if (writes_of(t) == MapWrites::Disjoint) return "each element writes only its own blocks";
  Scan scan{t, {}, {}, {}};
  scan.block(t.body);
  if (!scan.why.empty()) return scan.why;
  if (scan.written.empty()) return "it assembles nothing";
  std::set<int> results;
  for (const auto& w : scan.written) results.insert(std::get<0>(w));
  const size_t before = t.arrays.size();
  for (size_t i = 0; i < before; ++i) {
    const ArraySlot r = t.arrays[i];
    if (r.kind != ArraySlot::Kind::Result || !results.count(r.index)) continue;
    if (scan.vector_members.count(r.index)) {
      ArraySlot table;
      table.kind = ArraySlot::Kind::Table;
      table.index = r.index;
      table.ty = Ty::I32;
      table.components = t.arity + 1;
      table.name = r.name + ".table";
      t.arrays.push_back(table);
    }
    ArraySlot deferred = r;
    deferred.kind = ArraySlot::Kind::Deferred;
    deferred.written = true;
    deferred.name = r.name + ".deferred";
    t.arrays.push_back(deferred);
  }
  set_members(t.body);
  t.deferred = true;
  return "";
}

}  // namespace simit::jit
