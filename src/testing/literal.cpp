// Literal values written in `%@` directives (LANGUAGE.md §2.6, §3.4, §6.2).
#include "literal.h"

#include <cctype>
#include <climits>
#include <cstdlib>
#include <stdexcept>

namespace simit::tools {
namespace {

using frontend::ScalarKind;

// A literal syntax error; caught at the entry point and turned into a message.
struct LiteralError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Recursive-descent reader over one literal's text.
class Reader {
 public:
  explicit Reader(std::string_view text) : text_(text) {}

  // literal = { "+" | "-" } body { "'" }
  Literal literal() {
    bool negate = false;
    int signs = 0;
    for (skip_space(); peek() == '+' || peek() == '-'; skip_space()) {
      negate ^= get() == '-';
      ++signs;
    }
    Literal lit = body();
    if (signs > 0 && (lit.kind == ScalarKind::Bool || lit.kind == ScalarKind::String))
      fail(std::string("a sign cannot be applied to a ") + frontend::to_string(lit.kind) +
           " literal");
    if (negate) negate_all(lit);
    for (skip_space(); peek() == '\''; skip_space()) {
      ++pos_;
      transpose(lit);
    }
    if (!at_end()) fail("unexpected '" + std::string(1, peek()) + "' after the literal");
    return lit;
  }

 private:
  // body = INT | FLOAT | STRING | "true" | "false" | complex_literal | dense_literal
  Literal body() {
    skip_space();
    char c = peek();
    if (c == '[') return dense();
    if (c == '<') return scalar_complex();
    if (c == '"') return string_literal();
    if (std::isdigit(static_cast<unsigned char>(c))) return number();
    if (std::isalpha(static_cast<unsigned char>(c))) return word();
    fail(at_end() ? "missing value" : "unexpected '" + std::string(1, c) + "'");
  }

  Literal word() {
    size_t start = pos_;
    while (std::isalnum(static_cast<unsigned char>(peek())) || peek() == '_') ++pos_;
    std::string_view w = text_.substr(start, pos_ - start);
    if (w != "true" && w != "false") fail("'" + std::string(w) + "' is not a literal");
    Literal lit;
    lit.kind = ScalarKind::Bool;
    lit.ints.push_back(w == "true");
    return lit;
  }

  Literal number() {
    Literal lit;
    append_number(lit);
    return lit;
  }

  Literal scalar_complex() {
    Literal lit;
    lit.kind = ScalarKind::Complex;
    lit.complexes.push_back(complex_value());
    return lit;
  }

  // complex_literal = "<" signed_float "," signed_float ">"
  std::complex<double> complex_value() {
    expect('<');
    double re = signed_float();
    expect(',');
    double im = signed_float();
    expect('>');
    return {re, im};
  }

  double signed_float() {
    skip_space();
    bool negative = peek() == '-';
    if (peek() == '+' || peek() == '-') ++pos_;
    skip_space();
    Literal part;
    append_number(part);
    if (part.kind != ScalarKind::Float) fail("the parts of a complex literal must be floats");
    return negative ? -part.floats[0] : part.floats[0];
  }

  // INT = digits (not followed by '.', 'e', 'E'); FLOAT = digits "." digits [exp] | digits exp
  void append_number(Literal& lit) {
    size_t start = pos_;
    bool is_float = false;
    digits("a digit");
    if (peek() == '.') {
      ++pos_;
      digits("a digit after '.'");
      is_float = true;
    }
    if (peek() == 'e' || peek() == 'E') {
      ++pos_;
      if (peek() == '+' || peek() == '-') ++pos_;
      digits("a digit in the exponent");
      is_float = true;
    }
    std::string token(text_.substr(start, pos_ - start));
    if (is_float) {
      lit.kind = ScalarKind::Float;
      lit.floats.push_back(std::strtod(token.c_str(), nullptr));
      return;
    }
    if (token.size() > 10 || std::strtoll(token.c_str(), nullptr, 10) > INT_MAX)
      fail("integer literal " + token + " is out of range");
    lit.kind = ScalarKind::Int;
    lit.ints.push_back(std::strtoll(token.c_str(), nullptr, 10));
  }

  void digits(const char* what) {
    if (!std::isdigit(static_cast<unsigned char>(peek()))) fail(std::string("expected ") + what);
    while (std::isdigit(static_cast<unsigned char>(peek()))) ++pos_;
  }

  Literal string_literal() {
    Literal lit;
    lit.kind = ScalarKind::String;
    expect('"');
    while (!at_end() && peek() != '"') {
      char c = get();
      lit.string_value += c == '\\' ? escape() : c;
    }
    if (at_end()) fail("unclosed string literal");
    ++pos_;
    return lit;
  }

  char escape() {
    if (at_end()) fail("unclosed string literal");
    switch (char c = get()) {
      case 'a': return '\a';
      case 'b': return '\b';
      case 'f': return '\f';
      case 'n': return '\n';
      case 'r': return '\r';
      case 't': return '\t';
      case 'v': return '\v';
      case '\\':
      case '\'':
      case '"':
      case '?': return c;
      default: fail("unrecognized escape sequence '\\" + std::string(1, c) + "'");
    }
  }

  // dense_literal = "[" ( dense_literal { [","] dense_literal } | dense_rows ) "]"
  Literal dense() {
    expect('[');
    if (++depth_ > kMaxLiteralDepth)
      fail("a dense literal is nested more than " + std::to_string(kMaxLiteralDepth) +
           " levels deep");
    skip_space();
    Literal lit = peek() == '[' ? nested() : rows();
    expect(']');
    --depth_;
    return lit;
  }

