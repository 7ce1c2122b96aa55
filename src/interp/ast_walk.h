// The frontend's child walk, under the name the interpreter's analyses use.
#pragma once

#include "frontend/ast_walk.h"

namespace simit::interp {
using frontend::ast::for_each_child;
}  // namespace simit::interp
