// A scene's sets cut into the ranks' parts and sent as messages (dist/set_parts.h).
#include "dist/set_parts.h"

#include <algorithm>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>

#include "dist/partition.h"
#include "runtime/blocked_sum.h"
#include "runtime/mesh/reorder.h"

namespace simit::dist {

namespace {

// Appends numbers and bytes to a message.
class Writer {
 public:
  explicit Writer(std::vector<std::byte>& out) : out_(out) {}
  void int32(int32_t v) { bytes(&v, sizeof v); }
  void ints(std::span<const int32_t> v) {
    int32(static_cast<int32_t>(v.size()));
    bytes(v.data(), v.size_bytes());
  }
  void text(const std::string& s) {
    int32(static_cast<int32_t>(s.size()));
    bytes(s.data(), s.size());
  }
  void bytes(const void* p, size_t n) {
    const auto* b = static_cast<const std::byte*>(p);
    out_.insert(out_.end(), b, b + n);
  }

 private:
  std::vector<std::byte>& out_;
};

// Reads them back, checking that the message holds what is read.
class Reader {
 public:
  explicit Reader(std::span<const std::byte> in) : in_(in) {}
  int32_t int32() {
    int32_t v;
    bytes(&v, sizeof v);
    return v;
  }
  std::vector<int32_t> ints() {
    std::vector<int32_t> v(count(sizeof(int32_t)));
    bytes(v.data(), v.size() * sizeof(int32_t));
    return v;
  }
  std::string text() {
    std::string s(count(1), '\0');
    bytes(s.data(), s.size());
    return s;
  }
  void bytes(void* p, size_t n) {
    if (n > in_.size() - at_) throw std::runtime_error("a set part's message is cut short");
    if (n > 0) std::memcpy(p, in_.data() + at_, n);
    at_ += n;
  }
  size_t count(size_t each) {
    const int32_t n = int32();
    if (n < 0 || static_cast<size_t>(n) * each > in_.size() - at_)
      throw std::runtime_error("a set part's message is cut short");
    return static_cast<size_t>(n);
  }
  bool done() const { return at_ == in_.size(); }

