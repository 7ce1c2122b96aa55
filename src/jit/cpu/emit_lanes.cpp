// Map kernels in SIMD lanes: every value for lanes_of elements at once, then each element's
// statements in order, reading those values back (jit/cpu/cpu_hooks.h, docs/jit.md "Four
// elements at once").
#include <functional>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "jit/cpu/cpu_hooks.h"
#include "jit/tunables.h"

namespace simit::jit::cpu {

using llvm::IRBuilder;
using llvm::Value;

// Whether a map kernel can compute several elements at once: every value is then an SSA local
// or an expression of them, evaluated for all lanes with the same IEEE operations lane by
// lane (library calls once per lane), and everything that acts (the assembly writes, the
// branches, the checks) runs afterwards element by element in order, so the results, the
// order of every reduction and the first failing element are the one-element kernel's.
// Reads are speculative across branches: loads of fields and arguments at the element's own
// endpoints are always in range, and no operation traps.
bool lanes_fit(const Trace& t, std::string* why_not) {
  auto no = [&](const char* why) {
    if (why_not) *why_not = why;
    return false;
  };
  if (kLanes <= 1) return no("lanes are off");
  if (t.writes_fields) return no("it writes fields");
  // Tiled tensors' scratch arrays and loops are one element's: not in lanes.
  if (!t.scratch.empty()) return no("a tiled tensor's loops");
  if (t.local_mutable.size() < t.locals.size()) return no("a local assigned in a branch");
  for (bool m : t.local_mutable)
    if (m) return no("a local assigned in a branch");
  std::function<const char*(const std::vector<Stmt>&)> misfit =
      [&](const std::vector<Stmt>& body) -> const char* {
    for (const Stmt& s : body) {
      if (s.kind == StmtKind::Store) return "it writes fields";
      if (s.kind == StmtKind::Decompose) return "a decomposition call it cannot widen";
      if (s.kind == StmtKind::If) {
        if (const char* why = misfit(s.body)) return why;
        if (const char* why = misfit(s.orelse)) return why;
      }
    }
    return nullptr;
  };
  if (const char* why = misfit(t.body)) return no(why);
  if (why_not) why_not->clear();
  return true;
}

int lanes_of(const Trace& t) {
  if (kLanes <= 1) return 1;
  return t.float32 ? kLanes32 : kLanes;
}

namespace {

// Values the element-by-element statements compute themselves rather than read back.
bool trivial(const Expr& e) {
  return e.kind == ExprKind::Const || e.kind == ExprKind::Scalar || e.kind == ExprKind::Element ||
         e.kind == ExprKind::Endpoint;
}
int ty_index(Ty t) { return static_cast<int>(t); }

// How a root of type t lies in its buffer (truth values as bytes).
llvm::Type* root_type(IRBuilder<>& b, Ty t) {
  return t == Ty::F64 ? b.getDoubleTy() : t == Ty::I32 ? b.getInt32Ty() : b.getInt8Ty();
}

// Runs the lanes of one group of elements (run_lanes) and, while their statements are
// emitted one element at a time, hands them the values computed for all lanes.
class Lanes : public codegen::Precomputed {
 public:
  explicit Lanes(codegen::MapEmitter& k)
      : k_(k), b_(k.builder()), t_(k.trace()), n_(lanes_of(k.trace())) {}
  void run(Value* first, Value* end);

  Value* value(const Expr& e) override {
    auto root = roots_.find(&e);
    return root == roots_.end() ? nullptr : load_root(e.ty, root->second);
  }
  int side_by_side(const std::vector<Stmt>& body, size_t i) override;
  Value* side_by_side_values(const Stmt& s, int width) override {
    const int row = roots_.at(s.value.get());
    auto* ty = llvm::FixedVectorType::get(b_.getDoubleTy(), static_cast<unsigned>(width));
    if (!narrow_row_[static_cast<size_t>(row)])
      return b_.CreateAlignedLoad(ty, root_address(row), llvm::Align(8));
    auto* ty32 = llvm::FixedVectorType::get(b_.getFloatTy(), static_cast<unsigned>(width));
    return b_.CreateFPExt(b_.CreateAlignedLoad(ty32, root_address(row, true), llvm::Align(4)), ty);
  }

