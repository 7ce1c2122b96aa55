// The scene's seam of a distributed run over MPI (dist/mpi/scene_distribution.h).
#include "dist/mpi/scene_distribution.h"

#include <cstring>
#include <map>
#include <stdexcept>
#include <string>

#include "dist/mpi/comm.h"
#include "dist/overlap.h"
#include "dist/partition.h"
#include "runtime/mesh/reorder.h"

namespace simit::dist::mpi {

namespace {

// One split set as this rank holds it.
struct Part {
  SetPart layout;
  GhostPlan plan;
};

class SceneDistribution final : public scene::Distributed {
 public:
  SceneDistribution() : session_(nullptr, nullptr) {}

  int rank() const override { return session_.rank(); }
  int ranks() const override { return session_.size(); }
  int owned(const runtime::Set& set) const override {
    auto it = parts_.find(&set);
    return it == parts_.end() ? set.size() : it->second.layout.owned;
  }
  bool split(const runtime::Set& set) const override {
    return session_.size() > 1 && parts_.count(&set) > 0;
  }
  double sum(double partial) const override {
    ++traffic_.sums;
    return session_.sum_in_rank_order(partial);
  }
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
  std::string describe_parts(const std::vector<runtime::Set*>& local) const override;
  std::string describe_traffic() const override;
  bool any(bool flag) const override { return session_.any(flag); }
  [[noreturn]] void abort(int status) const override { session_.abort(status); }

  std::vector<std::unique_ptr<runtime::Set>> localize(
      const std::vector<runtime::Set*>& whole) override;
  void gather(const std::vector<runtime::Set*>& local,
              const std::vector<runtime::Set*>& whole) const override;

 private:
  std::vector<int32_t> owners(const runtime::Set& vertices,
                              std::span<const runtime::ElementList> lists) const;
  std::unique_ptr<runtime::Set> make_part(const runtime::Set& whole, const SetPart& layout,
                                          const runtime::Set* endpoints,
                                          std::span<const int32_t> connectivity);

