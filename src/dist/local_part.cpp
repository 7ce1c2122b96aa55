// One part of a partitioned mesh (dist/local_part.h).
#include "dist/local_part.h"

#include <algorithm>

namespace simit::dist {

int32_t element_owner(std::span<const int32_t> vertices, std::span<const int32_t> owner) {
  return owner[static_cast<size_t>(*std::min_element(vertices.begin(), vertices.end()))];
}

LocalPart local_part(std::span<const runtime::ElementList> lists, std::span<const int32_t> owner,
                     int32_t part) {
  LocalPart p;
  p.part = part;
  for (size_t v = 0; v < owner.size(); ++v)
    if (owner[v] == part) p.owned_vertices.push_back(static_cast<int32_t>(v));
  std::vector<uint8_t> ghost(owner.size(), 0);
  for (const runtime::ElementList& list : lists) {
    std::vector<int32_t>& mine = p.owned_elements.emplace_back();
    const auto arity = static_cast<size_t>(list.arity);
    const size_t count = list.indices.size() / arity;
    for (size_t e = 0; e < count; ++e) {
      const auto vs = list.indices.subspan(e * arity, arity);
      if (element_owner(vs, owner) != part) continue;
      mine.push_back(static_cast<int32_t>(e));
      for (int32_t v : vs)
        if (owner[static_cast<size_t>(v)] != part) ghost[static_cast<size_t>(v)] = 1;
    }
  }
  for (size_t v = 0; v < ghost.size(); ++v)
    if (ghost[v]) p.ghost_vertices.push_back(static_cast<int32_t>(v));
  return p;
}

}  // namespace simit::dist
