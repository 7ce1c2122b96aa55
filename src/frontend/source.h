// Source files and the spans that tie every token, node and diagnostic to a place in them.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace simit::frontend {

struct LineCol {
  int line = 1;    // 1-based
  int column = 1;  // 1-based, in bytes
};

// One loaded text. Owns its bytes; spans point into it, so it must outlive them.
class SourceFile {
 public:
  SourceFile(std::string name, std::string text);

  const std::string& name() const { return name_; }
  const std::string& text() const { return text_; }
  // Line and column of a byte offset; "\r\n" counts as one line break.
  LineCol locate(uint32_t offset) const;
  // The text of a 1-based line, without its line break.
  std::string_view line_text(int line) const;
  int line_count() const { return static_cast<int>(line_starts_.size()); }

 private:
  std::string name_;
  std::string text_;
  std::vector<uint32_t> line_starts_;
};

// A half-open byte range [begin, end) of one source file.
struct SourceSpan {
  const SourceFile* file = nullptr;
  uint32_t begin = 0;
  uint32_t end = 0;

  bool valid() const { return file != nullptr; }
  LineCol start() const { return file ? file->locate(begin) : LineCol{}; }
  // The smallest span covering both (both must be in the same file).
  static SourceSpan cover(const SourceSpan& a, const SourceSpan& b);
};

}  // namespace simit::frontend
