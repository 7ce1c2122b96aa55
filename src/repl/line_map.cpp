// Line maps of concatenated sources.
#include "line_map.h"

#include <algorithm>

namespace simit::repl {

namespace {

std::string base_name(const std::string& path) {
  size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

}  // namespace

LineMap::LineMap(std::vector<LineSegment> segments) : segments_(std::move(segments)) {
  std::sort(segments_.begin(), segments_.end(),
            [](const LineSegment& a, const LineSegment& b) { return a.first_line < b.first_line; });
}

LineMap::Place LineMap::place(int compiled_line) const {
  if (segments_.empty()) return {"", compiled_line};
  const LineSegment* seg = &segments_.front();
  for (const LineSegment& s : segments_)
    if (s.first_line <= compiled_line) seg = &s;
  if (compiled_line < seg->first_line) return {seg->file, 0};
  return {seg->file, seg->file_first_line + compiled_line - seg->first_line};
}

std::optional<int> LineMap::compiled_line(const std::string& file, int line) const {
  for (size_t i = 0; i < segments_.size(); ++i) {
    const LineSegment& s = segments_[i];
    if (s.file != file && base_name(s.file) != base_name(file)) continue;
    if (line < s.file_first_line) continue;
    int compiled = s.first_line + line - s.file_first_line;
    if (i + 1 < segments_.size() && compiled >= segments_[i + 1].first_line) continue;
    return compiled;
  }
  return std::nullopt;
}

const std::string& LineMap::default_file() const {
  static const std::string none;
  return segments_.empty() ? none : segments_.front().file;
}

}  // namespace simit::repl
