// Where the lines of a compiled source come from. The REPL compiles its loaded files and the
// declarations typed at the prompt as one text; the debugger shows and takes real file names
// and lines. A single file is the one-segment map {1, "fem.sim", 1}.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace simit::repl {

// Compiled lines from `first_line` on (until the next segment) are the lines of `file` from
// `file_first_line` on.
struct LineSegment {
  int first_line = 1;
  std::string file;
  int file_first_line = 1;
};

class LineMap {
 public:
  LineMap() = default;
  explicit LineMap(std::vector<LineSegment> segments);  // any order

  bool empty() const { return segments_.empty(); }
  struct Place {
    std::string file;
    int line = 0;
  };
  // The file line of a compiled line (before the first segment: line 0 of the first file).
  Place place(int compiled_line) const;
  // The compiled line of `line` of `file`, which matches a segment's file by its full name or
  // by its base name ("fem.sim" for "examples/fem/fem.sim"); null when no segment holds it.
  std::optional<int> compiled_line(const std::string& file, int line) const;
  // The file `break LINE` and `list LINE` mean when no program point is selected.
  const std::string& default_file() const;

 private:
  std::vector<LineSegment> segments_;  // by first_line
};

}  // namespace simit::repl
