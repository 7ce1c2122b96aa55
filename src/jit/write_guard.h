// Which inputs decide the blocks a map's matrix writes touch, and the guard that tells a
// specialised pattern whether they changed since the blocks were recorded.
//
// A trace's matrix writes sit under conditions (`if not v(j).pinned`). The blocks a call
// writes are a function of the target's topology and of what those conditions read: the
// fields and scalar arguments they depend on, through locals and enclosing conditions. While
// none of these has changed, the blocks recorded on one call are the blocks of the next
// (jit/specialise.h), and the guard is one compare per such field (its write version) and per
// such scalar (its bits) per call.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "jit/loop_ir.h"
#include "runtime/set.h"
#include "runtime/system_matrix.h"

namespace simit::jit {

struct WriteDeciders {
  std::vector<int> fields;   // array slots (fields) the conditions read
  std::vector<int> scalars;  // scalar slots they read
  std::string unguardable;   // why no guard can be built, or ""
};

// The inputs that decide which blocks of matrix results `t` writes.
WriteDeciders write_deciders(const Trace& t);

class WriteGuard {
 public:
  // Remembers the deciding inputs as they are now (before a call that records its blocks).
  void record(const WriteDeciders& d, const Trace& t, const runtime::Set& target,
              const std::vector<double>& scalars);
  // Whether every deciding input is as recorded.
  bool holds(const WriteDeciders& d, const Trace& t, const runtime::Set& target,
             const std::vector<double>& scalars) const;

 private:
  std::vector<uint64_t> versions_, bits_;
};

}  // namespace simit::jit
