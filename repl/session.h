// The REPL's state, with no terminal code: accumulated declarations (as source text),
// variables kept as values between inputs, and the `:` commands. The terminal front end
// (repl/terminal.h) feeds it lines; tests feed it strings.
#pragma once

#include <map>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "frontend/frontend.h"
#include "interp/value.h"

namespace simit::repl {

class Session {
 public:
  // Results and values go to `out`; diagnostics and run-time errors to `err`.
  Session(std::ostream& out, std::ostream& err);
  ~Session();

  // Feeds one line. An incomplete input (an open block or bracket) is kept until a later
  // line completes it. Returns false once the session has been asked to quit.
  bool feed_line(const std::string& line);
  // True while a multi-line input is waiting for more lines (the prompt changes).
  bool pending() const { return !buffer_.empty(); }
  bool quit_requested() const { return quit_; }

  // Candidates for tab completion of `prefix`: commands (when it starts with ':'),
  // declared names, persistent variables and intrinsics.
  std::vector<std::string> completions(const std::string& prefix) const;

  // Whether `text` is a complete input: blocks closed by `end`, brackets closed.
  static bool is_complete(const std::string& text);

 private:
  struct Var {
    std::string type;  // as the checker prints it
    interp::Value value;
  };

  void handle(const std::string& input);
  void command(const std::string& line);
  void declarations(const std::string& input);
  void statements(const std::string& input, bool expression, bool type_only);
  bool load(const std::string& path, std::string& text);
  std::string program_text() const;
  std::unique_ptr<frontend::Compilation> compile(const std::string& prefix,
                                                 const std::string& input,
                                                 const std::string& suffix, int& input_offset);
  void report(const frontend::Compilation& c, int input_offset);

  std::ostream& out_;
  std::ostream& err_;
  std::string buffer_;                 // lines of an incomplete input
  std::vector<std::string> files_;     // loaded with :load, in order
  std::vector<std::string> file_texts_;
  std::string decls_;                  // declarations entered at the prompt
  std::map<std::string, Var> vars_;    // persistent variables
  std::vector<std::string> names_;     // declared names (for completion)
  bool quit_ = false;
  int counter_ = 0;
};

}  // namespace simit::repl
