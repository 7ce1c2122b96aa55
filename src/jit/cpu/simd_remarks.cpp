// The loop and SLP vectorisers' remarks on a kernel's loops (jit/cpu/simd_remarks.h).
#include "jit/cpu/simd_remarks.h"

#include <algorithm>
#include <cctype>
#include <unordered_map>

#include <llvm/Analysis/LoopInfo.h>
#include <llvm/IR/Constants.h>
#include <llvm/IR/Dominators.h>
#include <llvm/IR/Instructions.h>
#include <llvm/IR/Metadata.h>

namespace simit::jit::cpu {

namespace {

constexpr const char* kTag = "simit.loop";

// The loop number a tagged loop ID carries, or 0.
int number_of(const llvm::MDNode* id) {
  if (!id) return 0;
  for (const llvm::MDOperand& op : id->operands()) {
    const auto* entry = llvm::dyn_cast_or_null<llvm::MDNode>(op.get());
    if (!entry || entry == id || entry->getNumOperands() != 2) continue;
    const auto* name = llvm::dyn_cast<llvm::MDString>(entry->getOperand(0));
    if (!name || name->getString() != kTag) continue;
    if (const auto* n = llvm::mdconst::dyn_extract<llvm::ConstantInt>(entry->getOperand(1)))
      return static_cast<int>(n->getSExtValue());
  }
  return 0;
}

// The number of the loop whose header is `header` (its latches' branches carry the loop ID),
// or 0: not a tagged loop's header.
int number_of_header(const llvm::BasicBlock* header) {
  for (const llvm::BasicBlock* pred : llvm::predecessors(header))
    if (const llvm::Instruction* t = pred->getTerminator())
      if (int n = number_of(t->getMetadata(llvm::LLVMContext::MD_loop))) return n;
  return 0;
}

// What a loop's own blocks (not its inner loops') hold, for its description.
struct Shape {
  bool i32_counter = false;  // the emitter counts a pass's components in i32
  bool vector_store = false, vector_fmul = false, int_load = false;
};

Shape shape_of(const llvm::Loop& l, const llvm::LoopInfo& li) {
  Shape s;
  if (const auto* phi = llvm::dyn_cast<llvm::PHINode>(&l.getHeader()->front()))
    s.i32_counter = phi->getType()->isIntegerTy(32);
  for (const llvm::BasicBlock* bb : l.blocks()) {
    if (li.getLoopFor(bb) != &l) continue;
    for (const llvm::Instruction& i : *bb) {
      if (const auto* st = llvm::dyn_cast<llvm::StoreInst>(&i))
        s.vector_store |= st->getValueOperand()->getType()->isVectorTy();
      else if (i.getOpcode() == llvm::Instruction::FMul)
        s.vector_fmul |= i.getType()->isVectorTy();
      else if (llvm::isa<llvm::LoadInst>(i))
        s.int_load |= i.getType()->isIntegerTy(32);
    }
  }
  return s;
}

bool is_while(const llvm::Loop* l) { return l->getHeader()->getName().starts_with("while"); }

// The loop around l, the solver's while loop not counted.
const llvm::Loop* parent_op_loop(const llvm::Loop& l) {
  const llvm::Loop* p = l.getParentLoop();
  return p && is_while(p) ? nullptr : p;
}

// What a loop of a system kernel (or of one of its outlined ops) does, read from its shape
// as the emitter makes it (jit/llvm/emit_system.cpp, emit_parallel.cpp).
std::string system_loop(const llvm::Loop& l, const llvm::LoopInfo& li, bool kernel_function) {
  if (is_while(&l)) return "the solver's while loop";
  const Shape s = shape_of(l, li);
  if (!l.isInnermost()) {
    for (const llvm::Loop* inner : l.getSubLoops())
      if (inner->isInnermost() && shape_of(*inner, li).vector_fmul && shape_of(*inner, li).int_load)
        return "product rows";
    return "a sum's chunks";
  }
  if (s.vector_fmul && s.int_load) return "a product row's blocks";
  if (parent_op_loop(l))
    return s.vector_store ? "a sum's runs, four in vectors" : "a sum's runs one by one";
  if (s.i32_counter) return "vector pass";
  return kernel_function ? "the chunks' partial sums in order" : "a loop";
}

// What a loop of a map kernel does.
std::string map_loop(const llvm::Loop& l, bool lanes) {
  if (l.getHeader()->getName().starts_with("element")) return "elements";
  return lanes ? "an element's writes, lane by lane" : "a tiled tensor's loop";
}

// Leading decimal digits of `s` (a remark argument), or 1.
int leading_int(const std::string& s) {
  int v = 0;
  size_t i = 0;
  for (; i < s.size() && std::isdigit(static_cast<unsigned char>(s[i])) && v < 100000; ++i)
    v = v * 10 + (s[i] - '0');
  return i == 0 || v < 1 ? 1 : v;
}

// Hands the vectorisers' remarks to SimdRemarks; other diagnostics go to LLVM's default.
class RemarkHandler : public llvm::DiagnosticHandler {
 public:
  explicit RemarkHandler(SimdRemarks& r) : r_(r) {}
  bool handleDiagnostics(const llvm::DiagnosticInfo& d) override {
    const auto* opt = llvm::dyn_cast<llvm::DiagnosticInfoOptimizationBase>(&d);
    if (!opt) return false;
    if (wanted(opt->getPassName())) r_.remark(*opt);
    return true;  // remarks are never printed
  }
  bool isAnalysisRemarkEnabled(llvm::StringRef pass) const override { return wanted(pass); }
  bool isMissedOptRemarkEnabled(llvm::StringRef pass) const override { return wanted(pass); }
  bool isPassedOptRemarkEnabled(llvm::StringRef pass) const override { return wanted(pass); }
  bool isAnyRemarkEnabled() const override { return true; }

