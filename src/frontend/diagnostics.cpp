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

namespace {

bool is_control(unsigned char c) { return (c < 0x20 && c != '\t') || c == 0x7f; }

// The columns `text` takes on a terminal once printable: a UTF-8 continuation byte takes
// none, an escaped control character four; tabs are kept so that the caret line keeps them.
std::string blanks_under(std::string_view text) {
  std::string out;
  for (char ch : text) {
    auto c = static_cast<unsigned char>(ch);
    if (ch == '\t')
      out += '\t';
    else if (is_control(c))
      out += "    ";
    else if ((c & 0xC0) != 0x80)
      out += ' ';
  }
  return out;
}

size_t columns(std::string_view text) {
  std::string b = blanks_under(text);
  return std::max<size_t>(1, b.size());
}

}  // namespace

std::string printable(std::string_view text) {
  static const char* const kHex = "0123456789abcdef";
  std::string out;
  out.reserve(text.size());
  for (char ch : text) {
    auto c = static_cast<unsigned char>(ch);
    if (!is_control(c)) {
      out += ch;
      continue;
    }
    out += "\\x";
    out += kHex[c >> 4];
    out += kHex[c & 15];
  }
  return out;
}

std::string Diagnostics::render(const Diagnostic& d) {
  if (!d.span.valid()) return "error: " + printable(d.message) + "\n";
  LineCol lc = d.span.start();
  return render(
      d, d.span.file->name() + ":" + std::to_string(lc.line) + ":" + std::to_string(lc.column));
}

std::string Diagnostics::render(const Diagnostic& d, const std::string& where) {
  if (!d.span.valid()) return printable(where) + ": error: " + printable(d.message) + "\n";
  LineCol lc = d.span.start();
  std::string out = printable(where) + ": error: " + printable(d.message) + "\n";
  std::string_view line = d.span.file->line_text(lc.line);
  size_t first = std::min(static_cast<size_t>(lc.column - 1), line.size());
  size_t width = d.span.end > d.span.begin ? d.span.end - d.span.begin : 1;
  width = std::max<size_t>(1, std::min(width, line.size() > first ? line.size() - first : 1));
  out += "  " + printable(line) + "\n  " + blanks_under(line.substr(0, first)) + '^';
  out += std::string(columns(line.substr(first, width)) - 1, '~');
  out += "\n";
  return out;
}

std::string Diagnostics::render_all() const {
  std::string out;
  for (const auto& d : items_) out += render(d);
  return out;
}

}  // namespace simit::frontend