  Literal nested() {
    Literal lit = dense();
    int count = 1;
    for (skip_space(); peek() != ']' && !at_end(); skip_space()) {
      if (peek() == ',') ++pos_;
      Literal next = dense();
      if (next.kind != lit.kind) fail("mismatched element types in a dense literal");
      if (next.shape != lit.shape) fail("mismatched dimension sizes in a dense literal");
      append_components(lit, next);
      ++count;
    }
    lit.shape.insert(lit.shape.begin(), count);
    return lit;
  }

  // dense_rows = dense_row { ";" dense_row }
  Literal rows() {
    Literal lit;
    int row_count = 0;
    int row_length = -1;
    while (true) {
      int length = row(lit, row_count == 0);
      if (row_length >= 0 && length != row_length)
        fail("mismatched dimension sizes in a dense literal");
      row_length = length;
      ++row_count;
      skip_space();
      if (peek() != ';') break;
      ++pos_;
    }
    lit.shape =
        row_count == 1 ? std::vector<int>{row_length} : std::vector<int>{row_count, row_length};
    return lit;
  }

  // dense_row = number { [","] number }, all of one kind; returns the row's length
  int row(Literal& lit, bool first_row) {
    int length = 0;
    for (skip_space(); peek() != ';' && peek() != ']' && !at_end(); skip_space()) {
      if (length > 0 && peek() == ',') ++pos_;
      Literal element = row_element();
      if (first_row && length == 0) lit.kind = element.kind;
      if (element.kind != lit.kind)
        fail(first_row && length > 0 ? "mixed element types in a dense literal row"
                                     : "mismatched element types in a dense literal");
      append_components(lit, element);
      ++length;
    }
    if (length == 0) fail("empty row in a dense literal");
    return length;
  }

  // signed_int | signed_float | complex_literal
  Literal row_element() {
    skip_space();
    if (peek() == '<') return scalar_complex();
    bool negative = peek() == '-';
    if (peek() == '+' || peek() == '-') ++pos_;
    skip_space();
    Literal element = number();
    if (negative) negate_all(element);
    return element;
  }

  static void append_components(Literal& to, const Literal& from) {
    to.ints.insert(to.ints.end(), from.ints.begin(), from.ints.end());
    to.floats.insert(to.floats.end(), from.floats.begin(), from.floats.end());
    to.complexes.insert(to.complexes.end(), from.complexes.begin(), from.complexes.end());
  }

  static void negate_all(Literal& lit) {
    for (auto& v : lit.ints) v = -v;
    for (auto& v : lit.floats) v = -v;
    for (auto& v : lit.complexes) v = -v;
  }

  void transpose(Literal& lit) {
    if (lit.shape.size() > 1) fail("a transposed matrix literal is not a literal");
    if (lit.shape.size() == 1) lit.column = !lit.column;
  }

  void expect(char c) {
    skip_space();
    if (peek() != c) {
      fail(std::string("expected '") + c + "'" +
           (at_end() ? " at the end" : std::string(" before '") + peek() + "'"));
    }
    ++pos_;
  }

  void skip_space() {
    while (!at_end() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }
  bool at_end() const { return pos_ >= text_.size(); }
  char peek() const { return at_end() ? '\0' : text_[pos_]; }
  char get() { return text_[pos_++]; }
  [[noreturn]] void fail(const std::string& message) const { throw LiteralError(message); }

  std::string_view text_;
  size_t pos_ = 0;
  int depth_ = 0;  // open '['
};

// A literal quoted in a message: a long one by its start only.
std::string clipped(std::string_view text) {
  constexpr size_t kShown = 60;
  return text.size() <= kShown ? std::string(text) : std::string(text.substr(0, kShown)) + "...";
}

}  // namespace

size_t Literal::size() const {
  size_t n = 1;
  for (int d : shape) n *= static_cast<size_t>(d);
  return n;
}

LiteralResult parse_literal(std::string_view text) {
  try {
    Literal lit = Reader(text).literal();
    lit.text = std::string(text);
    return {std::move(lit), ""};
  } catch (const LiteralError& e) {
    return {std::nullopt, "bad literal '" + clipped(text) + "': " + e.what()};
  }
}

std::vector<std::string> split_top_level(std::string_view text, char separator) {
  std::vector<std::string> parts;
  int depth = 0;
  bool in_string = false;
  std::string current;
  for (size_t i = 0; i < text.size(); ++i) {
    char c = text[i];
    if (in_string) {
      if (c == '\\' && i + 1 < text.size()) {
        current += c;
        c = text[++i];
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '(' || c == '<') {
      ++depth;
    } else if ((c == ']' || c == ')' || c == '>') && depth > 0) {
      --depth;
    } else if (c == separator && depth == 0) {
      parts.push_back(current);
      current.clear();
      continue;
    }
    current += c;
  }
  parts.push_back(current);
  for (auto& p : parts) {
    size_t b = p.find_first_not_of(" \t\r\n\v\f");
    size_t e = p.find_last_not_of(" \t\r\n\v\f");
    p = b == std::string::npos ? "" : p.substr(b, e - b + 1);
  }
  if (parts.size() == 1 && parts[0].empty()) parts.clear();
  return parts;
}

}  // namespace simit::tools
