// Reads a text mesh file one record (a line with at least one token) at a time and turns every
// problem into a MeshError "file:line: expected ...", so readers never index past a record.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace simit::runtime {

class LineReader {
 public:
  // `comment` starts a comment running to the end of the line; '\0' for formats without one.
  // Throws MeshError when the file cannot be read.
  LineReader(std::string path, char comment);

  // Advances to the next record; false at end of file.
  bool next();
  // Like next(), but end of file is an error: "expected WHAT, found end of file".
  void require_next(std::string_view what);

  // Starts again from the first line, for formats that need two passes.
  void rewind();

  const std::string& path() const { return path_; }
  const std::string& text() const { return text_; }
  int line() const { return line_; }  // at end of file, one past the last line
  size_t size() const { return tokens_.size(); }
  std::string_view operator[](size_t i) const { return tokens_[i]; }

  // Token i as a value; a missing or malformed token fails with "expected WHAT".
  long long integer(size_t i, std::string_view what) const;
  int count(size_t i, std::string_view what) const;      // in [0, INT_MAX]
  double number(size_t i, std::string_view what) const;  // finite

  // Fails unless the record has exactly n tokens; `what` names what the record holds.
  void expect_end(size_t n, std::string_view what) const;

  [[noreturn]] void fail(const std::string& message) const;
  [[noreturn]] void fail_token(size_t i, std::string_view what) const;

 private:
  std::string path_;
  std::string text_;
  char comment_;
  size_t pos_ = 0;
  int line_ = 0;
  std::vector<std::string_view> tokens_;
};

}  // namespace simit::runtime
