// Token kinds (one X-macro list) and the token value the lexer produces.
#pragma once

#include <string_view>
#include <vector>

#include "frontend/source.h"

namespace simit::frontend {

// X(name, spelling): keywords, then punctuation; the others have no fixed spelling.
// The entry lists are laid out by hand.
// clang-format off
#define SIMIT_KEYWORD_TOKENS(X)                                                       \
  X(KwInt, "int") X(KwFloat, "float") X(KwBool, "bool") X(KwComplex, "complex")       \
  X(KwString, "string") X(KwTensor, "tensor") X(KwMatrix, "matrix")                   \
  X(KwVector, "vector") X(KwElement, "element") X(KwSet, "set") X(KwGrid, "grid")     \
  X(KwOpaque, "opaque") X(KwVar, "var") X(KwConst, "const") X(KwExtern, "extern")     \
  X(KwExport, "export") X(KwFunc, "func") X(KwInout, "inout") X(KwIvar, "ivar")       \
  X(KwMap, "map") X(KwTo, "to") X(KwReduce, "reduce") X(KwThrough, "through")         \
  X(KwApply, "apply") X(KwIf, "if") X(KwElif, "elif") X(KwElse, "else")               \
  X(KwWhile, "while") X(KwDo, "do") X(KwFor, "for") X(KwIn, "in") X(KwEnd, "end")     \
  X(KwPrint, "print") X(KwPrintln, "println") X(KwError, "error")                     \
  X(KwAnd, "and") X(KwOr, "or") X(KwNot, "not") X(KwXor, "xor") X(KwTrue, "true")     \
  X(KwFalse, "false")                                                                 \
  X(KwWith, "with") X(KwReturn, "return") X(KwNew, "new") X(KwDelete, "delete")

#define SIMIT_PUNCT_TOKENS(X)                                                         \
  X(LParen, "(") X(RParen, ")") X(LBracket, "[") X(RBracket, "]") X(LBrace, "{")      \
  X(RBrace, "}") X(Less, "<") X(Greater, ">") X(LessEq, "<=") X(GreaterEq, ">=")      \
  X(EqEq, "==") X(NotEq, "!=") X(Assign, "=") X(Plus, "+") X(Minus, "-") X(Star, "*") \
  X(Slash, "/") X(Backslash, "\\") X(DotStar, ".*") X(DotSlash, "./") X(Caret, "^")   \
  X(Apostrophe, "'") X(Dot, ".") X(Comma, ",") X(Colon, ":") X(Semicolon, ";")        \
  X(Arrow, "->") X(Test, "%!")

#define SIMIT_OTHER_TOKENS(X)                                                         \
  X(Ident, "identifier") X(IntLiteral, "integer literal")                             \
  X(FloatLiteral, "float literal") X(StringLiteral, "string literal")                 \
  X(EndOfFile, "end of file")
// clang-format on

enum class TokenKind {
#define SIMIT_TOKEN_ENUM(name, spelling) name,
  SIMIT_KEYWORD_TOKENS(SIMIT_TOKEN_ENUM) SIMIT_PUNCT_TOKENS(SIMIT_TOKEN_ENUM)
      SIMIT_OTHER_TOKENS(SIMIT_TOKEN_ENUM)
#undef SIMIT_TOKEN_ENUM
};

// The fixed spelling of a keyword or punctuation token, or a description of the others.
const char* token_spelling(TokenKind kind);

struct Token {
  TokenKind kind = TokenKind::EndOfFile;
  SourceSpan span;
  std::string_view text;  // the raw characters, pointing into the source file
  // Decoded value of literals: string contents without quotes and with escapes applied.
  std::string string_value;
  long long int_value = 0;  // IntLiteral (range-checked by the lexer)
  double float_value = 0;   // FloatLiteral
};

}  // namespace simit::frontend
