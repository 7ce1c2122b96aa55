// Spellings of token kinds, derived from the X-macro lists in token.h.
#include "frontend/token.h"

namespace simit::frontend {

const char* token_spelling(TokenKind kind) {
  switch (kind) {
#define SIMIT_TOKEN_CASE(name, spelling) \
  case TokenKind::name: return spelling;
    SIMIT_KEYWORD_TOKENS(SIMIT_TOKEN_CASE)
    SIMIT_PUNCT_TOKENS(SIMIT_TOKEN_CASE)
    SIMIT_OTHER_TOKENS(SIMIT_TOKEN_CASE)
#undef SIMIT_TOKEN_CASE
  }
  return "?";
}

}  // namespace simit::frontend
