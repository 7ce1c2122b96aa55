// The public face of the REPL session (simit/repl.h) over Session, with scenes read through
// the scene library.
#include "simit/repl.h"

#include "scene_loader.h"
#include "session.h"

namespace simit::repl {

ReplSession::ReplSession(std::ostream& out, std::ostream& err)
    : session_(std::make_unique<Session>(out, err)) {
  session_->set_scene_loader(load_scene);
}

ReplSession::~ReplSession() = default;

bool ReplSession::feed_line(const std::string& line) { return session_->feed_line(line); }
bool ReplSession::pending() const { return session_->pending(); }
void ReplSession::cancel_pending() { session_->cancel_pending(); }

std::vector<std::string> ReplSession::completions(const std::string& prefix) const {
  return session_->completions(prefix);
}

void ReplSession::set_line_source(LineSource source) {
  session_->set_line_source(std::move(source));
}

void ReplSession::interrupt() { session_->interrupt(); }

}  // namespace simit::repl
