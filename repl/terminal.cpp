// The REPL's terminal front end: see terminal.h.
#include "terminal.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>

#include "session.h"

#ifdef SIMIT_HAVE_READLINE
#include <readline/history.h>
#include <readline/readline.h>
#endif

namespace simit::repl {
namespace {

#ifdef SIMIT_HAVE_READLINE
Session* g_session = nullptr;

char* complete_one(const char* text, int state) {
  static std::vector<std::string> matches;
  static size_t next = 0;
  if (state == 0) {
    // A command is completed only at the start of the line.
    std::string prefix = text;
    if (rl_point > 0 && rl_line_buffer[0] == ':' && rl_point == static_cast<int>(prefix.size()) + 1)
      prefix = ":" + prefix;
    matches = g_session->completions(prefix);
    if (prefix != text)
      for (auto& m : matches) m = m.substr(1);
    next = 0;
  }
  return next < matches.size() ? strdup(matches[next++].c_str()) : nullptr;
}

char** complete(const char* text, int, int) {
  rl_attempted_completion_over = 1;
  return rl_completion_matches(text, complete_one);
}

int run_terminal(Session& session) {
  g_session = &session;
  rl_attempted_completion_function = complete;
  std::string history;
  if (const char* home = std::getenv("HOME")) history = std::string(home) + "/.simit_history";
  if (!history.empty()) read_history(history.c_str());
  std::cout << "Simit REPL: :help for help, :quit or Ctrl-D to leave.\n";
  while (true) {
    char* line = readline(session.pending() ? "....> " : "simit> ");
    if (!line) {
      std::cout << "\n";
      break;
    }
    if (*line) {
      add_history(line);
      if (!history.empty()) append_history(1, history.c_str());
    }
    bool go_on = session.feed_line(line);
    std::free(line);
    std::cout.flush();
    if (!go_on) break;
  }
  return 0;
}
#endif

}  // namespace

int run_repl(const std::string& file) {
  Session session(std::cout, std::cerr);
  if (!file.empty()) session.feed_line(":load " + file);
#ifdef SIMIT_HAVE_READLINE
  if (isatty(fileno(stdin)) && isatty(fileno(stdout))) return run_terminal(session);
#endif
  std::string line;
  while (std::getline(std::cin, line)) {
    bool go_on = session.feed_line(line);
    std::cout.flush();
    if (!go_on) break;
  }
  return 0;
}

}  // namespace simit::repl
