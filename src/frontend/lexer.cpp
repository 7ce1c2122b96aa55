// The lexer of LANGUAGE.md §2: comments, test lines, keywords, literals, punctuation.
#include "frontend/lexer.h"

#include <cmath>
#include <cstdlib>
#include <string>
#include <unordered_map>

namespace simit::frontend {
namespace {

bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool is_letter(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }
bool is_ident_start(char c) { return is_letter(c) || c == '_'; }
bool is_ident_char(char c) { return is_ident_start(c) || is_digit(c); }
bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

const std::unordered_map<std::string_view, TokenKind>& keyword_table() {
  static const std::unordered_map<std::string_view, TokenKind> table = {
#define SIMIT_KEYWORD_ENTRY(name, spelling) {spelling, TokenKind::name},
      SIMIT_KEYWORD_TOKENS(SIMIT_KEYWORD_ENTRY)
#undef SIMIT_KEYWORD_ENTRY
  };
  return table;
}

// A printable rendering of one source byte for "unexpected symbol" messages.
std::string describe_char(char c) {
  auto u = static_cast<unsigned char>(c);
  if (u >= 0x20 && u < 0x7f) return std::string(1, c);
  static const char* hex = "0123456789ABCDEF";
  return std::string("\\x") + hex[u >> 4] + hex[u & 15];
}

class Lexer {
 public:
  Lexer(const SourceFile& file, Diagnostics& diags)
      : file_(file), text_(file.text()), diags_(diags) {}

  std::vector<Token> run() {
    // Source text averages well over four bytes per token; reserving once avoids moving
    // every token several times as the vector grows.
    tokens_.reserve(text_.size() / 4 + 16);
    while (true) {
      skip_trivia();
      if (pos_ >= text_.size()) break;
      lex_token();
    }
    Token eof;
    eof.kind = TokenKind::EndOfFile;
    eof.span = span(static_cast<uint32_t>(text_.size()), static_cast<uint32_t>(text_.size()));
    tokens_.push_back(std::move(eof));
    return std::move(tokens_);
  }

 private:
  char peek(size_t ahead = 0) const {
    return pos_ + ahead < text_.size() ? text_[pos_ + ahead] : '\0';
  }
  SourceSpan span(uint32_t b, uint32_t e) const { return {&file_, b, e}; }
  void error(uint32_t b, uint32_t e, std::string message) {
    diags_.lexical(span(b, e), std::move(message));
  }

  Token& push(TokenKind kind, size_t begin) {
    Token t;
    t.kind = kind;
    t.span = span(static_cast<uint32_t>(begin), static_cast<uint32_t>(pos_));
    t.text = std::string_view(text_).substr(begin, pos_ - begin);
    tokens_.push_back(std::move(t));
    return tokens_.back();
  }

  // Whitespace and comments; `%!` is not trivia and stops the scan.
  void skip_trivia() {
    while (pos_ < text_.size()) {
      char c = peek();
      if (is_space(c)) {
        ++pos_;
      } else if (c == '%' && peek(1) == '!') {
        return;
      } else if (c == '%' && peek(1) == '{') {
        skip_block_comment();
      } else if (c == '%' && peek(1) == '}') {
        error(static_cast<uint32_t>(pos_), static_cast<uint32_t>(pos_ + 2),
              "'%}' without an open block comment");
        pos_ += 2;
      } else if (c == '%') {
        while (pos_ < text_.size() && text_[pos_] != '\n' && text_[pos_] != '\r') ++pos_;
      } else {
        return;
      }
    }
  }

  // `%{ ... %}`, not nesting: the first `%}` closes.
  void skip_block_comment() {
    size_t begin = pos_;
    size_t close = text_.find("%}", pos_ + 2);
    if (close == std::string::npos) {
      error(static_cast<uint32_t>(begin), static_cast<uint32_t>(begin + 2), "unclosed comment");
      pos_ = text_.size();
      return;
    }
    pos_ = close + 2;
  }

  void lex_token() {
    char c = peek();
    if (is_ident_start(c)) return lex_word();
    if (is_digit(c)) return lex_number();
    if (c == '"') return lex_string();
    lex_punct();
  }

  void lex_word() {
    size_t begin = pos_;
    while (is_ident_char(peek())) ++pos_;
    std::string_view word = std::string_view(text_).substr(begin, pos_ - begin);
    auto it = keyword_table().find(word);
    push(it == keyword_table().end() ? TokenKind::Ident : it->second, begin);
  }

  void skip_digits() {
    while (is_digit(peek())) ++pos_;
  }

  // digits | digits "." digits [exp] | digits exp; see §2.6 for the malformed cases.
  void lex_number() {
    size_t begin = pos_;
    skip_digits();
    bool is_float = false;
    if (peek() == '.') {
      if (!is_digit(peek(1))) {
        std::string digits = text_.substr(begin, pos_ - begin);
        ++pos_;
        return bad_number(begin, "unexpected symbol '.' after '" + digits +
                                     "' (a float literal needs digits after the '.')");
      }
      ++pos_;
      skip_digits();
      is_float = true;
    }
    if (peek() == 'e' || peek() == 'E') {
      ++pos_;
      if (peek() == '+' || peek() == '-') ++pos_;
      if (!is_digit(peek())) return bad_number(begin, "exponent of float literal has no digits");
      skip_digits();
      is_float = true;
    }
    if (is_float) return finish_float(begin);
    finish_int(begin);
  }

  // Reports a malformed number and skips the rest of it (letters and digits included),
  // so `1.c` gives one error and no stray identifier.
  void bad_number(size_t begin, std::string message) {
    while (is_ident_char(peek())) ++pos_;
    error(static_cast<uint32_t>(begin), static_cast<uint32_t>(pos_), std::move(message));
  }

