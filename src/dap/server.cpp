// The DAP server's transport and threads: framed output, the reader thread, the queue of
// requests, and the debugger's stops handed to the client.
#include "dap/server.h"

#include <poll.h>
#include <unistd.h>

#include <cerrno>

#include <streambuf>

#include "dap/framing.h"

namespace simit::dap {

namespace {

// What the program prints (and the run's progress), line by line as `output` events.
class OutputEvents : public std::streambuf {
 public:
  explicit OutputEvents(Server& server) : server_(server) {}
  ~OutputEvents() override { flush_line(); }

 protected:
  int overflow(int c) override {
    if (c == traits_type::eof()) return 0;
    line_ += static_cast<char>(c);
    if (c == '\n') flush_line();
    return c;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    for (std::streamsize i = 0; i < n; ++i) overflow(static_cast<unsigned char>(s[i]));
    return n;
  }
  int sync() override {
    flush_line();
    return 0;
  }

 private:
  void flush_line() {
    if (line_.empty()) return;
    server_.event("output", {{"category", "stdout"}, {"output", line_}});
    line_.clear();
  }
  Server& server_;
  std::string line_;
};

class OutputStream : public std::ostream {
 public:
  explicit OutputStream(Server& server) : std::ostream(nullptr), buf_(server) { rdbuf(&buf_); }

 private:
  OutputEvents buf_;
};

bool write_all(int fd, const std::string& bytes) {
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<size_t>(n);
  }
  return true;
}

}  // namespace

Server::Server(int in_fd, int out_fd, std::ostream& log)
    : in_fd_(in_fd),
      out_fd_(out_fd),
      log_(log),
      program_out_(std::make_unique<OutputStream>(*this)),
      debugger_(*program_out_, *program_out_, [](const std::string&) {
        return std::optional<std::string>();  // never asked: the stop handler takes the stops
      }) {
  debugger_.set_stop_handler(this);
  if (::pipe(wake_) != 0) wake_[0] = wake_[1] = -1;
}

Server::~Server() {
  if (reader_.joinable()) {  // run() ended by an exception: wake the reader and wait for it
    const char wake = 1;
    if (::write(wake_[1], &wake, 1) == 1)
      reader_.join();
    else
      reader_.detach();
  }
  for (int fd : wake_)
    if (fd >= 0) ::close(fd);
}

void Server::send(json message) {
  std::lock_guard<std::mutex> lock(write_mutex_);
  message["seq"] = seq_++;
  // A client that went away: its requests end with the input, which ends the session.
  if (!write_all(out_fd_, frame(message.dump(-1, ' ', false, json::error_handler_t::replace))))
    log_ << "simit dap: the client's output is closed\n";
}

void Server::event(const std::string& name, json body) {
  send({{"type", "event"}, {"event", name}, {"body", std::move(body)}});
}

void Server::read_loop() {
  FrameParser parser;
  char buffer[1 << 16];
  bool ok = true;
  while (ok) {
    while (std::optional<std::string> body = parser.next()) incoming(*body);
    if (parser.malformed()) {
      log_ << "simit dap: " << parser.error() << "\n";
      event("output", {{"category", "console"},
                       {"output", "simit dap: malformed input (" + parser.error() +
                                      "); ending the session\n"}});
      break;
    }
    // The input, or the server's own wake-up when it ends first (after a disconnect, with a
    // client that keeps its end open): the thread must not outlive the server.
    pollfd fds[2] = {{in_fd_, POLLIN, 0}, {wake_[0], POLLIN, 0}};
    if (::poll(fds, 2, -1) < 0) {
      ok = errno == EINTR;
      continue;
    }
    if (fds[1].revents) break;
    const ssize_t n = ::read(in_fd_, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;  // end of input (a read error counts as one)
    parser.feed(std::string_view(buffer, static_cast<size_t>(n)));
  }
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    input_closed_ = true;
  }
  queue_cv_.notify_all();
  debugger_.request_service();
}

