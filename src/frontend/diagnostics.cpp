// Rendering and classification of diagnostics.
#include "frontend/diagnostics.h"

#include <algorithm>

namespace simit::frontend {

const char* category_name(const Diagnostic& d) {
  switch (d.category) {
    case DiagCategory::Lexical: return "lexical";
    case DiagCategory::Syntax: return "syntax";
    case DiagCategory::Semantic: break;
  }
  switch (d.kind) {
    case SemanticKind::None: return "semantic";
    case SemanticKind::Undeclared: return "undeclared";
    case SemanticKind::Redefinition: return "redefinition";
    case SemanticKind::Type: return "type";
    case SemanticKind::Dimension: return "dimension";
    case SemanticKind::NotWritable: return "not-writable";
    case SemanticKind::LiteralRequired: return "literal-required";
    case SemanticKind::GenericUnresolved: return "generic-unresolved";
    case SemanticKind::Arity: return "arity";
  }
  return "semantic";
}

bool category_matches(const Diagnostic& d, const std::string& name) {
  if (name == category_name(d)) return true;
  return name == "semantic" && d.category == DiagCategory::Semantic;
}

void Diagnostics::lexical(SourceSpan span, std::string message) {
  items_.push_back({DiagCategory::Lexical, SemanticKind::None, span, std::move(message)});
}

void Diagnostics::syntax(SourceSpan span, std::string message) {
  items_.push_back({DiagCategory::Syntax, SemanticKind::None, span, std::move(message)});
}

void Diagnostics::semantic(SemanticKind kind, SourceSpan span, std::string message) {
  items_.push_back({DiagCategory::Semantic, kind, span, std::move(message)});
}

std::string Diagnostics::render(const Diagnostic& d) {
  if (!d.span.valid()) return "error: " + d.message + "\n";
  LineCol lc = d.span.start();
  std::string out = d.span.file->name() + ":" + std::to_string(lc.line) + ":" +
                    std::to_string(lc.column) + ": error: " + d.message + "\n";
  std::string_view line = d.span.file->line_text(lc.line);
  out += "  ";
  out += line;
  out += "\n  ";
  // Tabs are kept so the caret lines up under the same columns as the source.
  for (int i = 0; i + 1 < lc.column && i < static_cast<int>(line.size()); ++i)
    out += line[i] == '\t' ? '\t' : ' ';
  size_t first = static_cast<size_t>(lc.column - 1);
  size_t width = d.span.end > d.span.begin ? d.span.end - d.span.begin : 1;
  width = std::max<size_t>(1, std::min(width, line.size() > first ? line.size() - first : 1));
  out += '^';
  out += std::string(width - 1, '~');
  out += "\n";
  return out;
}

std::string Diagnostics::render_all() const {
  std::string out;
  for (const auto& d : items_) out += render(d);
  return out;
}

}  // namespace simit::frontend
