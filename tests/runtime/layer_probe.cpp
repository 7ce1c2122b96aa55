// Must not compile: the runtime layer depends on nothing of ours, so what links simit_runtime
// sees its own headers and not the interpreter's. Built only by layers_runtime_refuse_interp.
// The order is the test: the first header compiles, the second is not found.
// clang-format off
#include "runtime/set.h"
#include "interp/value.h"
// clang-format on

int probe() { return 0; }
