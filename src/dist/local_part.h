// One part of a partitioned mesh as its rank holds it: the vertices it owns, the elements it
// owns, and its ghosts (the vertices its elements reach that other parts own), all in the
// mesh's own numbering, so that every message and output can name the mesh's numbers.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "runtime/mesh/reorder.h"

namespace simit::dist {

// The part an element belongs to: its lowest-numbered vertex's (a rule every rank applies
// alike, without asking the others).
int32_t element_owner(std::span<const int32_t> vertices, std::span<const int32_t> owner);

struct LocalPart {
  int32_t part = 0;
  std::vector<int32_t> owned_vertices;               // ascending
  std::vector<int32_t> ghost_vertices;               // ascending
  std::vector<std::vector<int32_t>> owned_elements;  // per element list, ascending
};

// Part `part` of the elements of `lists` under `owner` (a part per vertex).
LocalPart local_part(std::span<const runtime::ElementList> lists, std::span<const int32_t> owner,
                     int32_t part);

}  // namespace simit::dist