 private:
  void allocate_roots();
  void count_roots(const std::vector<Stmt>& body);
  Value* lanes(const Expr& e);
  Value* lanes_uncached(const Expr& e);
  void lanes_block(const std::vector<Stmt>& body);
  void spill(const Expr& e);
  void flush_pending(int first);
  Value* root_address(int row, bool narrow = false);
  Value* load_root(Ty t, int row);

  codegen::MapEmitter& k_;
  IRBuilder<>& b_;
  const Trace& t_;
  const int n_;  // elements at once (lanes_of)
  // Each expression's value for every lane (memoised by node: traces share nodes), the
  // locals', and each lane's element and endpoints.
  std::unordered_map<const Expr*, Value*> vmemo_;
  std::vector<Value*> vlocal_, element_lane_;
  std::vector<std::vector<Value*>> endpoint_lane_;
  // The values the element-by-element statements read (conditions, written values), stored
  // per lane in one buffer per type: root -> its row.
  std::unordered_map<const Expr*, int> roots_;
  std::unordered_set<const Expr*> spilled_;
  int root_rows_[3] = {0, 0, 0};
  Value* root_buffer_[3] = {nullptr, nullptr, nullptr};
  Value* lane_ = nullptr;        // the lane whose statements are being emitted (i64), or null
  uint64_t root_stride_ = 0;     // float rows per lane in the buffer (a multiple of 4)
  std::vector<Value*> pending_;  // float roots computed, not yet stored
  // Float roots that hold binary32 values (--float32: a widened binary32 vector) lie in a
  // buffer of binary32 values beside the binary64 one, at the same place: stored narrow, they
  // need no widening for all lanes and move half the bytes; a statement widens the value it
  // reads. narrow_row_ says which rows; the pending roots are all of one kind.
  Value* root_buffer32_ = nullptr;
  std::vector<bool> narrow_row_;
  bool pending_narrow_ = false;
};

// The statements' roots, each given its row in its type's buffer.
void Lanes::count_roots(const std::vector<Stmt>& body) {
  auto root = [&](const ExprRef& e) {
    if (!e || trivial(*e) || roots_.count(e.get())) return;
    roots_[e.get()] = root_rows_[ty_index(e->ty)]++;
  };
  for (const Stmt& s : body) {
    switch (s.kind) {
      case StmtKind::Assemble: root(s.value), root(s.index); break;
      case StmtKind::Check: root(s.value); break;
      case StmtKind::If:
        root(s.value);
        count_roots(s.body);
        count_roots(s.orelse);
        break;
      default: break;
    }
  }
}

// The roots' rows and their buffers, in the function's entry block (float rows padded to a
// multiple of four for the transposed stores).
void Lanes::allocate_roots() {
  count_roots(t_.body);
  llvm::BasicBlock& entry = k_.function()->getEntryBlock();
  llvm::IRBuilder<> at_entry(&entry, entry.begin());
  root_stride_ = static_cast<uint64_t>((root_rows_[0] + 3) / 4 * 4);
  narrow_row_.assign(static_cast<size_t>(root_rows_[0]), false);
  for (Ty ty : {Ty::F64, Ty::I32, Ty::Bool}) {
    const int t = ty_index(ty);
    if (root_rows_[t] == 0) continue;
    const int rows = ty == Ty::F64 ? static_cast<int>(root_stride_) : root_rows_[t];
    llvm::AllocaInst* a =
        at_entry.CreateAlloca(root_type(b_, ty), b_.getInt32(static_cast<uint32_t>(rows * n_)));
    a->setAlignment(llvm::Align(32));
    root_buffer_[t] = a;
    if (ty == Ty::F64 && t_.float32) {
      llvm::AllocaInst* narrow =
          at_entry.CreateAlloca(b_.getFloatTy(), b_.getInt32(static_cast<uint32_t>(rows * n_)));
      narrow->setAlignment(llvm::Align(32));
      root_buffer32_ = narrow;
    }
  }
}

// Elements first .. first + n_ - 1 (those past `end` compute element end - 1 again, and
// their statements do not run): every value for all lanes, then the statements lane by lane.
void Lanes::run(Value* first, Value* end) {
  allocate_roots();
  llvm::Type* i32 = b_.getInt32Ty();
  Value* last = b_.CreateSub(end, b_.getInt32(1));
  element_lane_.clear();
  endpoint_lane_.assign(static_cast<size_t>(t_.arity), {});
  for (int l = 0; l < n_; ++l) {
    Value* e = b_.CreateAdd(first, b_.getInt32(static_cast<uint32_t>(l)));
    if (l > 0) e = b_.CreateSelect(b_.CreateICmpSLT(e, end), e, last);
    k_.visit(e);
    element_lane_.push_back(e);
    for (int k = 0; k < t_.arity; ++k)
      endpoint_lane_[static_cast<size_t>(k)].push_back(k_.endpoints()[k]);
  }
  vmemo_.clear();
  spilled_.clear();
  vlocal_.assign(t_.locals.size(), nullptr);
  lanes_block(t_.body);
  if (!pending_.empty()) flush_pending(root_rows_[0] - static_cast<int>(pending_.size()));
  Value* left = b_.CreateSub(end, first);
  Value* count = b_.CreateSelect(b_.CreateICmpSLT(left, b_.getInt32(n_)), left, b_.getInt32(n_));
  k_.loop(llvm::ConstantInt::get(i32, 0), count, [&](Value* l) {
    lane_ = b_.CreateSExt(l, b_.getInt64Ty());
    k_.set_precomputed(this);
    k_.visit(b_.CreateAdd(first, l));
    k_.block(t_.body);
    k_.set_precomputed(nullptr);
    lane_ = nullptr;
  });
}

// How many statements from body[i] on add neighbouring components of one block from
// neighbouring rows of the lanes' buffer.
int Lanes::side_by_side(const std::vector<Stmt>& body, size_t i) {
  const Stmt& first = body[i];
  if (first.value->ty != Ty::F64 || !roots_.count(first.value.get())) return 1;
  const int row = roots_.at(first.value.get());
  auto same_place = [&](const Stmt& s) {
    if (s.kind != StmtKind::Assemble || s.slot != first.slot || s.pair != first.pair) return false;
    if (s.pair >= 0) return true;
    const Expr &a = *s.index, &b = *first.index;
    return &a == &b || ((a.kind == ExprKind::Endpoint || a.kind == ExprKind::Element) &&
                        a.kind == b.kind && a.slot == b.slot);
  };
  int n = 1;
  while (i + static_cast<size_t>(n) < body.size()) {
    const Stmt& s = body[i + static_cast<size_t>(n)];
    if (!same_place(s) || s.comp != first.comp + n || s.value->ty != Ty::F64) break;
    auto r = roots_.find(s.value.get());
    if (r == roots_.end() || r->second != row + n ||
        narrow_row_[static_cast<size_t>(r->second)] != narrow_row_[static_cast<size_t>(row)])
      break;
    ++n;
  }
  return n;
}

void Lanes::lanes_block(const std::vector<Stmt>& body) {
  for (const Stmt& s : body) {
    switch (s.kind) {
      case StmtKind::SetLocal: vlocal_[s.slot] = lanes(*s.value); break;
      case StmtKind::Assemble:
        spill(*s.value);
        if (s.index) spill(*s.index);
        break;
      case StmtKind::Check: spill(*s.value); break;
      case StmtKind::If:
        spill(*s.value);
        lanes_block(s.body);
        lanes_block(s.orelse);
        break;
      default: break;  // Store, Decompose: not in a trace that runs in lanes
    }
  }
}

// A root's value for every lane goes to the buffer. Integers and truth values lie row by
// row (row * n_ + lane); floats lie lane by lane (lane * stride + row), so that one
// element's block is contiguous and its additions take four components at a time: each four
// rows are transposed in registers before they are stored.
void Lanes::spill(const Expr& e) {
  if (trivial(e) || !spilled_.insert(&e).second) return;
  Value* v = lanes(e);
  const int t = ty_index(e.ty);
  if (e.ty == Ty::F64) {
    const int row = roots_.at(&e);
    Value* narrow = root_buffer32_ ? codegen::widened_binary32(v) : nullptr;
    if (!pending_.empty() && (narrow != nullptr) != pending_narrow_)
      flush_pending(row - static_cast<int>(pending_.size()));
    pending_narrow_ = narrow != nullptr;
    narrow_row_[static_cast<size_t>(row)] = pending_narrow_;
    pending_.push_back(narrow ? narrow : v);
    if (n_ % 4 == 0 && pending_.size() == 4) flush_pending(row - 3);
    return;
  }
  if (e.ty == Ty::Bool)
    v = b_.CreateZExt(v, llvm::FixedVectorType::get(b_.getInt8Ty(), static_cast<unsigned>(n_)));
  llvm::Type* elem = root_type(b_, e.ty);
  Value* at = b_.CreateConstInBoundsGEP1_64(elem, root_buffer_[t],
                                            static_cast<uint64_t>(roots_.at(&e)) * n_);
  b_.CreateAlignedStore(v, at, llvm::Align(8));
}

// Stores the pending float rows first, first + 1, ...: four of them transposed (one vector
// per lane; with 8 lanes each half of the rows in turn), fewer component by component.
void Lanes::flush_pending(int first) {
  llvm::Type* elem = pending_narrow_ ? b_.getFloatTy() : b_.getDoubleTy();
  Value* buffer = pending_narrow_ ? root_buffer32_ : root_buffer_[0];
  auto at = [&](int lane, int row) {
    return b_.CreateConstInBoundsGEP1_64(
        elem, buffer, static_cast<uint64_t>(lane) * root_stride_ + static_cast<uint64_t>(row));
  };
  if (pending_.size() == 4 && n_ % 4 == 0) {
    for (int base = 0; base < n_; base += 4) {
      Value* v[4];
      for (int r = 0; r < 4; ++r)
        v[r] = n_ == 4 ? pending_[static_cast<size_t>(r)]
                       : b_.CreateShuffleVector(pending_[static_cast<size_t>(r)],
                                                {base, base + 1, base + 2, base + 3});
      Value* a = b_.CreateShuffleVector(v[0], v[1], {0, 4, 2, 6});
      Value* b = b_.CreateShuffleVector(v[0], v[1], {1, 5, 3, 7});
      Value* c = b_.CreateShuffleVector(v[2], v[3], {0, 4, 2, 6});
      Value* d = b_.CreateShuffleVector(v[2], v[3], {1, 5, 3, 7});
      Value* lane[4] = {
          b_.CreateShuffleVector(a, c, {0, 1, 4, 5}), b_.CreateShuffleVector(b, d, {0, 1, 4, 5}),
          b_.CreateShuffleVector(a, c, {2, 3, 6, 7}), b_.CreateShuffleVector(b, d, {2, 3, 6, 7})};
      for (int l = 0; l < 4; ++l)
        b_.CreateAlignedStore(lane[l], at(base + l, first), llvm::Align(pending_narrow_ ? 4 : 8));
    }
  } else {
    for (size_t r = 0; r < pending_.size(); ++r)
      for (int l = 0; l < n_; ++l)
        b_.CreateStore(b_.CreateExtractElement(pending_[r], static_cast<uint64_t>(l)),
                       at(l, first + static_cast<int>(r)));
  }
  pending_.clear();
}

Value* Lanes::root_address(int row, bool narrow) {
  return b_.CreateInBoundsGEP(narrow ? b_.getFloatTy() : b_.getDoubleTy(),
                              narrow ? root_buffer32_ : root_buffer_[0],
                              b_.CreateAdd(b_.CreateMul(lane_, b_.getInt64(root_stride_)),
                                           b_.getInt64(static_cast<uint64_t>(row))));
}

Value* Lanes::load_root(Ty t, int row) {
  if (t == Ty::F64) {
    if (narrow_row_[static_cast<size_t>(row)])
      return b_.CreateFPExt(b_.CreateLoad(b_.getFloatTy(), root_address(row, true)),
                            b_.getDoubleTy());
    return b_.CreateLoad(b_.getDoubleTy(), root_address(row));
  }
  llvm::Type* elem = root_type(b_, t);
  Value* at =
      b_.CreateInBoundsGEP(elem, root_buffer_[ty_index(t)],
                           b_.CreateAdd(b_.getInt64(static_cast<uint64_t>(row) * n_), lane_));
  Value* v = b_.CreateLoad(elem, at);
  return t == Ty::Bool ? b_.CreateICmpNE(v, b_.getInt8(0)) : v;
}

Value* Lanes::lanes(const Expr& e) {
  auto it = vmemo_.find(&e);
  if (it != vmemo_.end()) return it->second;
  Value* v = lanes_uncached(e);
  vmemo_.emplace(&e, v);
  return v;
}

Value* Lanes::lanes_uncached(const Expr& e) {
  auto gather = [&](const std::vector<Value*>& per_lane) {
    Value* v = llvm::PoisonValue::get(
        llvm::FixedVectorType::get(per_lane[0]->getType(), static_cast<unsigned>(n_)));
    for (int l = 0; l < n_; ++l)
      v = b_.CreateInsertElement(v, per_lane[static_cast<size_t>(l)], static_cast<uint64_t>(l));
    return v;
  };
  switch (e.kind) {
    case ExprKind::Const:
    case ExprKind::Scalar: {
      Value* v = k_.expr(e);
      // A binary32 value widened (a float argument under --float32): splatted as binary32
      // and widened as one vector, which in_binary32 sees.
      if (Value* narrow = codegen::widened_binary32(v))
        return b_.CreateFPExt(
            b_.CreateVectorSplat(static_cast<unsigned>(n_), narrow),
            llvm::FixedVectorType::get(b_.getDoubleTy(), static_cast<unsigned>(n_)));
      return b_.CreateVectorSplat(static_cast<unsigned>(n_), v);
    }
    case ExprKind::Element: return gather(element_lane_);
    case ExprKind::Endpoint: return gather(endpoint_lane_[static_cast<size_t>(e.slot)]);
    case ExprKind::Load: {
      const Expr& at = *e.ops[0];
      std::vector<Value*> index, values;
      if (at.kind == ExprKind::Element) {
        index = element_lane_;
      } else if (at.kind == ExprKind::Endpoint) {
        index = endpoint_lane_[static_cast<size_t>(at.slot)];
      } else {
        Value* v = lanes(at);
        for (int l = 0; l < n_; ++l) index.push_back(b_.CreateExtractElement(v, l));
      }
      for (Value* i : index) values.push_back(k_.load(e, i));
      // A binary32 field's values are gathered as they are stored and widened as one vector:
      // Emitter::in_binary32 then sees the widening and computes their operations in
      // binary32 (--float32), where widened one by one they would stay binary64.
      std::vector<Value*> narrow;
      for (Value* v : values)
        if (Value* n = codegen::widened_binary32(v)) narrow.push_back(n);
      if (narrow.size() == values.size())
        return b_.CreateFPExt(gather(narrow), llvm::FixedVectorType::get(
                                                  b_.getDoubleTy(), static_cast<unsigned>(n_)));
      return gather(values);
    }
    case ExprKind::Local: return vlocal_[static_cast<size_t>(e.slot)];
    default: {
      std::vector<Value*> args;
      for (const ExprRef& o : e.ops) args.push_back(lanes(*o));
      return k_.combine(e, args);
    }
  }
}

}  // namespace

void run_lanes(codegen::MapEmitter& k, Value* first, Value* end) { Lanes(k).run(first, end); }

}  // namespace simit::jit::cpu
