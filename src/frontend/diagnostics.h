// Collected, located user diagnostics, kept apart from internal invariant failures.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "frontend/source.h"

namespace simit::frontend {

// Top-level category of a diagnostic (TESTFORMAT.md §7.2).
enum class DiagCategory { Lexical, Syntax, Semantic };

// Finer classification of semantic diagnostics (tests/lang/README.md).
enum class SemanticKind {
  None,  // lexical/syntax diagnostics, and semantic ones of no finer kind
  Undeclared,
  Redefinition,
  Type,
  Dimension,
  NotWritable,
  LiteralRequired,
  GenericUnresolved,
  Arity,
};

struct Diagnostic {
  DiagCategory category = DiagCategory::Semantic;
  SemanticKind kind = SemanticKind::None;
  SourceSpan span;
  std::string message;
};

// Name as written in `%@ error <category>` ("lexical", "undeclared", ...).
const char* category_name(const Diagnostic& d);
// True when `%@ error <name>` accepts this diagnostic.
bool category_matches(const Diagnostic& d, const std::string& name);

// `text` with its control characters other than tab written as \xNN: source text echoed to
// a terminal must not drive it.
std::string printable(std::string_view text);

// Collects diagnostics; passes report and go on (they never throw for user errors).
class Diagnostics {
 public:
  void lexical(SourceSpan span, std::string message);
  void syntax(SourceSpan span, std::string message);
  void semantic(SemanticKind kind, SourceSpan span, std::string message);

  bool has_errors() const { return !items_.empty(); }
  size_t size() const { return items_.size(); }
  const std::vector<Diagnostic>& items() const { return items_; }

  // `file:line:col: error: message`, the source line, and a caret/underline under the span.
  static std::string render(const Diagnostic& d);
  // The same with `where` in place of `file:line:col` (a REPL input's own line numbers).
  static std::string render(const Diagnostic& d, const std::string& where);
  std::string render_all() const;

 private:
  std::vector<Diagnostic> items_;
};

// A broken invariant of the implementation itself (never a user mistake).
class InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

#define SIMIT_ASSERT(cond, msg)                                                                   \
  do {                                                                                            \
    if (!(cond))                                                                                  \
      throw ::simit::frontend::InternalError(std::string("internal error: ") + (msg) +            \
                                             " (" __FILE__ ":" + std::to_string(__LINE__) + ")"); \
  } while (0)

}  // namespace simit::frontend
