// Settings of one interpreter run, passed down explicitly (there is no global state).
#pragma once

#include <ostream>

namespace simit::interp {

class Distribution;
class SiteHook;
class StatementHook;
class Trap;

struct Options {
  // Round every float to binary32 when it is produced (the program's float type is float32).
  bool float32 = false;
  // Stop with a run-time error at the first operation that produces a NaN or an infinity.
  bool check_finite = false;
  // Where `print` and `println` write; null means standard output.
  std::ostream* out = nullptr;
  // Called around every statement for the interpreter's whole life (hot counters, tests);
  // null when unused. Ignored when `trap` is set.
  StatementHook* hook = nullptr;
  // A host-owned switch of the trap point (interp/hook.h): the debugger installs and removes
  // its hook there while a run goes on, and Ctrl-C requests an interrupt through it.
  Trap* trap = nullptr;
  // The executor seam (interp/assembly_plan.h): offered every planned map / apply site;
  // null runs everything in the interpreter.
  SiteHook* sites = nullptr;
  // A distributed run's seam (interp/distribution.h): reductions over a set add the ranks'
  // owned parts and partial results refresh their ghosts; null in a run of one process.
  const Distribution* distribution = nullptr;
  // Whether the host reads what a call leaves only through the runtime's accessors (a scene
  // run writing its own output), which bring an array an executor keeps newer back when it is
  // read: those arrays then stay there across calls. False brings them all home at the end of
  // every entry call, for hosts that keep pointers of their own (runtime/residency.h).
  bool host_uses_accessors = false;
};

}  // namespace simit::interp
