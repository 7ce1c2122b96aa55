// `simit test`: runs the sections of test files (TESTFORMAT.md §1-7) and reports them.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "executor.h"
#include "sections.h"

namespace simit::tools {

enum class Outcome { Pass, Fail, Skip };

// What happened to one section.
struct SectionReport {
  std::string label;  // `file-stem::name` (just the stem for an unsectioned file)
  std::string file;
  int line = 1;  // where the section starts in the file
  Outcome outcome = Outcome::Pass;
  std::string reason;  // one line; empty for a pass
  std::string detail;  // further lines (rendered diagnostics), may be empty
  JitRecord jit;       // what the JIT made of the section's runs, when the executor records it
};

// How a section is to be judged, from where its file lives.
struct SectionContext {
  std::string file;
  bool illegal_folder = false;   // every section must be rejected (§5)
  Executor* executor = nullptr;  // null: sections with something to run are skipped
};

// Compiles one section on its own and judges it. Diagnostics carry file-relative lines.
SectionReport run_section(const Section& section, const SectionContext& context);

// Every section of one file's text, in order (disabled ones are reported as skipped).
std::vector<SectionReport> run_file(const std::string& file, const std::string& text,
                                    Executor* executor);

struct TestOptions {
  bool verbose = false;  // list every section, not only failures
  Executor* executor = nullptr;
  // Print the JIT's tables under each section listed and a summary of all traces before
  // the last line (the executor records them).
  bool jit_stats = false;
};

// Runs every test file under `paths`, prints reports and the summary line
// `N passed, N failed[, N skipped]` to `out`; returns 0, or 1 when anything failed.
int run_tests(const std::vector<std::string>& paths, const TestOptions& options, std::ostream& out,
              std::ostream& err);

}  // namespace simit::tools
