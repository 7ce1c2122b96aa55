// `launch` and the run: a scene (init and its frames, writing nothing) or one exported
// function of a .sim file with literal arguments, under the step debugger, as `simit debug`
// runs them; its end reported as the protocol's `exited` and `terminated` events.
#include <filesystem>
#include <sstream>

#include "api/compiled_program.h"
#include "commands/run_command.h"
#include "dap/server.h"
#include "scene/scene_sets.h"
#include "simit/scene.h"

namespace simit::dap {

namespace {

namespace fs = std::filesystem;

std::string absolute(const std::string& path, const std::string& cwd) {
  fs::path p(path);
  if (p.is_relative() && !cwd.empty()) p = fs::path(cwd) / p;
  std::error_code ec;
  fs::path c = fs::weakly_canonical(fs::absolute(p), ec);
  return ec ? fs::absolute(p).string() : c.string();
}

}  // namespace

bool Server::open_program(const json& args, std::string& why) {
  const std::string cwd = args.value("cwd", "");
  const std::string program = args.value("program", "");
  if (program.empty()) {
    why = "launch needs 'program': a scene (.toml) or a Simit file (.sim)";
    return false;
  }
  program_file_ = absolute(program, cwd);
  if (!fs::exists(program_file_)) {
    why = "no such file: " + program_file_;
    return false;
  }
  float32_ = args.value("float32", false);
  frames_ = args.value("frames", -1);
  std::ostringstream errors;
  if (program_file_.ends_with(".toml")) {
    scene::SceneOptions o;
    o.file = program_file_;
    o.float32 = float32_;
    o.quiet = true;
    o.finite_check = false;  // the exception filter `nan` is the debugger's way to find one
    scene_ = scene::SceneAccess::open(o, &debugger_.trap(), errors);
    if (!scene_) {
      why = errors.str();
      return false;
    }
    source_path_ = absolute(scene_->program_path(), "");
    debugger_.set_program(&scene::SceneAccess::program(*scene_),
                          {{1, fs::path(source_path_).filename().string(), 1}});
    return true;
  }
  function_ = args.value("function", "");
  if (function_.empty()) {
    why = "launch of a .sim file needs 'function': the exported function to call";
    return false;
  }
  for (const json& a : args.value("args", json::array()))
    args_.push_back(a.is_string() ? a.get<std::string>() : a.dump());
  compiled_ = api::CompiledProgram::from_file(program_file_);
  if (!compiled_->ok()) {
    why = compiled_->compilation()->diagnostics.render_all();
    return false;
  }
  source_path_ = program_file_;
  debugger_.set_program(&compiled_->program(),
                        {{1, fs::path(source_path_).filename().string(), 1}});
  return true;
}

void Server::on_launch(const json& request) {
  if (launched_) return fail(request, "the session has launched its program already");
  std::string why;
  if (!open_program(request["arguments"], why)) {
    while (!why.empty() && why.back() == '\n') why.pop_back();
    return fail(request, why);
  }
  if (request["arguments"].value("stopOnEntry", false)) debugger_.stop_at_entry();
  launched_ = true;
  respond(request);
  event("initialized");
}

void Server::run_program() {
  running_ = true;
  std::ostringstream errors;
  int rc = 0;
  debugger_.begin_run();
  try {
    if (scene_) {
      rc = scene_->run(*program_out_, errors, frames_);
    } else {
      tools::RunOptions ro;
      ro.file = program_file_;
      ro.func = function_;
      ro.args = args_;
      ro.float32 = float32_;
      rc = tools::run_function(ro, tools::RunHooks{&debugger_.trap(), compiled_}, *program_out_,
                               errors);
    }
  } catch (const std::exception& e) {
    errors << "simit dap: internal error: " << e.what() << "\n";
    rc = 1;
  }
  const bool killed = debugger_.end_run();
  program_out_->flush();
  running_ = false;
  ran_ = true;
  if (!killed && !errors.str().empty()) {
    event("output", {{"category", "stderr"}, {"output", errors.str()}});
    if (!disconnect_) stop_on_error(errors.str());
  }
  event("exited", {{"exitCode", killed ? 0 : rc}});
  event("terminated");
}

// A run-time error ends the run where it happened: the client sees it as a stop on an
// exception, with the message and one frame at the error's line, until it goes on.
void Server::stop_on_error(const std::string& message) {
  ErrorStop stop;
  stop.message = message;
  while (!stop.message.empty() && stop.message.back() == '\n') stop.message.pop_back();
  // "FILE:LINE:COL: runtime error: ..." on the first line, the calls after it.
  const std::string first = stop.message.substr(0, stop.message.find('\n'));
  if (size_t at = first.find(": runtime error"); at != std::string::npos) {
    const std::string where = first.substr(0, at);
    const size_t c2 = where.rfind(':');
    const size_t c1 =
        c2 == std::string::npos || c2 == 0 ? std::string::npos : where.rfind(':', c2 - 1);
    if (c1 != std::string::npos) {
      stop.line = std::atoi(where.substr(c1 + 1, c2 - c1 - 1).c_str());
      stop.column = std::atoi(where.substr(c2 + 1).c_str());
      stop.function = "runtime error";
      if (size_t in = stop.message.find("\n  in "); in != std::string::npos) {
        const std::string call = stop.message.substr(in + 6);
        stop.function = call.substr(0, call.find(' '));
      }
    }
  }
  error_stop_ = stop;
  resume_ = false;
  event("stopped", {{"reason", "exception"},
                    {"threadId", 1},
                    {"allThreadsStopped", true},
                    {"description", first},
                    {"text", stop.message}});
  while (!resume_ && !disconnect_) {
    std::optional<json> request = take(true);
    if (!request) break;
    handle(*request);
  }
  error_stop_.reset();
}

}  // namespace simit::dap
