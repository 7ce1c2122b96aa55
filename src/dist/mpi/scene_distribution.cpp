// The scene's seam of a distributed run over MPI (dist/mpi/scene_distribution.h).
#include "dist/mpi/scene_distribution.h"

#include <algorithm>
#include <cstring>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>

#include "dist/mpi/comm.h"
#include "dist/overlap.h"
#include "dist/set_parts.h"
#include "dist/sum_terms.h"
#ifdef SIMIT_HAVE_PETSC
#include "dist/mpi/petsc_solver.h"
#endif

namespace simit::dist::mpi {

namespace {

// One split set as this rank holds it.
struct Part {
  SetPart layout;
  GhostPlan plan;
  int32_t whole_size = 0;  // the set's size in one process
};

class SceneDistribution final : public scene::Distributed {
 public:
  SceneDistribution() : session_(nullptr, nullptr) {}

  int rank() const override { return session_.rank(); }
  int ranks() const override { return session_.size(); }
  const std::vector<int32_t>* owned(const runtime::Set& set) const override {
    auto it = parts_.find(&set);
    return it == parts_.end() ? nullptr : &it->second.layout.owned;
  }
  bool split(const runtime::Set& set) const override {
    return session_.size() > 1 && parts_.count(&set) > 0;
  }
  double blocked_sum(const runtime::Set& set, std::span<const double> sums) const override;
  void refresh(const runtime::Set& set, std::span<std::byte> values,
               size_t element_bytes) const override {
    auto it = parts_.find(&set);
    if (it == parts_.end()) return;
    ++traffic_.refreshes;
    for (const GhostLink& link : it->second.plan.links)
      if (!link.send.empty()) {
        ++traffic_.messages;
        traffic_.bytes += static_cast<int64_t>(link.send.size() * element_bytes);
      }
    session_.refresh_ghosts(it->second.plan, values, element_bytes);
  }
  bool solve(const runtime::SystemMatrix& a, const runtime::Set& rows, std::span<const double> b,
             std::span<double> x, std::string& why) const override {
#ifdef SIMIT_HAVE_PETSC
    auto it = parts_.find(&rows);
    if (it == parts_.end()) {
      why = rows.describe() + " is not split over the ranks";
      return false;
    }
    return petsc_.solve(a, it->second.layout, it->second.plan, b, x, why);
#else
    (void)a, (void)rows, (void)b, (void)x;
    why = "this simit was built without PETSc (libpetsc-real-dev)";
    return false;
#endif
  }
  std::string describe_parts(const std::vector<runtime::Set*>& local) const override;
  std::string describe_traffic() const override;
  bool any(bool flag) const override { return session_.any(flag); }
  void least(std::vector<int64_t>& values) const override { session_.least(values); }
  void broadcast(std::string& text) const override {
    std::vector<int32_t> codes(text.begin(), text.end());
    session_.broadcast(codes);
    text.assign(codes.begin(), codes.end());
  }
  [[noreturn]] void abort(int status) const override { session_.abort(status); }
  [[noreturn]] void wait_for_abort() const override { session_.wait_for_abort(); }

  std::vector<std::unique_ptr<runtime::Set>> localize(
      const std::vector<runtime::Set*>& whole) override;
  void gather(const std::vector<runtime::Set*>& local,
              const std::vector<runtime::Set*>& whole) const override;

