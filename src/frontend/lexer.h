// The lexer of LANGUAGE.md §2: source text to tokens, reporting lexical errors.
#pragma once

#include <vector>

#include "frontend/diagnostics.h"
#include "frontend/token.h"

namespace simit::frontend {

// Tokens of the whole file, always ending with EndOfFile. Comments are dropped; `%!`
// becomes a Test token. After a lexical error it reports and goes on.
std::vector<Token> lex(const SourceFile& file, Diagnostics& diags);

}  // namespace simit::frontend
