// `simit test`: runs the sections of test files (TESTFORMAT.md §1-7) and reports them.
#include "test_runner.h"

#include <algorithm>
#include <exception>
#include <filesystem>
#include <map>
#include <memory>

#include "directives.h"
#include "files.h"
#include "frontend/frontend.h"

namespace simit::tools {
namespace {

using frontend::Compilation;
using frontend::Diagnostic;

constexpr size_t kMaxDetailDiagnostics = 5;

// Skip reasons are fixed texts so that the summary can count them.
constexpr const char* kSkipDisabled = "disabled (%%%-)";
constexpr const char* kSkipTests =
    "has %! tests; running them needs an executor (none is built yet)";
constexpr const char* kSkipGraph =
    "has graph directives; running them needs an executor (none is built yet)";
constexpr const char* kSkipRuntime =
    "expects a run-time error; running it needs an executor (none is built yet)";

std::string label_of(const std::string& file, const Section& section) {
  std::string stem = std::filesystem::path(file).stem().string();
  return section.sectioned ? stem + "::" + section.name : stem;
}

// The section's text placed where it stands in the file, so that diagnostics carry the
// file's line and column numbers.
std::string positioned_source(const Section& section) {
  std::string text(static_cast<size_t>(section.line - 1), '\n');
  text.append(static_cast<size_t>(section.column - 1), ' ');
  return text + section.source;
}

int file_line(const Section& section, int section_line) { return section.line + section_line - 1; }

// `file:line:col`
std::string location(const frontend::SourceSpan& span) {
  frontend::LineCol lc = span.start();
  return span.file->name() + ":" + std::to_string(lc.line) + ":" + std::to_string(lc.column);
}

// `file:line:col: message` (or just the message for a diagnostic without a place).
std::string one_line(const Diagnostic& d) {
  return d.span.valid() ? location(d.span) + ": " + d.message : d.message;
}

std::string rendered(const Compilation& c) {
  std::string out;
  const auto& items = c.diagnostics.items();
  for (size_t i = 0; i < items.size() && i < kMaxDetailDiagnostics; ++i)
    out += frontend::Diagnostics::render(items[i]);
  if (items.size() > kMaxDetailDiagnostics)
    out += "(" + std::to_string(items.size() - kMaxDetailDiagnostics) + " more diagnostics)\n";
  return out;
}

void fail(SectionReport& r, std::string reason, std::string detail = "") {
  r.outcome = Outcome::Fail;
  r.reason = std::move(reason);
  r.detail = std::move(detail);
}

void skip(SectionReport& r, std::string reason) {
  r.outcome = Outcome::Skip;
  r.reason = std::move(reason);
}

// Directive problems fail the section before anything is compiled.
bool report_directive_errors(const SectionDirectives& d, const SectionContext& context,
                             const Section& section, SectionReport& r) {
  std::string detail;
  for (const auto& e : d.errors)
    detail +=
        context.file + ":" + std::to_string(file_line(section, e.line)) + ": " + e.message + "\n";
  if (context.illegal_folder && d.error && d.error->runtime())
    detail += context.file + ":" + std::to_string(section.line) +
              ": '%@ error runtime' in a folder named illegal, whose sections must be rejected\n";
  if (detail.empty()) return false;
  size_t first_end = detail.find('\n');
  // The detail repeats the reason; it is worth printing only when there are several.
  fail(r, "bad directive: " + detail.substr(0, first_end),
       first_end + 1 < detail.size() ? detail : "");
  return true;
}

// A must-fail section: rejected, and the first diagnostic as the directives describe (§7.2).
void judge_rejection(const Compilation& c, const ErrorExpectation& expected, const Section& section,
                     SectionReport& r) {
  if (c.ok()) {
    std::string what = expected.category.empty() ? "an error" : "a " + expected.category + " error";
    return fail(r, "expected " + what + ", but the section compiled");
  }
  if (c.diagnostics.items().empty()) return fail(r, "rejected without a diagnostic");
  const Diagnostic& first = c.diagnostics.items().front();
  if (!expected.category.empty() && !frontend::category_matches(first, expected.category))
    return fail(r,
                "expected a " + expected.category + " error first, got " +
                    frontend::category_name(first) + ": " + one_line(first),
                rendered(c));
  if (expected.line) {
    int line = first.span.valid() ? first.span.start().line - section.line + 1 : 0;
    if (line != *expected.line)
      return fail(r,
                  "expected the first error on section line " + std::to_string(*expected.line) +
                      " (file line " + std::to_string(file_line(section, *expected.line)) +
                      "), got section line " + std::to_string(line) + ": " + one_line(first),
                  rendered(c));
  }
  for (const auto& text : expected.contains) {
    bool found = false;
    for (const auto& d : c.diagnostics.items())
      found = found || d.message.find(text) != std::string::npos;
    if (!found) return fail(r, "no diagnostic contains \"" + text + "\"", rendered(c));
  }
}

std::vector<const frontend::ast::TestDecl*> inline_tests(const frontend::ast::Program& program) {
  std::vector<const frontend::ast::TestDecl*> tests;
  for (const auto& decl : program.decls)
    if (const auto* t = decl->as<frontend::ast::TestDecl>()) tests.push_back(t);
  return tests;
}

// Runs the `%!` tests, then the graph directives; the first result that did not pass.
RunResult run_in_order(Executor& executor, const Compilation& c, const SectionDirectives& d) {
  for (const auto* test : inline_tests(*c.program)) {
    RunResult result = executor.run_test(*c.program, *test);
    if (!result.passed()) {
      std::string where = test->span.valid() ? location(test->span) + ": " : "";
      result.message = where + "%! " + test->func + ": " + result.message;
      return result;
    }
  }
  if (d.has_graph()) return executor.run_graph(*c.program, d.graph);
  return {};
}

RunResult run_all(Executor& executor, const Compilation& c, const SectionDirectives& d) {
  try {
    return run_in_order(executor, c, d);
  } catch (const std::exception& e) {
    // Executors report run-time errors as results; an exception is their own failure.
    return {RunResult::Status::Failed, "the " + executor.name() + " threw: " + e.what()};
  }
}

// A section expected to compile and then stop with a run-time error.
void judge_runtime_error(const Compilation& c, const SectionDirectives& d,
                         const SectionContext& context, const Section& section, SectionReport& r) {
  if (inline_tests(*c.program).empty() && !d.has_graph())
    return fail(r, "expects a run-time error, but has nothing to run");
  if (!context.executor) return skip(r, kSkipRuntime);
  RunResult result = run_all(*context.executor, c, d);
  if (result.status == RunResult::Status::Skipped) return skip(r, result.message);
  if (result.status != RunResult::Status::RuntimeError)
    return fail(r, result.passed() ? "expected a run-time error, but the runs succeeded"
                                   : "expected a run-time error, got: " + result.message);
  if (d.error->line && result.line != file_line(section, *d.error->line))
    return fail(r, "expected the run-time error on section line " + std::to_string(*d.error->line) +
                       " (file line " + std::to_string(file_line(section, *d.error->line)) +
                       "), got: " + result.message);
  for (const auto& text : d.error->contains)
    if (result.message.find(text) == std::string::npos)
      return fail(r, "the run-time error does not contain \"" + text + "\": " + result.message);
}

// A section expected to compile, then run its tests and graph directives.
void judge_run(const Compilation& c, const SectionDirectives& d, const SectionContext& context,
               SectionReport& r) {
  bool has_tests = !inline_tests(*c.program).empty();
  if (!has_tests && !d.has_graph()) return;
  if (!context.executor) return skip(r, has_tests ? kSkipTests : kSkipGraph);
  RunResult result = run_all(*context.executor, c, d);
  if (result.status == RunResult::Status::Skipped) return skip(r, result.message);
  if (!result.passed()) fail(r, result.message);
}

std::unique_ptr<Compilation> compile_section(const Section& section, const SectionContext& context,
                                             SectionReport& r) {
  try {
    return frontend::compile_source(context.file, positioned_source(section));
  } catch (const std::exception& e) {
    // Never a user mistake: the frontend must report, not throw.
    fail(r, std::string("the compiler threw: ") + e.what());
    return nullptr;
  }
}

void judge_section(const Section& section, const SectionContext& context, SectionReport& r) {
  if (section.disabled) return skip(r, kSkipDisabled);
  SectionDirectives d = parse_directives(section.source);
  if (report_directive_errors(d, context, section, r)) return;
  std::unique_ptr<Compilation> c = compile_section(section, context, r);
  if (!c) return;
  bool runtime_error = d.error && d.error->runtime();
  if (context.illegal_folder || (d.error && !runtime_error)) {
    judge_rejection(*c, d.error.value_or(ErrorExpectation{}), section, r);
  } else if (!c->ok()) {
    const auto& items = c->diagnostics.items();
    fail(r, "does not compile: " + (items.empty() ? "no diagnostic" : one_line(items.front())),
         rendered(*c));
  } else if (runtime_error) {
    judge_runtime_error(*c, d, context, section, r);
  } else {
    judge_run(*c, d, context, r);
  }
}

}  // namespace

SectionReport run_section(const Section& section, const SectionContext& context) {
  SectionReport r;
  r.label = label_of(context.file, section);
  r.file = context.file;
  r.line = section.line;
  if (context.executor) context.executor->take_jit_record();  // not an earlier caller's
  judge_section(section, context, r);
  if (context.executor) r.jit = context.executor->take_jit_record();
  return r;
}

std::vector<SectionReport> run_file(const std::string& file, const std::string& text,
                                    Executor* executor) {
  SectionContext context{file, in_illegal_folder(file), executor};
  std::vector<SectionReport> reports;
  for (const Section& section : split_sections(text))
    reports.push_back(run_section(section, context));
  return reports;
}

namespace {

const char* outcome_word(Outcome o) {
  switch (o) {
    case Outcome::Pass: return "PASS";
    case Outcome::Fail: return "FAIL";
    case Outcome::Skip: return "SKIP";
  }
  return "?";
}

void print_indented(const std::string& text, std::ostream& out) {
  size_t begin = 0;
  while (begin < text.size()) {
    size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    out << "    " << text.substr(begin, end - begin) << "\n";
    begin = end + 1;
  }
}

void print_report(const SectionReport& r, bool jit_stats, std::ostream& out) {
  out << outcome_word(r.outcome) << " " << r.label << " (" << r.file << ":" << r.line << ")";
  if (!r.reason.empty()) out << ": " << r.reason;
  out << "\n";
  print_indented(r.detail, out);
  if (jit_stats) print_indented(r.jit.tables, out);
}

// A trace's status without the line it ends with ("... (line 12)"), so that the same reason
// in many sections counts as one.
std::string without_line(const std::string& status) {
  const size_t open = status.rfind(" (line ");
  if (open == std::string::npos || !status.ends_with(")")) return status;
  const std::string digits = status.substr(open + 7, status.size() - open - 8);
  if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos) return status;
  return status.substr(0, open);
}

// What the JIT made of every section: traces compiled (or fused) and run interpreted, with
// the reasons counted, so that a corpus run shows what its sections did not compile.
struct JitTally {
  int sections = 0, traces = 0, compiled = 0, on_gpu = 0;
  std::map<std::string, int> interpreted;  // the status ("interpreted: why") and its count

