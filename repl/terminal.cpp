// The REPL's terminal front end: see terminal.h. On a terminal it uses readline's callback
// interface, so that Ctrl-C at the prompt can abandon the line being typed; through a pipe it
// reads plain lines.
#include "terminal.h"

#include <sys/select.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <optional>

#include "simit/repl.h"

#ifdef SIMIT_HAVE_READLINE
#include <readline/history.h>
#include <readline/readline.h>
#endif

namespace simit::repl {
namespace {

// Ctrl-C stops the session's computation; at the prompt it abandons the line being typed.
// The handler only sets flags (ReplSession::interrupt is async-signal-safe).
ReplSession* g_interruptible = nullptr;
volatile std::sig_atomic_t g_sigint = 0;

void on_sigint(int) {
  g_sigint = 1;
  if (g_interruptible) g_interruptible->interrupt();
}

// Installed for the session's lifetime, restored after. SA_RESTART: a blocking read goes on;
// select() still returns EINTR, which the prompt uses.
class SigintHandler {
 public:
  explicit SigintHandler(ReplSession& session) {
    g_interruptible = &session;
    struct sigaction sa {};
    sa.sa_handler = on_sigint;
    sa.sa_flags = SA_RESTART;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &previous_);
  }
  ~SigintHandler() {
    sigaction(SIGINT, &previous_, nullptr);
    g_interruptible = nullptr;
  }
  SigintHandler(const SigintHandler&) = delete;
  SigintHandler& operator=(const SigintHandler&) = delete;

 private:
  struct sigaction previous_ {};
};

#ifdef SIMIT_HAVE_READLINE
ReplSession* g_session = nullptr;

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
  // `verts.x` is usually followed by `[` or an operator, not by a blank.
  if (std::strchr(text, '.')) rl_completion_append_character = '\0';
  return rl_completion_matches(text, complete_one);
}

// The line readline's callback interface finished (or end of input).
std::optional<std::string> g_line;
bool g_eof = false;

void on_line(char* line) {
  if (!line) {
    g_eof = true;
  } else {
    g_line = line;
    std::free(line);
  }
}

class History {
 public:
  History() {
    if (const char* home = std::getenv("HOME")) path_ = std::string(home) + "/.simit_history";
    // append_history only extends an existing file: create it on the first run.
    if (!path_.empty() && read_history(path_.c_str()) != 0) write_history(path_.c_str());
  }
  void add(const std::string& line) {
    if (line.empty()) return;
    add_history(line.c_str());
    if (!path_.empty()) append_history(1, path_.c_str());
  }

 private:
  std::string path_;
};

// Reads one line at `prompt`; nullopt at Ctrl-D. Ctrl-C abandons the line being typed and
// returns an empty one (`interrupted` is set).
std::optional<std::string> read_line(const char* prompt, bool& interrupted) {
  g_line.reset();
  g_eof = false;
  interrupted = false;
  g_sigint = 0;
  rl_callback_handler_install(prompt, on_line);
  while (!g_line && !g_eof) {
    fd_set fds;
    FD_ZERO(&fds);
    FD_SET(fileno(rl_instream), &fds);
    int ready = select(fileno(rl_instream) + 1, &fds, nullptr, nullptr, nullptr);
    if (ready < 0 && errno == EINTR) {
      if (!g_sigint) continue;
      g_sigint = 0;
      rl_free_line_state();
      rl_replace_line("", 0);
      rl_crlf();
      interrupted = true;
      break;
    }
    if (ready > 0) rl_callback_read_char();
  }
  rl_callback_handler_remove();
  if (interrupted) return std::string();
  if (g_eof) return std::nullopt;
  return g_line;
}

int run_terminal(ReplSession& session) {
  g_session = &session;
  rl_catch_signals = 0;  // our handler: Ctrl-C must reach the session
  rl_attempted_completion_function = complete;
  History history;
  session.set_line_source([&](const std::string& prompt) -> std::optional<std::string> {
    bool interrupted = false;
    std::optional<std::string> line = read_line(prompt.c_str(), interrupted);
    if (line) history.add(*line);
    return line;
  });
  std::cout << "Simit REPL: :help for help, :quit or Ctrl-D to leave.\n";
  while (true) {
    bool interrupted = false;
    std::optional<std::string> line =
        read_line(session.pending() ? "....> " : "simit> ", interrupted);
    if (interrupted) {
      session.cancel_pending();
      continue;
    }
    if (!line) {
      std::cout << "\n";
      break;
    }
    history.add(*line);
    bool go_on = session.feed_line(*line);
    std::cout.flush();
    if (!go_on) break;
  }
  return 0;
}
#endif

}  // namespace

int run_repl(const std::string& file) {
  ReplSession session(std::cout, std::cerr);
  SigintHandler sigint(session);
#ifdef SIMIT_HAVE_READLINE
  const bool terminal = isatty(fileno(stdin)) && isatty(fileno(stdout));
#else
  const bool terminal = false;
#endif
  if (!terminal) {
    // Through a pipe the debugger reads its commands from the same stream, with no prompt.
    session.set_line_source([](const std::string&) -> std::optional<std::string> {
      std::string line;
      if (!std::getline(std::cin, line)) return std::nullopt;
      return line;
    });
  }
  if (!file.empty()) session.feed_line((file.ends_with(".toml") ? ":scene " : ":load ") + file);
#ifdef SIMIT_HAVE_READLINE
  if (terminal) return run_terminal(session);
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