 private:
  Session session_;
  std::map<const runtime::Set*, Part> parts_;  // by the local set
  // What this rank sent (describe_traffic).
  struct Traffic {
    int64_t refreshes = 0, messages = 0, bytes = 0, sums = 0;
  };
  mutable Traffic traffic_;
#ifdef SIMIT_HAVE_PETSC
  mutable PetscSolver petsc_{session_};  // after the session: ends before MPI does
#endif
};

// 1234567 as "1,234,567".
std::string grouped(int64_t n) {
  std::string digits = std::to_string(n < 0 ? -n : n), out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return n < 0 ? "-" + out : out;
}

std::vector<std::unique_ptr<runtime::Set>> SceneDistribution::localize(
    const std::vector<runtime::Set*>& whole) {
  // Rank 0 read the meshes: it cuts the sets and sends each rank its part.
  std::vector<std::vector<std::byte>> messages;
  std::vector<int32_t> ok = {1};
  std::string error;
  if (session_.rank() == 0) {
    try {
      messages = encode_parts(std::vector<const runtime::Set*>(whole.begin(), whole.end()),
                              session_.size());
    } catch (const std::exception& e) {
      error = e.what();
      ok = {0};
    }
  }
  session_.broadcast(ok);
  if (ok[0] == 0) {
    if (session_.rank() == 0) throw std::runtime_error(error);
    session_.wait_for_abort();  // rank 0 reports it
  }
  LocalSets mine = decode_part(session_.scatter(std::move(messages)));
  for (size_t k = 0; k < mine.sets.size(); ++k)
    parts_[mine.sets[k].get()] =
        Part{std::move(mine.layouts[k]), std::move(mine.plans[k]), mine.whole_sizes[k]};
  return std::move(mine.sets);
}

double SceneDistribution::blocked_sum(const runtime::Set& set, std::span<const double> sums) const {
  auto it = parts_.find(&set);
  if (it == parts_.end()) {  // every rank holds the set whole and owns every term
    std::vector<int64_t> global(sums.size());
    std::iota(global.begin(), global.end(), int64_t{0});
    return combine_contributions(sum_contribution(global, sums, static_cast<int64_t>(sums.size())));
  }
  ++traffic_.sums;
  const Part& part = it->second;
  const size_t local = part.layout.global.size();
  if (local > 0 && sums.size() % local != 0)
    throw std::invalid_argument("a sum over " + set.describe() + " of " +
                                std::to_string(sums.size()) + " terms, not so many per element");
  // The terms are the whole set's in its order, m per element: term m * element + j.
  const size_t m = local > 0 ? sums.size() / local : 0;
  std::vector<int64_t> global;
  std::vector<double> terms;
  global.reserve(part.layout.owned.size() * m);
  terms.reserve(global.capacity());
  for (int32_t i : part.layout.owned)
    for (size_t j = 0; j < m; ++j) {
      global.push_back(static_cast<int64_t>(part.layout.global[static_cast<size_t>(i)]) *
                           static_cast<int64_t>(m) +
                       static_cast<int64_t>(j));
      terms.push_back(sums[static_cast<size_t>(i) * m + j]);
    }
  const std::vector<double> mine = sum_contribution(
      global, terms, static_cast<int64_t>(part.whole_size) * static_cast<int64_t>(m));
  // Every rank combines the same contributions alike: the same bits everywhere.
  return combine_contributions(session_.all_gather(mine));
}

void SceneDistribution::gather(const std::vector<runtime::Set*>& local,
                               const std::vector<runtime::Set*>& whole) const {
  for (size_t k = 0; k < local.size() && k < whole.size(); ++k) {
    const Part& part = parts_.at(local[k]);
    std::vector<int32_t> owned;
    owned.reserve(part.layout.owned.size());
    for (int32_t i : part.layout.owned) owned.push_back(part.layout.global[static_cast<size_t>(i)]);
    std::vector<std::byte> values;
    for (int f = 0; f < local[k]->field_count(); ++f) {
      const runtime::Field& from = local[k]->field(f);
      const size_t bytes = from.element_bytes();
      values.resize(owned.size() * bytes);
      for (size_t n = 0; n < owned.size(); ++n)
        std::memcpy(values.data() + n * bytes,
                    from.bytes() + static_cast<size_t>(part.layout.owned[n]) * bytes, bytes);
      std::vector<std::byte> all = session_.gather_owned(owned, values, bytes, part.whole_size);
      if (session_.rank() != 0 || all.empty()) continue;
      std::memcpy(whole[k]->field(f).bytes(), all.data(), all.size());
    }
  }
}

std::string SceneDistribution::describe_parts(const std::vector<runtime::Set*>& local) const {
  // Per set, per rank: owned, ghosts, entries sent per refresh, neighbours.
  std::vector<std::vector<std::vector<int64_t>>> figures;  // [set][figure][rank]
  for (const runtime::Set* set : local) {
    const Part& part = parts_.at(set);
    int64_t sent = 0, neighbours = 0;
    for (const GhostLink& link : part.plan.links) {
      sent += static_cast<int64_t>(link.send.size());
      neighbours += 1;
    }
    figures.push_back({session_.gather(static_cast<int64_t>(part.layout.owned.size())),
                       session_.gather(static_cast<int64_t>(part.layout.ghosts.size())),
                       session_.gather(sent), session_.gather(neighbours)});
  }
  if (session_.rank() != 0) return "";
  std::string text;
  for (int r = 0; r < session_.size(); ++r) {
    const auto i = static_cast<size_t>(r);
    text += "rank " + std::to_string(r) + ":";
    for (size_t k = 0; k < local.size(); ++k)
      text += std::string(k == 0 ? " " : "; ") + local[k]->name() + " " +
              grouped(figures[k][0][i]) + " owned + " + grouped(figures[k][1][i]) +
              " ghosts, sends " + grouped(figures[k][2][i]) + " per refresh to " +
              grouped(figures[k][3][i]) + (figures[k][3][i] == 1 ? " rank" : " ranks");
    text += "\n";
  }
  return text;
}

std::string SceneDistribution::describe_traffic() const {
  const std::vector<int64_t> refreshes = session_.gather(traffic_.refreshes),
                             messages = session_.gather(traffic_.messages),
                             bytes = session_.gather(traffic_.bytes),
                             sums = session_.gather(traffic_.sums);
  if (session_.rank() != 0) return "";
  std::string text;
  for (int r = 0; r < session_.size(); ++r) {
    const auto i = static_cast<size_t>(r);
    text += "rank " + std::to_string(r) + " sent " + grouped(bytes[i]) + " bytes in " +
            grouped(messages[i]) + " messages (" + grouped(refreshes[i]) +
            " ghost refreshes) and took part in " + grouped(sums[i]) + " sums across ranks\n";
  }
  return text;
}

}  // namespace

std::shared_ptr<scene::Distributed> start_scene_distribution() {
  return std::make_shared<SceneDistribution>();
}

}  // namespace simit::dist::mpi
