// Read-only views of a paused interpreter for the step debugger: its active calls and, for a
// call that a `map` or `apply` made, the element it serves and that element's endpoints.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "frontend/ast.h"
#include "runtime/set.h"

namespace simit::interp {

// The map or apply a mapped call serves.
struct MapView {
  const frontend::ast::Assembly* assembly = nullptr;  // callee and target set variable
  frontend::SourceSpan at;                            // the map expression / apply statement
  bool is_apply = false;                              // the mapped function has no results
  const runtime::Set* set = nullptr;                  // the target set
  int element = -1;
  struct Endpoint {
    const frontend::ast::Variable* set_var = nullptr;  // from the target set's type; may be null
    const runtime::Set* set = nullptr;
    int index = -1;
  };
  std::vector<Endpoint> endpoints;  // of `element`, in order (none for vertex sets)
};

// One active call.
struct FrameView {
  const frontend::ast::FuncDecl* func = nullptr;
  int depth = 0;  // call depth as hooks see it: 0 for the entry call
  // The call, map or apply that made this frame (invalid for the entry call).
  frontend::SourceSpan call_site;
  // Where a frame that is not the innermost is executing: the call it is making (the next
  // frame's call_site). Invalid for the innermost, whose statement the hook reports.
  frontend::SourceSpan position;
  // Distinct for every call and every mapped element: tells successive activations of one
  // function at one depth apart.
  uint64_t activation = 0;
  std::optional<MapView> map;
};

}  // namespace simit::interp
