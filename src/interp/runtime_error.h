// A run-time error of the program (LANGUAGE.md §10.6): where it happened, what happened,
// and the chain of calls that led there. It stops the run; it never crashes the host.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "frontend/source.h"

namespace simit::interp {

class RuntimeError : public std::runtime_error {
 public:
  // One active call: the function and where it was (the error, or the call it made).
  struct Frame {
    std::string func;
    frontend::SourceSpan at;
  };

  RuntimeError(frontend::SourceSpan where, std::string message);

  const frontend::SourceSpan& where() const { return where_; }
  const std::string& message() const { return message_; }
  // Innermost call first.
  const std::vector<Frame>& stack() const { return stack_; }
  // Records the next enclosing call, innermost first: `func` was at the place recorded last
  // (the error itself for the first frame); `call_site` is where `func` was called from.
  void add_frame(std::string func, frontend::SourceSpan call_site);
  // Says which element the innermost frame recorded so far was mapped over, so that an error
  // in a mapped function names its element: `  in f, element 17 of set 'tets' (file:line)`.
  void name_element(const std::string& element);
  // The line of `where` (0 when it has no place).
  int line() const;

  // `file:line:col: runtime error: message`, then `  in f (file:line)` per active call.
  std::string render() const;

 private:
  frontend::SourceSpan where_;
  std::string message_;
  std::vector<Frame> stack_;
  frontend::SourceSpan next_;  // where the next frame added was executing
};

}  // namespace simit::interp