  void finish_int(size_t begin) {
    std::string_view digits = std::string_view(text_).substr(begin, pos_ - begin);
    if (digits.size() > 1 && digits[0] == '0') {
      error(static_cast<uint32_t>(begin), static_cast<uint32_t>(pos_),
            "integer literal '" + std::string(digits) + "' has a leading zero");
      return;
    }
    long long value = 0;
    for (char d : digits) {
      value = value * 10 + (d - '0');
      if (value > 2147483647LL) {
        error(static_cast<uint32_t>(begin), static_cast<uint32_t>(pos_),
              "integer literal '" + std::string(digits) + "' is out of range");
        return;
      }
    }
    push(TokenKind::IntLiteral, begin).int_value = value;
  }

  void finish_float(size_t begin) {
    std::string digits = text_.substr(begin, pos_ - begin);
    double value = std::strtod(digits.c_str(), nullptr);
    if (std::isinf(value)) {
      error(static_cast<uint32_t>(begin), static_cast<uint32_t>(pos_),
            "float literal '" + digits + "' is out of range");
      return;
    }
    push(TokenKind::FloatLiteral, begin).float_value = value;
  }

  // The character after a backslash, decoded; false for an unknown escape.
  static bool decode_escape(char c, char& out) {
    switch (c) {
      case 'a': out = '\a'; return true;
      case 'b': out = '\b'; return true;
      case 'f': out = '\f'; return true;
      case 'n': out = '\n'; return true;
      case 'r': out = '\r'; return true;
      case 't': out = '\t'; return true;
      case 'v': out = '\v'; return true;
      case '\\': out = '\\'; return true;
      case '\'': out = '\''; return true;
      case '"': out = '"'; return true;
      case '?': out = '?'; return true;
      default: return false;
    }
  }

  // A raw line break ends an unclosed string, so the next line lexes normally.
  void lex_string() {
    size_t begin = pos_++;
    std::string value;
    bool ok = true;
    while (true) {
      char c = peek();
      if (pos_ >= text_.size() || c == '\n' || c == '\r') {
        error(static_cast<uint32_t>(begin), static_cast<uint32_t>(pos_), "unclosed string literal");
        return;
      }
      ++pos_;
      if (c == '"') break;
      if (c != '\\') {
        value += c;
        continue;
      }
      char e = peek();
      if (pos_ >= text_.size() || e == '\n' || e == '\r') continue;  // reported above
      ++pos_;
      char decoded = 0;
      if (decode_escape(e, decoded)) {
        value += decoded;
      } else {
        error(static_cast<uint32_t>(pos_ - 2), static_cast<uint32_t>(pos_),
              "unrecognized escape sequence '\\" + describe_char(e) + "'");
        ok = false;
      }
    }
    if (ok) push(TokenKind::StringLiteral, begin).string_value = std::move(value);
  }

  // Two-character tokens first (greedy), then single characters.
  void lex_punct() {
    size_t begin = pos_;
    TokenKind two = TokenKind::EndOfFile;
    switch (peek()) {
      case '-':
        if (peek(1) == '>') two = TokenKind::Arrow;
        break;
      case '.':
        if (peek(1) == '*') two = TokenKind::DotStar;
        if (peek(1) == '/') two = TokenKind::DotSlash;
        break;
      case '<':
        if (peek(1) == '=') two = TokenKind::LessEq;
        break;
      case '>':
        if (peek(1) == '=') two = TokenKind::GreaterEq;
        break;
      case '=':
        if (peek(1) == '=') two = TokenKind::EqEq;
        break;
      case '!':
        if (peek(1) == '=') two = TokenKind::NotEq;
        break;
      case '%':
        if (peek(1) == '!') two = TokenKind::Test;
        break;
      default: break;
    }
    if (two != TokenKind::EndOfFile) {
      pos_ += 2;
      push(two, begin);
      return;
    }
    TokenKind one = single_char_kind(peek());
    ++pos_;
    if (one == TokenKind::EndOfFile) {
      error(static_cast<uint32_t>(begin), static_cast<uint32_t>(pos_),
            "unexpected symbol '" + describe_char(text_[begin]) + "'");
      // Like the original, skip to the next whitespace, so `&&` is one error.
      while (pos_ < text_.size() && !is_space(text_[pos_])) ++pos_;
      return;
    }
    push(one, begin);
  }

  static TokenKind single_char_kind(char c) {
    switch (c) {
      case '(': return TokenKind::LParen;
      case ')': return TokenKind::RParen;
      case '[': return TokenKind::LBracket;
      case ']': return TokenKind::RBracket;
      case '{': return TokenKind::LBrace;
      case '}': return TokenKind::RBrace;
      case '<': return TokenKind::Less;
      case '>': return TokenKind::Greater;
      case '=': return TokenKind::Assign;
      case '+': return TokenKind::Plus;
      case '-': return TokenKind::Minus;
      case '*': return TokenKind::Star;
      case '/': return TokenKind::Slash;
      case '\\': return TokenKind::Backslash;
      case '^': return TokenKind::Caret;
      case '\'': return TokenKind::Apostrophe;
      case '.': return TokenKind::Dot;
      case ',': return TokenKind::Comma;
      case ':': return TokenKind::Colon;
      case ';': return TokenKind::Semicolon;
      default: return TokenKind::EndOfFile;  // not a token character
    }
  }

  const SourceFile& file_;
  const std::string& text_;
  Diagnostics& diags_;
  size_t pos_ = 0;
  std::vector<Token> tokens_;
};

}  // namespace

std::vector<Token> lex(const SourceFile& file, Diagnostics& diags) {
  return Lexer(file, diags).run();
}

}  // namespace simit::frontend
