// Deferred assembly's tables and additions (jit/deferred_plan.h).
#include "jit/deferred_plan.h"

#include <algorithm>
#include <atomic>
#include <map>
#include <set>

#include "runtime/sum_rounding.h"

namespace simit::jit {

namespace {

// The pairs or members each assembled result is written through, by result index.
void written_places(const std::vector<Stmt>& body, const Trace& t,
                    std::map<int, std::set<int>>& out) {
  for (const Stmt& s : body) {
    if (s.kind == StmtKind::Assemble)
      out[t.arrays[static_cast<size_t>(s.slot)].index].insert(s.pair >= 0 ? s.pair : s.member);
    written_places(s.body, t, out);
    written_places(s.orelse, t, out);
  }
}

}  // namespace

bool DeferredPlan::prepare(const Trace& t, const runtime::Set& target,
                           const std::vector<Source>& results, int32_t chunk, bool split) {
  std::vector<const int32_t*> sources;
  std::vector<runtime::PatternPtr> patterns;
  for (const Source& s : results) {
    sources.push_back(s.table);
    patterns.push_back(s.pattern);
  }
  const bool same = set_id_ == target.id() && set_version_ == target.topology_version() &&
                    size_ == target.size() && sources == sources_ && patterns == patterns_;
  if (!same) {
    set_id_ = target.id();
    set_version_ = target.topology_version();
    size_ = target.size();
    sources_ = std::move(sources);
    patterns_ = std::move(patterns);
    built_split_ = false;
    results_.clear();
    std::map<int, std::set<int>> places;
    written_places(t.body, t, places);
    for (const auto& [index, written] : places) {
      Result r;
      r.result = index;
      r.vector = results[static_cast<size_t>(index)].table == nullptr;
      r.components = results[static_cast<size_t>(index)].components;
      r.written.assign(written.begin(), written.end());
      r.stride = r.vector ? target.arity() + 1 : t.pairs[static_cast<size_t>(index)];
      r.source = results[static_cast<size_t>(index)].table;
      if (r.vector) {
        // Entry m of an element: the element itself (m = 0) or its endpoint m - 1.
        const size_t stride = static_cast<size_t>(r.stride);
        const size_t arity = static_cast<size_t>(target.arity());
        const int32_t* ends = target.endpoints();
        r.plain.assign(static_cast<size_t>(target.size()) * stride, 0);
        int32_t* plain = r.plain.data();
        for (int32_t e = 0; e < target.size(); ++e)
          for (int m : r.written)
            plain[static_cast<size_t>(e) * stride + static_cast<size_t>(m)] =
                m == 0 ? e : ends[static_cast<size_t>(e) * arity + static_cast<size_t>(m - 1)];
        r.source = r.plain.data();
      }
      results_.push_back(std::move(r));
    }
  }
  float32_ = t.float32;
  split_ = false;
  if (!split) return true;
  bool fresh = false;  // build leaves the deferred blocks at -0.0
  if (!built_split_ || chunk_ != chunk) {
    fresh = true;
    chunk_ = chunk;
    built_split_ = true;
    split_ok_ = true;
    for (Result& r : results_)
      split_ok_ = split_ok_ && build(r, target, results[static_cast<size_t>(r.result)].blocks);
    // Process-wide, so that two plans (one freed, one at its address) never share a value.
    static std::atomic<uint64_t> builds{0};
    build_id_ = ++builds;
  }
  if (!split_ok_) return false;
  split_ = true;
  if (!fresh)
    for (Result& r : results_) std::fill(r.scratch.begin(), r.scratch.end(), -0.0);
  return true;
}

// A block's first chunk adds in place; each later contribution (element, block) gets a
// deferred block of its own, numbered in element order, so that adding them in number order
// adds each block's in element order. A deferred block starts at -0.0, which an addition
// leaves exactly the value added.
//
// Deferred block 0 is a sink: a specialised pattern's table has -1 for the blocks the guard
// knows the call does not write (jit/specialise.h); they point at the sink, which is never
// added anywhere.
bool DeferredPlan::build(Result& r, const runtime::Set& target, int64_t blocks) {
  // Hot: a plan is built on a site's first split call and again whenever its pattern changes
  // (a specialised result's, on the call after the one that recorded it), serially, once per
  // table entry (a fem stiffness on 160k tets: 2.6 million). Hence raw pointers (the stores
  // into the tables would otherwise make the compiler reload every vector's data) and a
  // per-block record of the last element that wrote it rather than a search of the
  // element's blocks.
  const size_t stride = static_cast<size_t>(r.stride);
  const int32_t n = target.size();
  r.split.assign(static_cast<size_t>(n) * stride, 0);
  r.dest.assign(1, -1);
  struct Seen {
    int32_t owner = -1;  // the chunk that adds into the block in place
    int32_t last = -1;   // the last element that wrote it
  };
  std::vector<Seen> seen(static_cast<size_t>(blocks));
  Seen* const state = seen.data();
  const int32_t* const source = r.source;
  int32_t* const split = r.split.data();
  const int* const written = r.written.data();
  const size_t places = r.written.size();
  for (int32_t c = 0, first = 0; first < n; ++c, first += chunk_) {
    const int32_t end = first + std::min(chunk_, n - first);
    for (int32_t e = first; e < end; ++e) {
      const size_t row = static_cast<size_t>(e) * stride;
      for (size_t w = 0; w < places; ++w) {
        const size_t at = row + static_cast<size_t>(written[w]);
        const int32_t b = source[at];
        if (b < 0) {
          split[at] = -1;  // the sink
          continue;
        }
        if (b >= blocks) return false;
        Seen& s = state[b];
        if (s.last == e) return false;  // the element writes the block through two members
        s.last = e;
        if (s.owner < 0) s.owner = c;
        if (s.owner == c) {
          split[at] = b;
        } else {
          split[at] = -1 - static_cast<int32_t>(r.dest.size());
          r.dest.push_back(b);
        }
      }
    }
  }
  r.scratch.assign(r.dest.size() * static_cast<size_t>(r.components), -0.0);
  // The gather index, by a counting sort of the deferred blocks by their block (k ascending
  // within each).
  const size_t deferred = r.dest.size();
  std::vector<int32_t> count(static_cast<size_t>(blocks), 0);
  for (size_t k = 1; k < deferred; ++k) ++count[static_cast<size_t>(r.dest[k])];
  r.gather_block.clear();
  r.gather_start.assign(1, 0);
  for (int64_t b = 0; b < blocks; ++b) {
    int32_t& c = count[static_cast<size_t>(b)];
    if (c == 0) continue;
    r.gather_block.push_back(static_cast<int32_t>(b));
    const int32_t start = r.gather_start.back();
    r.gather_start.push_back(start + c);
    c = start;  // from here on: the block's next slot in gather_k
  }
  r.gather_k.assign(deferred > 0 ? deferred - 1 : 0, 0);
  for (size_t k = 1; k < deferred; ++k)
    r.gather_k[static_cast<size_t>(count[static_cast<size_t>(r.dest[k])]++)] =
        static_cast<int32_t>(k);
  return true;
}

const int32_t* DeferredPlan::table(int result) const {
  for (const Result& r : results_)
    if (r.result == result) return split_ ? r.split.data() : r.source;
  return nullptr;
}

double* DeferredPlan::deferred(int result) {
  for (Result& r : results_)
    if (r.result == result) return r.scratch.data();
  return nullptr;
}

size_t DeferredPlan::table_entries(int result) const {
  for (const Result& r : results_)
    if (r.result == result) return static_cast<size_t>(size_) * static_cast<size_t>(r.stride);
  return 0;
}

size_t DeferredPlan::deferred_values(int result) const {
  for (const Result& r : results_)
    if (r.result == result) return r.scratch.size();
  return 0;
}

void DeferredPlan::finish(
    const std::vector<double*>& values,
    const std::function<void(int64_t, const std::function<void(int64_t)>&)>& for_each) const {
  if (!split_) return;
  // Blocks per task: enough that a task costs far more than handing it out.
  constexpr size_t kBlocksPerTask = 2048;
  for (const Result& r : results_) {
    double* v = values[static_cast<size_t>(r.result)];
    if (!v) continue;
    const size_t n = static_cast<size_t>(r.components);
    const size_t blocks = r.gather_block.size();
    auto add = [&](int64_t task) {
      const size_t first = static_cast<size_t>(task) * kBlocksPerTask;
      const size_t end = std::min(blocks, first + kBlocksPerTask);
      for (size_t i = first; i < end; ++i) {
        double* to = v + static_cast<size_t>(r.gather_block[i]) * n;
        for (int32_t j = r.gather_start[i]; j < r.gather_start[i + 1]; ++j) {
          const double* from = r.scratch.data() + static_cast<size_t>(r.gather_k[j]) * n;
          runtime::with_sums(float32_, [&]<class R>(R) {
            for (size_t c = 0; c < n; ++c) to[c] = R::r(to[c] + from[c]);
          });
        }
      }
    };
    const int64_t tasks = static_cast<int64_t>((blocks + kBlocksPerTask - 1) / kBlocksPerTask);
    if (for_each && tasks > 1) {
      for_each(tasks, add);
    } else {
      for (int64_t t = 0; t < tasks; ++t) add(t);
    }
  }
}

std::vector<DeferredPlan::Gather> DeferredPlan::gathers() const {
  std::vector<Gather> out;
  if (!split_) return out;
  for (const Result& r : results_) {
    Gather g;
    g.result = r.result;
    g.components = r.components;
    g.blocks = r.gather_block.size();
    g.block = r.gather_block.data();
    g.start = r.gather_start.data();
    g.k = r.gather_k.data();
    g.deferred = r.scratch.data();
    g.deferred_values = r.scratch.size();
    g.round32 = float32_;
    out.push_back(g);
  }
  return out;
}

int64_t DeferredPlan::deferred_blocks() const {
  int64_t n = 0;
  for (const Result& r : results_)
    n += r.dest.empty() ? 0 : static_cast<int64_t>(r.dest.size()) - 1;
  return n;
}

}  // namespace simit::jit
