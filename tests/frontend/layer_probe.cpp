// Must not compile: the frontend layer depends on nothing of ours, so what links
// simit_frontend sees its own headers and not the runtime's. Built only by
// layers_frontend_refuse_runtime.
#include "frontend/ast.h"
#include "runtime/set.h"

int probe() { return 0; }
