// Splitting a test file into sections at `%%%` (TESTFORMAT.md §2).
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace simit::tools {

// One section of a test file. `source` is the section's whole text, header line included.
struct Section {
  std::string name;       // header without surrounding whitespace (may be empty)
  std::string source;     // compiled on its own
  int line = 1;           // 1-based line of the file at which the section starts
  int column = 1;         // 1-based column of that line (sections may start mid-line)
  bool disabled = false;  // header starts with `-` (`%%%-name`)
  bool sectioned = true;  // false: the file does not begin with `%%%` and is one section
};

// Splits `text` at every occurrence of `%%%`; a file that does not begin with `%%%`
// is one unnamed section. Sections with nothing after the delimiter are dropped.
std::vector<Section> split_sections(std::string_view text);

// Number of line breaks in `text`; "\r\n" and a lone '\r' count as one each, as in
// the frontend's line table.
int count_line_breaks(std::string_view text);

}  // namespace simit::tools