 private:
  std::span<const std::byte> in_;
  size_t at_ = 0;
};

// The rank of each vertex: whole chunks of the contract's blocked sums each
// (dist/partition.h), so that a reduction over the set sends one partial per chunk.
std::vector<int32_t> owners(const runtime::Set& vertices,
                            std::span<const runtime::ElementList> lists, int ranks) {
  try {
    return partition_in_chunks(vertices.size(), lists, ranks,
                               static_cast<int32_t>(runtime::kSumChunk));
  } catch (const std::exception& e) {
    throw std::runtime_error(vertices.describe() + " could not be partitioned: " + e.what());
  }
}

// One set's part in a message: see decode_part for the order.
void write_part(Writer& w, const runtime::Set& whole, int endpoints, const SetPart& layout,
                const GhostPlan& plan, std::span<const int32_t> connectivity) {
  w.text(whole.name());
  w.int32(whole.arity());
  w.int32(endpoints);
  w.int32(whole.size());
  w.ints(layout.global);
  w.ints(layout.owned);
  w.ints(layout.ghosts);
  w.ints(layout.ghost_owner);
  w.int32(static_cast<int32_t>(plan.links.size()));
  for (const GhostLink& link : plan.links) {
    w.int32(link.rank);
    w.ints(link.send);
    w.ints(link.recv);
  }
  w.ints(connectivity);
  std::vector<int32_t> numbers;
  numbers.reserve(layout.global.size());
  for (int32_t g : layout.global) numbers.push_back(whole.mesh_number(g));
  w.ints(numbers);
  w.int32(whole.field_count());
  for (int k = 0; k < whole.field_count(); ++k) {
    const runtime::Field& f = whole.field(k);
    w.text(f.name());
    w.int32(static_cast<int32_t>(f.type().kind));
    w.ints(f.type().dims);
    w.int32(f.type().single ? 1 : 0);
    const size_t bytes = f.element_bytes();
    w.int32(static_cast<int32_t>(bytes));
    const std::byte* data = f.bytes();
    for (int32_t g : layout.global) w.bytes(data + static_cast<size_t>(g) * bytes, bytes);
  }
}

// Whether a decoded layout is one overlap_layout could give: global ascending in [0, whole),
// owned and ghosts ascending and together every local index once, an owner per ghost.
bool holds_together(const SetPart& layout, int32_t whole) {
  const auto ascending = [](const std::vector<int32_t>& v) {
    return std::adjacent_find(v.begin(), v.end(), std::greater_equal<>()) == v.end();
  };
  const size_t elements = layout.global.size();
  if (!ascending(layout.global) || !ascending(layout.owned) || !ascending(layout.ghosts) ||
      layout.owned.size() + layout.ghosts.size() != elements ||
      layout.ghost_owner.size() != layout.ghosts.size() ||
      (elements > 0 && (layout.global.front() < 0 || layout.global.back() >= whole)))
    return false;
  std::vector<uint8_t> seen(elements, 0);
  for (const std::vector<int32_t>* list : {&layout.owned, &layout.ghosts})
    for (int32_t i : *list) {
      if (i < 0 || static_cast<size_t>(i) >= elements || seen[static_cast<size_t>(i)]) return false;
      seen[static_cast<size_t>(i)] = 1;
    }
  return true;
}

}  // namespace

std::vector<std::vector<std::byte>> encode_parts(const std::vector<const runtime::Set*>& whole,
                                                 int ranks) {
  if (ranks < 1) throw std::runtime_error("a distributed run needs at least one rank");
  // Per set: its layouts on every rank (vertex sets with their edge sets).
  struct Cut {
    int endpoints = -1;  // the vertex set's index, for an edge set
    std::vector<SetPart> layouts;
    std::vector<GhostPlan> plans;
    std::vector<std::vector<int32_t>> connectivity;  // per rank (edge sets)
  };
  std::vector<Cut> cuts(whole.size());
  std::vector<bool> done(whole.size(), false);
  for (size_t k = 0; k < whole.size(); ++k) {
    const runtime::Set& v = *whole[k];
    if (v.is_grid())
      throw std::runtime_error(v.describe() +
                               " is a grid, which a distributed run cannot split yet");
    if (v.arity() != 0) continue;
    std::vector<size_t> edge_sets;
    std::vector<runtime::ElementList> lists;
    for (size_t j = 0; j < whole.size(); ++j) {
      const runtime::Set& e = *whole[j];
      if (e.arity() == 0) continue;
      if (!std::all_of(e.endpoint_sets().begin(), e.endpoint_sets().end(),
                       [&](const runtime::Set* s) { return s == &v; }))
        continue;
      edge_sets.push_back(j);
      lists.push_back(
          {std::span<const int32_t>(e.endpoints(), static_cast<size_t>(e.size()) * e.arity()),
           e.arity()});
    }
    const std::vector<int32_t> owner = owners(v, lists, ranks);
    for (size_t j : edge_sets) cuts[j].endpoints = static_cast<int>(k);
    for (int r = 0; r < ranks; ++r) {
      RankLayout layout = overlap_layout(owner, lists, ranks, r);
      cuts[k].layouts.push_back(std::move(layout.vertices));
      cuts[k].plans.push_back(std::move(layout.vertex_plan));
      for (size_t i = 0; i < edge_sets.size(); ++i) {
        Cut& c = cuts[edge_sets[i]];
        c.layouts.push_back(std::move(layout.edge_sets[i]));
        c.plans.push_back(std::move(layout.edge_plans[i]));
        c.connectivity.push_back(std::move(layout.local_connectivity[i]));
      }
    }
    done[k] = true;
    for (size_t j : edge_sets) done[j] = true;
  }
  for (size_t j = 0; j < whole.size(); ++j)
    if (!done[j])
      throw std::runtime_error(whole[j]->describe() +
                               " has endpoints in more than one set, which a distributed run "
                               "cannot split yet");
  std::vector<std::vector<std::byte>> messages(static_cast<size_t>(ranks));
  for (int r = 0; r < ranks; ++r) {
    Writer w(messages[static_cast<size_t>(r)]);
    w.int32(static_cast<int32_t>(whole.size()));
    // Vertex sets first, so that an edge set's endpoint set is there when it is decoded.
    for (int pass = 0; pass < 2; ++pass)
      for (size_t k = 0; k < whole.size(); ++k) {
        if ((whole[k]->arity() == 0) != (pass == 0)) continue;
        const Cut& c = cuts[k];
        const auto i = static_cast<size_t>(r);
        w.int32(static_cast<int32_t>(k));
        write_part(w, *whole[k], c.endpoints, c.layouts[i], c.plans[i],
                   c.connectivity.empty() ? std::span<const int32_t>() : c.connectivity[i]);
      }
  }
  return messages;
}

LocalSets decode_part(std::span<const std::byte> message) {
  Reader in(message);
  LocalSets out;
  const size_t count = in.count(1);
  out.sets.resize(count);
  out.layouts.resize(count);
  out.plans.resize(count);
  out.whole_sizes.resize(count);
  for (size_t n = 0; n < count; ++n) {
    const int32_t index = in.int32();
    if (index < 0 || static_cast<size_t>(index) >= count || out.sets[static_cast<size_t>(index)])
      throw std::runtime_error("a set part's message does not hold together");
    const auto k = static_cast<size_t>(index);
    const std::string name = in.text();
    const int32_t arity = in.int32();
    const int32_t endpoints = in.int32();
    const int32_t whole_size = in.int32();
    SetPart layout;
    layout.global = in.ints();
    layout.owned = in.ints();
    layout.ghosts = in.ints();
    layout.ghost_owner = in.ints();
    GhostPlan plan;
    plan.links.resize(in.count(3 * sizeof(int32_t)));
    for (GhostLink& link : plan.links) {
      link.rank = in.int32();
      link.send = in.ints();
      link.recv = in.ints();
    }
    const std::vector<int32_t> connectivity = in.ints();
    std::vector<int32_t> numbers = in.ints();
    const size_t elements = layout.global.size();
    if (!holds_together(layout, whole_size) || numbers.size() != elements ||
        (arity > 0 && (endpoints < 0 || static_cast<size_t>(endpoints) >= count ||
                       !out.sets[static_cast<size_t>(endpoints)] ||
                       connectivity.size() != elements * static_cast<size_t>(arity))))
      throw std::runtime_error("the part of set '" + name + "' does not hold together");
    std::unique_ptr<runtime::Set> set;
    if (arity == 0) {
      set = std::make_unique<runtime::Set>(name);
      set->add_many(static_cast<int>(elements));
    } else {
      const runtime::Set* ends = out.sets[static_cast<size_t>(endpoints)].get();
      set = std::make_unique<runtime::Set>(
          name, std::vector<const runtime::Set*>(static_cast<size_t>(arity), ends));
      set->add_edges(connectivity);
    }
    const size_t fields = in.count(1);
    for (size_t f = 0; f < fields; ++f) {
      const std::string field = in.text();
      runtime::FieldType type;
      type.kind = static_cast<runtime::ComponentKind>(in.int32());
      type.dims = in.ints();
      type.single = in.int32() != 0;
      const auto bytes = static_cast<size_t>(in.int32());
      const int index = set->add_field(field, type);
      runtime::Field& to = set->field(index);
      if (to.element_bytes() != bytes)
        throw std::runtime_error("field '" + field + "' of set '" + name +
                                 "' does not hold together");
      if (bytes > 0 && elements > 0) in.bytes(to.bytes(), bytes * elements);
    }
    set->set_mesh_numbers(std::move(numbers), whole_size);
    out.sets[k] = std::move(set);
    out.layouts[k] = std::move(layout);
    out.plans[k] = std::move(plan);
    out.whole_sizes[k] = whole_size;
  }
  if (!in.done()) throw std::runtime_error("a set part's message has bytes left over");
  return out;
}

}  // namespace simit::dist
