// --jit-stats: each trace's site, key, status, compile time, calls and time in its kernels.
#include <algorithm>
#include <chrono>
#include <cstring>
#include <ctime>
#include <functional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "interp/exec_state.h"
#include "interp/runtime_error.h"
#include "interp/set_binding.h"
#include "jit/controller_state.h"
#include "jit/matrix_sum.h"
#include "jit/pruned_matrix.h"
#include "jit/ptx/gpu_executor.h"
#include "jit/specialise.h"
#include "jit/write_guard.h"
#include "runtime/system_ops.h"

namespace simit::jit {

namespace ast = frontend::ast;
using interp::Value;

std::string bytes_text(long long bytes) {
  std::ostringstream os;
  os.precision(1);
  if (bytes < 10 * 1024)
    os << bytes << " bytes";
  else if (bytes < 10 * 1024 * 1024)
    os << std::fixed << static_cast<double>(bytes) / 1024.0 << " KB";
  else
    os << std::fixed << static_cast<double>(bytes) / (1024.0 * 1024.0) << " MB";
  return os.str();
}

double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

CallTimer::CallTimer(TraceStats& stats) : stats_(stats), start_(std::chrono::steady_clock::now()) {
  constexpr double kReadCpuFromMs = 0.2;
  if (stats_.calls == 0 || stats_.run_ms >= kReadCpuFromMs * static_cast<double>(stats_.calls))
    cpu_ = thread_cpu_ms();
}

void CallTimer::done() {
  const double wall =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
  stats_.run_ms += wall;
  stats_.cpu_ms += cpu_ >= 0.0 ? thread_cpu_ms() - cpu_ : wall;
  ++stats_.calls;
}

std::string SimdReport::summary() const {
  std::string out = "SIMD: ";
  if (map && lanes > 1) {
    out += std::to_string(lanes) + " elements at once";
  } else {
    if (map) out += "no lanes (" + (lanes_why_not.empty() ? "no reason" : lanes_why_not) + "); ";
    if (!vectorisers) return out + "LLVM's vectorisers off (a large trace)";
    if (loops.empty()) {
      out += "no loop for LLVM's vectoriser";
    } else {
      int vectorised = 0, lo = 0, hi = 0;
      // Each reason not to vectorise (a loop's first), with its count, in order of appearance.
      std::vector<std::pair<std::string, int>> not_why;
      for (const SimdLoop& l : loops) {
        if (l.width > 1) {
          ++vectorised;
          lo = lo == 0 ? l.width : std::min(lo, l.width);
          hi = std::max(hi, l.width);
          continue;
        }
        const std::string why = l.why_not.substr(0, l.why_not.find(", "));
        auto it = std::find_if(not_why.begin(), not_why.end(),
                               [&](const auto& w) { return w.first == why; });
        if (it == not_why.end())
          not_why.emplace_back(why, 1);
        else
          ++it->second;
      }
      out += std::to_string(vectorised) + " of " + std::to_string(loops.size()) + " loop" +
             (loops.size() == 1 ? "" : "s") + " vectorised";
      if (vectorised > 0)
        out += " (width " + std::to_string(lo) + (hi > lo ? "-" + std::to_string(hi) : "") + ")";
      std::stable_sort(not_why.begin(), not_why.end(),
                       [](const auto& a, const auto& b) { return a.second > b.second; });
      for (size_t i = 0; i < not_why.size(); ++i)
        out += (i == 0 ? "; not: " : ", ") + not_why[i].first + " (" +
               std::to_string(not_why[i].second) + ")";
    }
  }
  if (slp_groups > 0)
    out += "; SLP: " + std::to_string(slp_groups) + " group" + (slp_groups == 1 ? "" : "s");
  return out;
}

std::vector<TraceStats> TraceController::stats() const {
  std::vector<TraceStats> out;
  for (const auto& [site, s] : sites_)
    for (const auto& [key, e] : s->kernels) {
      out.push_back(e->stats);
      for (size_t i = 0; i < e->special.size(); ++i) {
        const Entry::Special& sp = e->special[i];
        char note[160];
        if (sp.pattern) {
          std::snprintf(note, sizeof note,
                        "; result %zu specialised to %.1f%% of its blocks (%lld of %lld, built in "
                        "%.2f ms)",
                        i,
                        100.0 * static_cast<double>(sp.pattern->kept) /
                            static_cast<double>(std::max<int64_t>(sp.pattern->total, 1)),
                        static_cast<long long>(sp.pattern->kept),
                        static_cast<long long>(sp.pattern->total), sp.pattern->build_ms);
          out.back().note += note;
        }
      }
      if (e->guard_calls > 0) {
        char note[200];
        std::snprintf(note, sizeof note,
                      "; guard: %zu field version%s and %zu scalar%s compared per call, %.0f ns "
                      "per call",
                      e->deciders->fields.size(), e->deciders->fields.size() == 1 ? "" : "s",
                      e->deciders->scalars.size(), e->deciders->scalars.size() == 1 ? "" : "s",
                      1e6 * e->guard_ms / static_cast<double>(e->guard_calls));
        out.back().note += note;
      }
      if (e->guard_failures > 0)
        out.back().note += "; the guard failed on " + std::to_string(e->guard_failures) + " call" +
                           (e->guard_failures > 1 ? "s" : "") + " (blocks recorded again)";
      if (!e->full_why.empty()) out.back().note += "; full patterns: " + e->full_why;
    }
  // A system kernel's note is rebuilt at each call (jit/loop_kernel.cpp): its SIMD report
  // is added here.
  for (const auto* states : {&runs_, &loops_})
    for (const auto& [at, s] : *states)
      for (const auto& e : s->entries) {
        out.push_back(e->stats);
        if (e->kernel && e->kernel->simd.reported)
          out.back().note += "; " + e->kernel->simd.summary();
      }
  for (const auto& [at, s] : alone_)
    for (const auto& e : s->entries)
      if (e->kernel) {
        out.push_back(e->stats);
        if (e->kernel->simd.reported) out.back().note += "; " + e->kernel->simd.summary();
      }
  for (const auto& [at, s] : sums_) {
    if (s.stats.status.empty()) continue;
    out.push_back(s.stats);
    // Sums left pending (jit/pending_sums.h): how many a read outside a loop's copy wrote.
    if (s.pending > 0)
      out.back().note += "; " + std::to_string(s.pending) +
                         " calls summed where a solver loop's binary32 copy reads them (of all "
                         "fused sums, " +
                         std::to_string(pending_sums_.written()) + " of " +
                         std::to_string(pending_sums_.held()) +
                         " written whole for another reader)";
  }
  std::stable_sort(out.begin(), out.end(), [](const TraceStats& a, const TraceStats& b) {
    return a.line != b.line ? a.line < b.line : a.site < b.site;
  });
  return out;
}

void TraceController::print_stats(std::ostream& os) const {
  os << "jit traces:\n";
  char line[256];
  std::snprintf(line, sizeof line, "  %-28s %10s %8s %10s %10s %8s  %s\n", "site", "compile ms",
                "calls", "run ms", "cpu ms", "ir nodes", "status");
  os << line;
  for (const TraceStats& s : stats()) {
    std::snprintf(line, sizeof line, "  %-28s %10.1f %8ld %10.2f %10.2f %8zu  ", s.site.c_str(),
                  s.compile_ms, s.calls, s.run_ms, s.cpu_ms, s.ir_nodes);
    os << line << s.status << "\n      key: " << s.key << s.note << "\n";
  }
  if (!device_executor_) return;
  // Residency over the whole run (runtime/residency.h): what stayed on the device, and what
  // the host touched and had brought back.
  const ptx::GpuTraffic t = ptx::gpu_traffic(*device_executor_);
  os << "gpu residency: " << t.kept_on_device << " writes left on the device ("
     << bytes_text(t.bytes_kept) << "), " << t.uploads_resident << " uploads skipped for them, "
     << t.brought_back << " brought back when the host read them ("
     << bytes_text(t.bytes_brought_back) << "), " << t.dropped << " dropped unread; "
     << bytes_text(t.bytes_to_device) << " copied in, " << bytes_text(t.bytes_to_host)
     << " copied back\n";
}

}  // namespace simit::jit
