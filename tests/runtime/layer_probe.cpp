// Must not compile: the runtime layer depends on nothing of ours, so what links simit_runtime
// sees its own headers and not the interpreter's. Built only by layers_runtime_refuse_interp.
#include "runtime/set.h"
#include "interp/value.h"

int probe() { return 0; }