  Session session_;
  std::map<const runtime::Set*, Part> parts_;  // by the local set
  // What this rank sent (describe_traffic).
  struct Traffic {
    int64_t refreshes = 0, messages = 0, bytes = 0, sums = 0;
  };
  mutable Traffic traffic_;
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

// Copies the fields of `whole`'s elements `global` into `local` (same fields, same order).
void copy_fields(const runtime::Set& whole, std::span<const int32_t> global, runtime::Set& local) {
  for (int k = 0; k < whole.field_count(); ++k) {
    const runtime::Field& from = whole.field(k);
    const int index = local.add_field(from.name(), from.type());
    runtime::Field& to = local.field(index);
    const size_t bytes = from.element_bytes();
    if (bytes == 0 || global.empty()) continue;
    std::byte* dst = to.bytes();
    const std::byte* src = from.bytes();
    for (size_t i = 0; i < global.size(); ++i)
      std::memcpy(dst + i * bytes, src + static_cast<size_t>(global[i]) * bytes, bytes);
  }
}

// The rank of each vertex: METIS's parts (on rank 0, sent to the others) where edge sets join
// the vertices, else blocks of consecutive vertices.
std::vector<int32_t> SceneDistribution::owners(const runtime::Set& vertices,
                                               std::span<const runtime::ElementList> lists) const {
  const int32_t n = vertices.size();
  const int ranks = session_.size();
  std::vector<int32_t> owner(static_cast<size_t>(n));
  if (lists.empty() || n < ranks) {
    for (int32_t v = 0; v < n; ++v)
      owner[static_cast<size_t>(v)] =
          static_cast<int32_t>(static_cast<int64_t>(v) * ranks / std::max<int32_t>(n, 1));
    return owner;
  }
  std::vector<int32_t> head = {0};
  std::string error;
  if (session_.rank() == 0) {
    try {
      owner = partition_vertices(runtime::vertex_graph(n, lists), ranks, lists);
      head = {1};
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
  session_.broadcast(head);
  if (head[0] == 0)
    throw std::runtime_error(vertices.describe() + " could not be partitioned" +
                             (error.empty() ? "" : ": " + error));
  session_.broadcast(owner);
  return owner;
}

std::unique_ptr<runtime::Set> SceneDistribution::make_part(const runtime::Set& whole,
                                                           const SetPart& layout,
                                                           const runtime::Set* endpoints,
                                                           std::span<const int32_t> connectivity) {
  std::unique_ptr<runtime::Set> local;
  if (!endpoints) {
    local = std::make_unique<runtime::Set>(whole.name());
    local->add_many(static_cast<int>(layout.global.size()));
  } else {
    local = std::make_unique<runtime::Set>(
        whole.name(),
        std::vector<const runtime::Set*>(static_cast<size_t>(whole.arity()), endpoints));
    local->add_edges(connectivity);
  }
  copy_fields(whole, layout.global, *local);
  std::vector<int32_t> numbers;
  numbers.reserve(layout.global.size());
  for (int32_t g : layout.global) numbers.push_back(whole.mesh_number(g));
  local->set_mesh_numbers(std::move(numbers), whole.size());
  return local;
}

std::vector<std::unique_ptr<runtime::Set>> SceneDistribution::localize(
    const std::vector<runtime::Set*>& whole) {
  std::vector<std::unique_ptr<runtime::Set>> out(whole.size());
  for (size_t k = 0; k < whole.size(); ++k) {
    const runtime::Set& v = *whole[k];
    if (v.is_grid() || (v.arity() == 0 && v.kind() == runtime::SetKind::Grid))
      throw std::runtime_error(v.describe() +
                               " is a grid, which a distributed run cannot split yet");
    if (v.arity() != 0) continue;
    // The edge sets over this vertex set: every endpoint in it.
    std::vector<size_t> edge_sets;
    std::vector<runtime::ElementList> lists;
    for (size_t j = 0; j < whole.size(); ++j) {
      const runtime::Set& e = *whole[j];
      if (e.arity() == 0) continue;
      bool over = true;
      for (const runtime::Set* s : e.endpoint_sets()) over = over && s == &v;
      if (!over) continue;
      edge_sets.push_back(j);
      lists.push_back(
          {std::span<const int32_t>(e.endpoints(), static_cast<size_t>(e.size()) * e.arity()),
           e.arity()});
    }
    const std::vector<int32_t> owner = owners(v, lists);
    RankLayout layout = overlap_layout(owner, lists, session_.size(), session_.rank());
    out[k] = make_part(v, layout.vertices, nullptr, {});
    parts_[out[k].get()] = Part{std::move(layout.vertices), std::move(layout.vertex_plan)};
    for (size_t i = 0; i < edge_sets.size(); ++i) {
      const size_t j = edge_sets[i];
      out[j] =
          make_part(*whole[j], layout.edge_sets[i], out[k].get(), layout.local_connectivity[i]);
      parts_[out[j].get()] = Part{std::move(layout.edge_sets[i]), std::move(layout.edge_plans[i])};
    }
  }
  for (size_t j = 0; j < whole.size(); ++j)
    if (!out[j])
      throw std::runtime_error(whole[j]->describe() +
                               " has endpoints in more than one set, which a distributed run "
                               "cannot split yet");
  return out;
}

void SceneDistribution::gather(const std::vector<runtime::Set*>& local,
                               const std::vector<runtime::Set*>& whole) const {
  for (size_t k = 0; k < local.size() && k < whole.size(); ++k) {
    const Part& part = parts_.at(local[k]);
    const std::span<const int32_t> owned(part.layout.global.data(),
                                         static_cast<size_t>(part.layout.owned));
    for (int f = 0; f < local[k]->field_count(); ++f) {
      const runtime::Field& from = local[k]->field(f);
      const size_t bytes = from.element_bytes();
      const std::span<const std::byte> values(from.bytes(), owned.size() * bytes);
      std::vector<std::byte> all = session_.gather_owned(owned, values, bytes, whole[k]->size());
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
    figures.push_back({session_.gather(part.layout.owned),
                       session_.gather(set->size() - part.layout.owned), session_.gather(sent),
                       session_.gather(neighbours)});
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
