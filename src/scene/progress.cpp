// Progress lines and the summary of a scene run.
#include "scene/progress.h"

#include <cstdio>

namespace simit::scene {

namespace {

std::string format_seconds(double s) {
  char buf[32];
  if (s < 60)
    std::snprintf(buf, sizeof buf, "%.1f s", s);
  else if (s < 3600)
    std::snprintf(buf, sizeof buf, "%d min %02d s", int(s) / 60, int(s) % 60);
  else
    std::snprintf(buf, sizeof buf, "%d h %02d min", int(s) / 3600, (int(s) % 3600) / 60);
  return buf;
}

}  // namespace

void print_progress(std::ostream& out, const FrameReport& r, bool rewrite_line) {
  const double eta = r.elapsed_s / r.frame * (r.frames - r.frame);
  char line[160];
  std::snprintf(line, sizeof line, "frame %d/%d  %.1f ms/frame  ETA %s", r.frame, r.frames,
                r.total_ms / r.frame, format_seconds(eta).c_str());
  if (rewrite_line) {
    out << '\r' << line << "   " << std::flush;
    return;
  }
  out << line << "  (this frame " << std::fixed;
  out.precision(1);
  out << r.ms << " ms";
  out << std::defaultfloat;
  out.precision(6);
  for (size_t k = 0; k < r.stats->size(); ++k)
    out << ", " << (*r.stat_names)[k] << " = " << (*r.stats)[k];
  out << ")\n" << std::flush;
}

void print_summary(std::ostream& out, int frames, double total_ms, bool quiet,
                   const std::string& pvd_path) {
  char summary[160];
  std::snprintf(summary, sizeof summary, "%d frames, %.1f ms/frame", frames,
                frames ? total_ms / frames : 0.0);
  if (quiet) std::snprintf(summary, sizeof summary, "%d frames", frames);
  out << summary;
  if (!pvd_path.empty()) out << "; wrote " << pvd_path;
  out << "\n";
}

}  // namespace simit::scene