  void add(const JitRecord& j) {
    if (j.statuses.empty()) return;
    ++sections;
    for (const std::string& s : j.statuses) {
      ++traces;
      if (s.starts_with("interpreted"))
        ++interpreted[without_line(s)];
      else
        ++compiled;
      if (s == "compiled for the GPU") ++on_gpu;
    }
  }

  // The most frequent reasons first.
  void print(std::ostream& out) const {
    out << "jit: " << traces << (traces == 1 ? " trace" : " traces") << " in " << sections
        << (sections == 1 ? " section" : " sections") << ", " << compiled << " compiled";
    if (on_gpu) out << " (" << on_gpu << " for the GPU)";
    out << ", " << traces - compiled << " interpreted\n";
    std::vector<std::pair<int, std::string>> reasons;
    for (const auto& [status, count] : interpreted) reasons.emplace_back(-count, status);
    std::sort(reasons.begin(), reasons.end());
    for (const auto& [count, status] : reasons) out << "jit: " << -count << " " << status << "\n";
  }
};

struct Tally {
  int passed = 0, failed = 0, skipped = 0;
  std::map<std::string, int> skip_reasons;
  JitTally jit;

  void add(const SectionReport& r) {
    if (r.outcome == Outcome::Pass) ++passed;
    if (r.outcome == Outcome::Fail) ++failed;
    if (r.outcome == Outcome::Skip) {
      ++skipped;
      ++skip_reasons[r.reason];
    }
    jit.add(r.jit);
  }
};

void print_summary(const Tally& t, const TestOptions& options, std::ostream& out) {
  if (!options.verbose)
    for (const auto& [reason, count] : t.skip_reasons)
      out << "skipped " << count << ": " << reason << "\n";
  if (options.jit_stats) t.jit.print(out);
  out << t.passed << " passed, " << t.failed << " failed";
  if (t.skipped > 0) out << ", " << t.skipped << " skipped";
  out << "\n";
}

}  // namespace

int run_tests(const std::vector<std::string>& paths, const TestOptions& options, std::ostream& out,
              std::ostream& err) {
  FoundFiles found = find_test_files(paths);
  for (const auto& p : found.errors) err << "simit test: cannot read '" << p << "'\n";
  if (found.files.empty() && found.errors.empty()) {
    err << "simit test: no .sim files found\n";
    return 1;
  }
  Tally tally;
  for (const auto& file : found.files) {
    std::string error;
    std::optional<std::string> text = read_text_file(file, error);
    if (!text) {
      err << "simit test: cannot read '" << file << "': " << error << "\n";
      ++tally.failed;
      continue;
    }
    for (const SectionReport& r : run_file(file, *text, options.executor)) {
      tally.add(r);
      if (options.verbose || r.outcome == Outcome::Fail) print_report(r, options.jit_stats, out);
    }
  }
  tally.failed += static_cast<int>(found.errors.size());
  print_summary(tally, options, out);
  return tally.failed > 0 ? 1 : 0;
}

}  // namespace simit::tools
