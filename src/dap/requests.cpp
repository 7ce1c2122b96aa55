// The DAP requests: each checked against the session's state and answered through the step
// debugger's structured interface (repl/debugger.h).
#include <filesystem>

#include "dap/server.h"

namespace simit::dap {

namespace {

namespace fs = std::filesystem;

std::string canonical(const std::string& path) {
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(path), ec);
  return ec ? path : p.string();
}

// Frame ids are levels + 1 (0 is not an id); scopes' references are made per request.
int level_of(const json& args) {
  const int id = args.value("frameId", 1);
  return id > 0 ? id - 1 : 0;
}

// "verts[4 3 7 16]" from "map tet_force to tets, element 17, endpoints verts[4 3 7 16] (...)".
std::string endpoints_of(const std::string& map) {
  const size_t at = map.find(", endpoints ");
  if (at == std::string::npos) return "";
  std::string rest = map.substr(at + 12);
  if (size_t paren = rest.rfind(" ("); paren != std::string::npos) rest = rest.substr(0, paren);
  return rest;
}

// The protocol's breakpoints (SourceBreakpoint, FunctionBreakpoint, DataBreakpoint) as the
// debugger's requests of `kind`: each names its place by its own key.
std::vector<repl::BreakpointRequest> breakpoint_requests(const json& list,
                                                         repl::BreakpointRequest::Kind kind) {
  std::vector<repl::BreakpointRequest> out;
  for (const json& b : list) {
    repl::BreakpointRequest r;
    r.kind = kind;
    r.line = b.value("line", 0);
    r.function = b.value("name", "");
    r.watch = b.value("dataId", "");
    r.condition = b.value("condition", "");
    r.hit_condition = b.value("hitCondition", "");
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace

void Server::respond(const json& request, json body) {
  send({{"type", "response"},
        {"request_seq", request.value("seq", 0)},
        {"success", true},
        {"command", request.value("command", "")},
        {"body", std::move(body)}});
}

void Server::fail(const json& request, const std::string& message) {
  send({{"type", "response"},
        {"request_seq", request.value("seq", 0)},
        {"success", false},
        {"command", request.value("command", "")},
        {"message", message},
        {"body", {{"error", {{"id", 1}, {"format", message}}}}}});
}

void Server::handle(const json& request) {
  const std::string command = request.value("command", "");
  const json args = request.contains("arguments") && request["arguments"].is_object()
                        ? request["arguments"]
                        : json::object();
  try {
    if (command == "initialize") {
      initialised_ = true;
      respond(request, {{"supportsConfigurationDoneRequest", true},
                        {"supportsFunctionBreakpoints", true},
                        {"supportsConditionalBreakpoints", true},
                        {"supportsHitConditionalBreakpoints", true},
                        {"supportsEvaluateForHovers", true},
                        {"supportsDataBreakpoints", true},
                        {"supportsTerminateRequest", true},
                        {"exceptionBreakpointFilters",
                         json::array({{{"filter", "nan"},
                                       {"label", "NaN or infinity"},
                                       {"description",
                                        "Stop after the first statement that writes a NaN or an "
                                        "infinity"},
                                       {"default", false}}})}});
      return;
    }
    if (!initialised_) return fail(request, "'" + command + "' before 'initialize'");
    if (command == "launch") return on_launch(request);
    if (command == "disconnect" || command == "terminate") {
      if (command == "disconnect") disconnect_ = true;
      if (running_) end_run();
      respond(request);
      return;
    }
    if (command == "configurationDone") {
      if (!launched_) return fail(request, "configurationDone before launch");
      respond(request);
      configured_ = true;
      return;
    }
    if (!launched_ && command != "setExceptionBreakpoints")
      return fail(request, "'" + command + "' before 'launch'");
    if (command == "setBreakpoints") return on_set_breakpoints(request);
    if (command == "setFunctionBreakpoints") return on_set_function_breakpoints(request);
    if (command == "setExceptionBreakpoints") return on_set_exception_breakpoints(request);
    if (command == "dataBreakpointInfo") return on_data_breakpoint_info(request);
    if (command == "setDataBreakpoints") return on_set_data_breakpoints(request);
    if (error_stop_) return on_error_stop(request);
    const bool stopped = debugger_.stopped();
    const bool needs_stop = command == "stackTrace" || command == "scopes" ||
                            command == "variables" || command == "continue" || command == "next" ||
                            command == "stepIn" || command == "stepOut";
    if (needs_stop && !stopped)
      return fail(request, running_ ? "the program is running (pause it first)"
                                    : "the program is not running");
    if (command == "stackTrace") return on_stack_trace(request);
    if (command == "scopes") return on_scopes(request);
    if (command == "variables") return on_variables(request);
    if (command == "evaluate") return on_evaluate(request);
    using Resume = repl::Debugger::Resume;
    if (command == "continue") return on_resume(request, Resume::Continue);
    if (command == "next") return on_resume(request, Resume::StepOver);
    if (command == "stepIn") return on_resume(request, Resume::StepIn);
    if (command == "stepOut") return on_resume(request, Resume::StepOut);
    (void)args;
    fail(request, "unknown request '" + command + "'");
  } catch (const json::exception& e) {  // an argument of the wrong type
    fail(request, "'" + command + "': bad arguments: " + e.what());
  }
}

json Server::replace_breakpoints(std::vector<int>& numbers,
                                 const std::vector<repl::BreakpointRequest>& requests) {
  for (int n : numbers) debugger_.delete_breakpoint(n);
  numbers.clear();
  json list = json::array();
  for (const repl::BreakpointRequest& r : requests) {
    repl::BreakpointResult b = debugger_.add_breakpoint(r);
    json out = {{"verified", b.verified}};
    if (b.verified) {
      numbers.push_back(b.number);
      out["id"] = b.number;
      if (b.line) out["line"] = b.line;
    } else {
      out["message"] = b.message;
    }
    list.push_back(out);
  }
  return list;
}

void Server::on_set_breakpoints(const json& request) {
  const json& args = request["arguments"];
  const std::string path = args.contains("source") ? args["source"].value("path", "") : "";
  const json lines = args.value("breakpoints", json::array());
  const bool ours = !path.empty() && canonical(path) == source_path_;
  json list = json::array();
  if (!ours) {
    for (size_t i = 0; i < lines.size(); ++i)
      list.push_back(
          {{"verified", false},
           {"message", "'" + path + "' is not the program's source (" + source_path_ + ")"}});
    return respond(request, {{"breakpoints", list}});
  }
  respond(request,
          {{"breakpoints",
            replace_breakpoints(line_breakpoints_,
                                breakpoint_requests(lines, repl::BreakpointRequest::Kind::Line))}});
}

void Server::on_set_function_breakpoints(const json& request) {
  const json list = request["arguments"].value("breakpoints", json::array());
  respond(
      request,
      {{"breakpoints",
        replace_breakpoints(function_breakpoints_,
                            breakpoint_requests(list, repl::BreakpointRequest::Kind::Function))}});
}

void Server::on_set_exception_breakpoints(const json& request) {
  bool nan = false;
  for (const json& f : request["arguments"].value("filters", json::array()))
    if (f.is_string() && f == "nan") nan = true;
  if (nan_breakpoint_ && !nan) {
    debugger_.delete_breakpoint(*nan_breakpoint_);
    nan_breakpoint_.reset();
  }
  if (nan && !nan_breakpoint_) {
    repl::BreakpointRequest r;
    r.kind = repl::BreakpointRequest::Kind::Nan;
    nan_breakpoint_ = debugger_.add_breakpoint(r).number;
  }
  respond(request, {{"breakpoints", nan ? json::array({{{"verified", true}}}) : json::array()}});
}

void Server::on_data_breakpoint_info(const json& request) {
  const std::string name = request["arguments"].value("name", "");
  // Only a field of one element can be watched: SET.FIELD[i].
  const bool watchable = name.find('.') != std::string::npos && name.ends_with("]") &&
                         name.find('[') != std::string::npos;
  if (!watchable)
    return respond(request, {{"dataId", nullptr},
                             {"description",
                              "only a field of one element, SET.FIELD[i], can "
                              "be watched"}});
  respond(request, {{"dataId", name}, {"description", name}, {"accessTypes", {"write"}}});
}

void Server::on_set_data_breakpoints(const json& request) {
  const json list = request["arguments"].value("breakpoints", json::array());
  respond(request,
          {{"breakpoints",
            replace_breakpoints(data_breakpoints_,
                                breakpoint_requests(list, repl::BreakpointRequest::Kind::Watch))}});
}

// The requests a client makes at the stop after a run-time error: one frame, no variables.
void Server::on_error_stop(const json& request) {
  const std::string command = request.value("command", "");
  if (command == "stackTrace") {
    json frame = {{"id", 1},
                  {"name", error_stop_->function.empty() ? "runtime error" : error_stop_->function},
                  {"line", error_stop_->line},
                  {"column", error_stop_->column}};
    if (error_stop_->line > 0)
      frame["source"] = {{"name", fs::path(source_path_).filename().string()},
                         {"path", source_path_}};
    return respond(request, {{"stackFrames", json::array({frame})}, {"totalFrames", 1}});
  }
  if (command == "scopes") return respond(request, {{"scopes", json::array()}});
  if (command == "exceptionInfo")
    return respond(request, {{"exceptionId", "runtime error"},
                             {"description", error_stop_->message},
                             {"breakMode", "always"}});
  if (command == "continue" || command == "next" || command == "stepIn" || command == "stepOut") {
    respond(request, {{"allThreadsContinued", true}});
    resume_ = true;
    return;
  }
  fail(request, "the run has ended with a run-time error: " +
                    error_stop_->message.substr(0, error_stop_->message.find('\n')));
}

void Server::on_stack_trace(const json& request) {
  const std::vector<repl::FrameInfo> frames = debugger_.frames();
  json list = json::array();
  for (size_t i = 0; i < frames.size(); ++i) {
    const repl::FrameInfo& f = frames[i];
    std::string name = f.function;
    if (!f.element.empty()) {
      const std::string ends = endpoints_of(f.map);
      name += " (" + f.element + (ends.empty() ? "" : ", endpoints " + ends) + ")";
    }
    json frame = {
        {"id", i + 1},
        {"name", name},
        {"line", f.line},
        {"column", f.column},
        {"source", {{"name", fs::path(source_path_).filename().string()}, {"path", source_path_}}}};
    list.push_back(frame);
  }
  respond(request, {{"stackFrames", list}, {"totalFrames", list.size()}});
}

void Server::on_scopes(const json& request) {
  const int level = level_of(request["arguments"]);
  std::vector<repl::VariableInfo> globals, sets;
  for (const repl::VariableInfo& g : debugger_.globals()) {
    const bool is_set = g.value && g.value->kind() == interp::Value::Kind::Set;
    (is_set ? sets : globals).push_back(g);
  }
  const std::vector<repl::VariableInfo> locals = debugger_.locals(level);
  auto scope = [&](const char* name, const std::vector<repl::VariableInfo>& vars, bool expensive) {
    return json{{"name", name},
                {"variablesReference", variables_.add_scope(vars)},
                {"namedVariables", vars.size()},
                {"expensive", expensive},
                {"presentationHint", std::string(name) == "Locals" ? "locals" : ""}};
  };
  respond(request,
          {{"scopes", json::array({scope("Locals", locals, false), scope("Globals", globals, false),
                                   scope("Sets", sets, true)})}});
}

void Server::on_variables(const json& request) {
  const json& args = request["arguments"];
  std::optional<json> list =
      variables_.children(args.value("variablesReference", int64_t{0}),
                          args.value("start", int64_t{0}), args.value("count", int64_t{0}));
  if (!list) return fail(request, "no such variables reference (they last until the run goes on)");
  respond(request, {{"variables", *list}});
}

void Server::on_evaluate(const json& request) {
  const json& args = request["arguments"];
  const std::string text = args.value("expression", "");
  if (!debugger_.stopped())
    return fail(request, running_ ? "the program is running (pause it first)"
                                  : "the program is not running: expressions need a stop");
  std::string why;
  const int level = level_of(args);
  std::optional<repl::Debugger::Evaluated> e = debugger_.evaluate_value(text, level, why);
  if (!e) return fail(request, why);
  json v = variables_.variable(text, &e->value, nullptr);
  respond(request, {{"result", e->text}, {"variablesReference", v["variablesReference"]}});
}

void Server::on_resume(const json& request, repl::Debugger::Resume how) {
  std::string why;
  if (!debugger_.resume(how, level_of(request.value("arguments", json::object())), why))
    return fail(request, why);
  respond(request, {{"allThreadsContinued", true}});
  resume_ = true;
}

}  // namespace simit::dap
