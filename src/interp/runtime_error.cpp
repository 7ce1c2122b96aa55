// Run-time errors with their call stacks.
#include "interp/runtime_error.h"

namespace simit::interp {

namespace {

std::string headline(const frontend::SourceSpan& where, const std::string& message) {
  std::string out;
  if (where.valid()) {
    frontend::LineCol lc = where.start();
    out =
        where.file->name() + ":" + std::to_string(lc.line) + ":" + std::to_string(lc.column) + ": ";
  }
  return out + "runtime error: " + message;
}

}  // namespace

RuntimeError::RuntimeError(frontend::SourceSpan where, std::string message)
    : std::runtime_error(headline(where, message)),
      where_(where),
      message_(std::move(message)),
      next_(where) {}

void RuntimeError::add_frame(std::string func, frontend::SourceSpan call_site) {
  stack_.push_back({std::move(func), next_});
  next_ = call_site;
}

void RuntimeError::name_element(const std::string& element) {
  if (!stack_.empty()) stack_.back().func += ", " + element;
}

int RuntimeError::line() const { return where_.valid() ? where_.start().line : 0; }

std::string RuntimeError::render() const {
  std::string out = what();
  out += "\n";
  for (const Frame& f : stack_) {
    out += "  in " + f.func;
    if (f.at.valid())
      out += " (" + f.at.file->name() + ":" + std::to_string(f.at.start().line) + ")";
    out += "\n";
  }
  return out;
}

}  // namespace simit::interp
