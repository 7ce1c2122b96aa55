// Record-by-record reading of text mesh files with line numbers for error messages.
#include "runtime/mesh/line_reader.h"

#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "runtime/mesh/mesh.h"

namespace simit::runtime {

namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// Echoes a token in an error message without flooding the terminal or printing binary bytes.
std::string quote(std::string_view token) {
  std::string out = "'";
  for (size_t i = 0; i < token.size() && i < 40; ++i) {
    unsigned char c = static_cast<unsigned char>(token[i]);
    out += (c >= 32 && c < 127) ? static_cast<char>(c) : '?';
  }
  if (token.size() > 40) out += "...";
  return out + "'";
}

// from_chars rejects a leading '+', which hand-written files sometimes use.
std::string_view strip_plus(std::string_view s) {
  return (s.size() > 1 && s[0] == '+' && s[1] != '-') ? s.substr(1) : s;
}

std::string read_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw MeshError(path, 0, "expected a mesh file, found a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MeshError(path, 0, std::string("cannot open file: ") + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw MeshError(path, 0, "cannot read file");
  return std::move(text).str();
}

}  // namespace

LineReader::LineReader(std::string path, char comment)
    : path_(std::move(path)), text_(read_file(path_)), comment_(comment) {}

bool LineReader::next() {
  tokens_.clear();
  while (pos_ < text_.size()) {
    size_t eol = text_.find('\n', pos_);
    if (eol == std::string::npos) eol = text_.size();
    std::string_view line(text_.data() + pos_, eol - pos_);
    pos_ = eol + 1;
    ++line_;
    if (comment_ != '\0') line = line.substr(0, line.find(comment_));
    size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && is_space(line[i])) ++i;
      size_t start = i;
      while (i < line.size() && !is_space(line[i])) ++i;
      if (i > start) tokens_.push_back(line.substr(start, i - start));
    }
    if (!tokens_.empty()) return true;
  }
  line_ += 1;
  pos_ = text_.size();
  return false;
}

void LineReader::rewind() {
  pos_ = 0;
  line_ = 0;
  tokens_.clear();
}

void LineReader::require_next(std::string_view what) {
  if (!next()) fail("expected " + std::string(what) + ", found end of file");
}

long long LineReader::integer(size_t i, std::string_view what) const {
  if (i >= tokens_.size()) fail_token(i, what);
  std::string_view s = strip_plus(tokens_[i]);
  long long value = 0;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || end != s.data() + s.size()) fail_token(i, what);
  return value;
}

int LineReader::count(size_t i, std::string_view what) const {
  long long value = integer(i, what);
  if (value < 0 || value > INT_MAX) fail_token(i, what);
  return static_cast<int>(value);
}

double LineReader::number(size_t i, std::string_view what) const {
  if (i >= tokens_.size()) fail_token(i, what);
  std::string_view s = strip_plus(tokens_[i]);
  double value = 0;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(value))
    fail_token(i, std::string(what) + " (a finite number)");
  return value;
}

void LineReader::expect_end(size_t n, std::string_view what) const {
  if (tokens_.size() > n)
    fail("expected end of line after " + std::string(what) + ", got " + quote(tokens_[n]));
  if (tokens_.size() < n) fail_token(tokens_.size(), what);
}

void LineReader::fail(const std::string& message) const { throw MeshError(path_, line_, message); }

void LineReader::fail_token(size_t i, std::string_view what) const {
  std::string found = i < tokens_.size() ? "got " + quote(tokens_[i]) : "found end of line";
  fail("expected " + std::string(what) + ", " + found);
}

}  // namespace simit::runtime
