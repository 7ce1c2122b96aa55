// Set fields as VTK arrays (runtime/mesh/vtu_writer.h), for the frames a scene writes whole
// (scene/output_series.h) and the pieces of a distributed run's frames (scene/output_pieces.h).
#pragma once

#include <cstdint>
#include <deque>
#include <span>
#include <string>
#include <vector>

#include "runtime/mesh/vtu_writer.h"
#include "runtime/set.h"

namespace simit::scene {

// Field values of a set as a VTK array, in the order of `rows` (row r holds element rows[r];
// the set's own order when empty), converted to double or int32 where needed.
struct ArrayStore {
  std::deque<std::vector<double>> doubles;
  std::deque<std::vector<int32_t>> ints;

  template <typename To, typename From>
  std::span<const To> copy(std::deque<std::vector<To>>& store, const From* p, size_t components,
                           size_t count, std::span<const int32_t> rows) {
    std::vector<To>& out = store.emplace_back();
    out.reserve(count * components);
    for (size_t r = 0; r < count; ++r) {
      const From* e = p + (rows.empty() ? r : static_cast<size_t>(rows[r])) * components;
      out.insert(out.end(), e, e + components);
    }
    return out;
  }

  // The first `count` rows (every element of the set when negative). Values that need no
  // conversion are viewed where the field holds them, unless `own`: then the array is the
  // store's own (a frame written while the fields change: scene/frame_writer.h).
  runtime::VtuArray add(const runtime::Set& set, const std::string& name,
                        std::span<const int32_t> rows, int count_rows = -1, bool own = false) {
    const runtime::Field& f = set.field(name);
    const runtime::FieldType& ft = f.type();
    const size_t comps = ft.components();
    const size_t count = static_cast<size_t>(count_rows < 0 ? set.size() : count_rows);
    runtime::VtuArray a{name, static_cast<int>(comps), std::span<const double>()};
    switch (ft.kind) {
      case runtime::ComponentKind::Float:
        if (!ft.single && rows.empty() && !own)
          a.values = std::span<const double>(f.data<double>(), comps * count);
        else if (!ft.single)
          a.values = copy(doubles, f.data<double>(), comps, count, rows);
        else
          a.values = copy(doubles, f.data<float>(), comps, count, rows);
        break;
      case runtime::ComponentKind::Int:
        if (rows.empty() && !own)
          a.values = std::span<const int32_t>(f.data<int32_t>(), comps * count);
        else
          a.values = copy(ints, f.data<int32_t>(), comps, count, rows);
        break;
      case runtime::ComponentKind::Bool:
        a.values = copy(ints, f.data<bool>(), comps, count, rows);
        break;
      default: break;
    }
    return a;
  }
};

inline double coordinate(const runtime::Field& f, int i, int d) {
  return f.type().single ? f.at<float>(i)[d] : f.at<double>(i)[d];
}

}  // namespace simit::scene
