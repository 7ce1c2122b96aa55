// Must not compile: a front end's libraries (tools/, repl/) see the public headers, and a
// private header of src/ is not found. Built only by the layers_*_refuse_private_headers tests.
// The order is the test: the first header compiles, the second is not found.
// clang-format off
#include "simit/simit.h"
#include "frontend/ast.h"
// clang-format on

int probe() { return 0; }
