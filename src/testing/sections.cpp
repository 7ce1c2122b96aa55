// Splitting a test file into sections at `%%%` (TESTFORMAT.md §2).
#include "sections.h"

namespace simit::tools {
namespace {

constexpr std::string_view kDelimiter = "%%%";

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

// The rest of the section's first line after the delimiter.
std::string_view header_of(std::string_view section) {
  std::string_view rest = section.substr(kDelimiter.size());
  size_t eol = rest.find_first_of("\r\n");
  return eol == std::string_view::npos ? rest : rest.substr(0, eol);
}

// 1-based column of `offset`: bytes since the last line break before it, plus one.
int column_of(std::string_view text, size_t offset) {
  size_t last_break = text.substr(0, offset).find_last_of("\r\n");
  return static_cast<int>(last_break == std::string_view::npos ? offset + 1 : offset - last_break);
}

Section make_section(std::string_view text, size_t begin, size_t end, int line) {
  std::string_view body = text.substr(begin, end - begin);
  std::string_view header = header_of(body);
  Section s;
  s.source = std::string(body);
  s.line = line;
  s.column = column_of(text, begin);
  s.disabled = !header.empty() && header.front() == '-';
  s.name = std::string(trim(header));
  return s;
}

}  // namespace

int count_line_breaks(std::string_view text) {
  int breaks = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++breaks;
    } else if (text[i] == '\r') {
      if (i + 1 < text.size() && text[i + 1] == '\n') ++i;
      ++breaks;
    }
  }
  return breaks;
}

std::vector<Section> split_sections(std::string_view text) {
  std::vector<Section> sections;
  if (text.substr(0, kDelimiter.size()) != kDelimiter) {
    Section whole;
    whole.source = std::string(text);
    whole.sectioned = false;
    sections.push_back(std::move(whole));
    return sections;
  }
  int line = 1;
  size_t begin = 0;
  while (begin < text.size()) {
    size_t next = text.find(kDelimiter, begin + kDelimiter.size());
    size_t end = next == std::string_view::npos ? text.size() : next;
    // A delimiter directly followed by another (`%%%%%%`) is not a section.
    if (end - begin > kDelimiter.size()) sections.push_back(make_section(text, begin, end, line));
    line += count_line_breaks(text.substr(begin, end - begin));
    begin = end;
  }
  return sections;
}

}  // namespace simit::tools
