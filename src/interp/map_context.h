// The state of one running `map` or `apply`: the target, the element being visited, the
// global results the mapped function writes into, and for stencil maps the offsets seen.
#pragma once

#include <deque>
#include <vector>

#include "interp/interpreter.h"

namespace simit::interp {

struct Interpreter::MapContext {
  const frontend::ast::Assembly* assembly = nullptr;
  frontend::SourceSpan at;  // the map expression or apply statement
  SetBinding* target = nullptr;
  int element = 0;
  bool reduce = false;
  SetBinding* grid = nullptr;     // `through G`
  bool results_binary32 = false;  // SiteCall::results_binary32 of the hook that ran it
  // The global results; for stencil matrices, `values` holds a placeholder and `stencil`
  // one dense block array per offset (one block per point), built into a matrix at the end.
  std::deque<Value> values;
  std::vector<bool> is_matrix;
  std::vector<Shape> blocks;
  std::deque<std::deque<Value>> stencil;
  std::vector<std::vector<int>> offsets;

  int offset_tag(const std::vector<int>& o) {
    for (size_t i = 0; i < offsets.size(); ++i)
      if (offsets[i] == o) return static_cast<int>(i);
    offsets.push_back(o);
    return static_cast<int>(offsets.size() - 1);
  }
};

}  // namespace simit::interp
