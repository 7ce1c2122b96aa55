// What `simit run SCENE` prints while the frames run: one progress line per frame (or one
// line rewritten in place on a terminal) and a summary.
#pragma once

#include <ostream>
#include <string>
#include <vector>

namespace simit::scene {

struct FrameReport {
  int frame = 0, frames = 0;
  double ms = 0.0;         // this frame
  double total_ms = 0.0;   // every frame so far
  double elapsed_s = 0.0;  // wall time since the first frame started
  const std::vector<std::string>* stat_names = nullptr;
  const std::vector<double>* stats = nullptr;  // step's scalar results, in that order
};

void print_progress(std::ostream& out, const FrameReport& r, bool rewrite_line);
// "N frames, X ms/frame" (without timings when `quiet`) and the series written.
void print_summary(std::ostream& out, int frames, double total_ms, bool quiet,
                   const std::string& pvd_path);

}  // namespace simit::scene
