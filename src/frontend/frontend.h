// The frontend pipeline: lex, parse and check one source text.
#pragma once

#include <memory>
#include <string>

#include "frontend/ast.h"
#include "frontend/diagnostics.h"
#include "frontend/source.h"

namespace simit::frontend {

// Owns everything a compiled text needs: the source (spans point into it), the tree
// and the diagnostics. `program` is complete and typed exactly when ok().
struct Compilation {
  std::unique_ptr<SourceFile> source;
  std::unique_ptr<ast::Program> program;
  Diagnostics diagnostics;
  bool ok() const { return program && !diagnostics.has_errors(); }
};

struct CompileOptions {
  bool check = true;  // false: stop after parsing (for --dump=ast and round trips)
};

// Lexes, parses and (when there are no lexical or syntax errors) checks `text`.
std::unique_ptr<Compilation> compile_source(std::string name, std::string text,
                                            const CompileOptions& options = {});
// The same for a file on disk; an unreadable file gives one diagnostic naming it.
std::unique_ptr<Compilation> compile_file(const std::string& path,
                                          const CompileOptions& options = {});

}  // namespace simit::frontend