// One message from the client: answered here when its answer needs nothing of the run
// (threads, pause), else queued for the main thread.
void Server::incoming(const std::string& body) {
  json message = json::parse(body, nullptr, false);
  if (message.is_discarded() || !message.is_object() || message.value("type", "") != "request" ||
      !message.contains("command") || !message["command"].is_string()) {
    send({{"type", "response"},
          {"request_seq",
           message.is_object() && message.contains("seq") && message["seq"].is_number_integer()
               ? message["seq"]
               : json(0)},
          {"success", false},
          {"command", ""},
          {"message", "not a DAP request (a JSON object with type \"request\" and a command)"}});
    return;
  }
  const std::string command = message["command"];
  if (command == "threads") {  // the same answer in every state: no need to wait for a stop
    send({{"type", "response"},
          {"request_seq", message.value("seq", 0)},
          {"success", true},
          {"command", command},
          {"body", {{"threads", json::array({{{"id", 1}, {"name", "simit"}}})}}}});
    return;
  }
  if (command == "pause") {  // answered before the stop it causes is reported
    const bool running = running_.load();
    if (running) debugger_.request_pause();
    send({{"type", "response"},
          {"request_seq", message.value("seq", 0)},
          {"success", running},
          {"command", command},
          {"message", running ? "" : "the program is not running"}});
    return;
  }
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    queue_.push_back(std::move(message));
  }
  queue_cv_.notify_all();
  // A running program takes requests at its next statement.
  debugger_.request_service();
}

bool Server::input_ended() {
  std::lock_guard<std::mutex> lock(queue_mutex_);
  return input_closed_;
}

std::optional<json> Server::take(bool wait) {
  std::unique_lock<std::mutex> lock(queue_mutex_);
  if (wait) queue_cv_.wait(lock, [&] { return !queue_.empty() || input_closed_; });
  if (queue_.empty()) return std::nullopt;
  json request = std::move(queue_.front());
  queue_.pop_front();
  return request;
}

int Server::run() {
  reader_ = std::thread([this] { read_loop(); });
  while (!disconnect_) {
    if (configured_ && !ran_) {
      run_program();
      continue;
    }
    std::optional<json> request = take(true);
    if (!request) break;  // the client's input ended
    handle(*request);
  }
  program_out_->flush();
  // The reader ends with the input, or now, woken, when the session ended first.
  const char wake = 1;
  if (::write(wake_[1], &wake, 1) == 1 || input_ended()) {
    reader_.join();
  } else {  // no way to wake it (no pipe): leave it blocked in read(2) as the process ends
    log_ << "simit dap: cannot wake the reader\n";
    reader_.detach();
  }
  return 0;
}

void Server::stopped(const repl::StopInfo& stop) {
  using Reason = repl::StopInfo::Reason;
  const char* reason = "step";
  switch (stop.reason) {
    case Reason::Breakpoint: reason = "breakpoint"; break;
    case Reason::FunctionBreakpoint: reason = "function breakpoint"; break;
    case Reason::Step: reason = "step"; break;
    case Reason::Pause: reason = "pause"; break;
    case Reason::Watch: reason = "data breakpoint"; break;
    case Reason::Nan: reason = "exception"; break;
    case Reason::Entry: reason = "entry"; break;
  }
  if (end_run_) {  // terminate or disconnect came while it ran: this stop ends the run
    debugger_.kill();
    return;
  }
  json body = {{"reason", reason}, {"threadId", 1}, {"allThreadsStopped", true}};
  if (!stop.text.empty() && stop.reason != Reason::Pause) {
    std::string text = stop.text;
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ' || text.back() == ','))
      text.pop_back();
    body["text"] = text;
    body["description"] = text;
  }
  if (stop.breakpoint) body["hitBreakpointIds"] = json::array({stop.breakpoint});
  resume_ = false;
  variables_.clear();
  event("stopped", body);
  while (!resume_) {
    std::optional<json> request = take(true);
    if (!request) {  // the client is gone: end the run
      debugger_.kill();
      break;
    }
    handle(*request);
  }
  variables_.clear();
}

void Server::service() {
  while (std::optional<json> request = take(false)) handle(*request);
  bool closed = false;
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    closed = input_closed_;
  }
  if (closed) end_run();
}

void Server::end_run() {
  if (debugger_.stopped()) {
    debugger_.kill();
    resume_ = true;
    return;
  }
  end_run_ = true;
  debugger_.request_pause();  // the next statement stops, and that stop ends the run
}

}  // namespace simit::dap