 private:
  static bool wanted(llvm::StringRef pass) {
    return pass == "loop-vectorize" || pass == "slp-vectorizer";
  }
  SimdRemarks& r_;
};

}  // namespace

SimdRemarks::SimdRemarks(llvm::Module& m, bool lanes) {
  llvm::LLVMContext& ctx = m.getContext();
  for (llvm::Function& f : m) {
    if (f.isDeclaration()) continue;
    llvm::DominatorTree dt(f);
    llvm::LoopInfo li(dt);
    llvm::SmallVector<llvm::Loop*, 4> loops = li.getLoopsInPreorder();
    // The emitter appends a loop's blocks to the function as it emits the loop, its header
    // first: the headers' order is the emission order.
    std::unordered_map<const llvm::BasicBlock*, size_t> place;
    for (const llvm::BasicBlock& bb : f) place.emplace(&bb, place.size());
    std::sort(loops.begin(), loops.end(), [&](const llvm::Loop* a, const llvm::Loop* b) {
      return place.at(a->getHeader()) < place.at(b->getHeader());
    });
    // A map kernel returns a status and takes its element range as two i32s, its fourth and
    // fifth arguments (jit/cpu/cpu_hooks.h); a system kernel takes six pointers; an outlined
    // op returns nothing.
    const bool map = f.arg_size() == 6 && f.getArg(3)->getType()->isIntegerTy(32);
    const bool kernel_function = !f.getReturnType()->isVoidTy();
    for (llvm::Loop* l : loops) {
      Loop seen;
      seen.what = map ? map_loop(*l, lanes) : system_loop(*l, li, kernel_function);
      loops_.push_back(seen);
      llvm::Metadata* tag[] = {llvm::MDString::get(ctx, kTag),
                               llvm::ConstantAsMetadata::get(llvm::ConstantInt::get(
                                   llvm::Type::getInt32Ty(ctx), loops_.size()))};
      llvm::TempMDNode self = llvm::MDNode::getTemporary(ctx, {});
      llvm::MDNode* id = llvm::MDNode::getDistinct(ctx, {self.get(), llvm::MDNode::get(ctx, tag)});
      id->replaceOperandWith(0, id);
      l->setLoopID(id);
    }
  }
}

std::unique_ptr<llvm::DiagnosticHandler> SimdRemarks::handler() {
  return std::make_unique<RemarkHandler>(*this);
}

void SimdRemarks::remark(const llvm::DiagnosticInfoOptimizationBase& r) {
  const bool passed = r.getKind() == llvm::DK_OptimizationRemark;
  if (r.getPassName() == "slp-vectorizer") {
    if (passed) ++slp_groups_;
    return;
  }
  int n = 0;
  if (const auto* ir = llvm::dyn_cast<llvm::DiagnosticInfoIROptimization>(&r))
    if (const auto* bb = llvm::dyn_cast_or_null<llvm::BasicBlock>(ir->getCodeRegion()))
      n = number_of_header(bb);
  const std::string name = r.getRemarkName().str();
  std::string reason;
  // A loop unswitching or versioning copied is two loops of one number: each copy's remarks
  // go to the number (a copy vectorised makes it vectorised).
  if (passed) {
    int width = 1, interleave = 1;
    for (const auto& a : r.getArgs()) {
      if (a.Key == "VectorizationFactor") width = leading_int(a.Val);
      if (a.Key == "InterleaveCount") interleave = leading_int(a.Val);
    }
    if (n > 0 && static_cast<size_t>(n) <= loops_.size()) {
      Loop& l = loops_[static_cast<size_t>(n) - 1];
      l.width = std::max(l.width, width);
      l.interleave = std::max(l.interleave, interleave);
    }
  } else if (name != "MissedDetails" && name.rfind("Interleav", 0) != 0) {
    // "loop not vectorized" alone says nothing more; the interleaving remarks are about the
    // interleave count, not about vectorising.
    reason = short_reason(name, r.getMsg());
  }
  if (!reason.empty()) pending_.push_back(reason);
  if (n <= 0 || static_cast<size_t>(n) > loops_.size()) {
    // A passed or missed remark names the loop's header, and ends what is said of a loop: a
    // loop the optimiser made (no number) takes its reasons with it.
    if (r.getKind() != llvm::DK_OptimizationRemarkAnalysis &&
        r.getKind() != llvm::DK_OptimizationRemarkAnalysisFPCommute &&
        r.getKind() != llvm::DK_OptimizationRemarkAnalysisAliasing)
      pending_.clear();
    return;
  }
  Loop& l = loops_[static_cast<size_t>(n) - 1];
  l.reported = true;
  for (std::string& why : pending_)
    if (std::find(l.why_not.begin(), l.why_not.end(), why) == l.why_not.end())
      l.why_not.push_back(std::move(why));
  pending_.clear();
}

void SimdRemarks::fill(SimdReport& report) const {
  report.slp_groups = slp_groups_;
  for (size_t i = 0; i < loops_.size(); ++i) {
    const Loop& l = loops_[i];
    if (!l.reported) continue;
    SimdLoop out;
    out.number = static_cast<int>(i + 1);
    out.what = l.what;
    out.width = l.width;
    out.interleave = l.interleave;
    for (const std::string& why : l.why_not) out.why_not += (out.why_not.empty() ? "" : ", ") + why;
    if (l.width == 1 && out.why_not.empty()) out.why_not = "no reason given";
    if (l.width > 1) out.why_not.clear();
    report.loops.push_back(out);
  }
}

std::string SimdRemarks::describe(const SimdLoop& loop) {
  std::string s = "loop " + std::to_string(loop.number) + " (" + loop.what + "): ";
  if (loop.width > 1)
    return s + "vectorised, width " + std::to_string(loop.width) + ", interleave " +
           std::to_string(loop.interleave);
  return s + "not vectorised: " + loop.why_not;
}

std::string short_reason(const std::string& remark_name, const std::string& message) {
  struct Short {
    const char* name;
    const char* words;
  };
  static const Short kShort[] = {
      {"CantReorderFPOps", "reduction in the contract's order"},
      {"CantReorderMemOps", "memory order it cannot prove"},
      {"CantVectorizeInstructionReturnType", "already in vectors"},
      {"UnsafeDep", "a value carried through memory"},
      {"CFGNotUnderstood", "control flow it cannot follow"},
      {"CantComputeNumberOfIterations", "trip count unknown"},
      {"CantIdentifyArrayBounds", "indirect accesses"},
      {"CantVectorizeCall", "a call it cannot widen"},
      {"CantVectorizeLibcall", "a call it cannot widen"},
      {"NonReductionValueUsedOutsideLoop", "a value used after the loop"},
      {"NoInductionVariable", "no counter"},
      {"VectorizationNotBeneficial", "not profitable"},
  };
  for (const Short& s : kShort)
    if (remark_name == s.name) return s.words;
  // LLVM's own words: its first sentence, without "loop not vectorized: ".
  std::string m = message;
  const std::string prefix = "loop not vectorized: ";
  if (m.rfind(prefix, 0) == 0) m.erase(0, prefix.size());
  const size_t end = m.find_first_of(".;\n");
  if (end != std::string::npos) m.resize(end);
  if (m.size() > 80) m.resize(80);
  return m.empty() ? remark_name : m;
}

}  // namespace simit::jit::cpu
