// The REPL session: inputs, their compilation inside a wrapper function, and runs that keep
// variables and scene data between inputs. See session.h.
#include "session.h"

#include <algorithm>
#include <chrono>
#include <fstream>
#include <sstream>

#include "frontend/ast.h"
#include "frontend/types.h"
#include "input_text.h"
#include "interp/printing.h"
#include "interp/runtime_error.h"

namespace simit::repl {

namespace ast = frontend::ast;

Session::Session(std::ostream& out, std::ostream& err)
    : out_(out),
      err_(err),
      debugger_(out, err, [this](const std::string& prompt) -> std::optional<std::string> {
        if (!line_source_) return std::nullopt;
        return line_source_(prompt);
      }) {
  refresh_program();
}
Session::~Session() = default;

bool Session::is_complete(const std::string& text) {
  int brackets = 0;
  std::vector<std::string> w = words(text, brackets);
  int depth = 0;
  for (size_t i = 0; i < w.size(); ++i) {
    const std::string& x = w[i];
    if (x == "func" || x == "proc") {
      if (i == 0 || w[i - 1] != "extern") ++depth;
    } else if (x == "if" || x == "for" || x == "while" || x == "element") {
      ++depth;
    } else if (x == "end") {
      --depth;
    }
  }
  return depth <= 0 && brackets <= 0;
}

bool Session::feed_line(const std::string& line) {
  if (quit_) return false;
  // Blank lines and comments alone are not inputs.
  if (buffer_.empty() && (trim(line).empty() || trim(line)[0] == '%')) return true;
  if (buffer_.empty() && trim(line)[0] == ':') {
    command(trim(line));
    return !quit_;
  }
  buffer_ += line;
  buffer_ += "\n";
  if (!is_complete(buffer_)) return true;
  std::string input = buffer_;
  buffer_.clear();
  handle(input);
  return !quit_;
}

void Session::handle(const std::string& input) {
  static const char* const kDecl[] = {"element", "extern", "func", "export", "const", "proc"};
  std::string w = first_word(input);
  if (std::find(std::begin(kDecl), std::end(kDecl), w) != std::end(kDecl)) {
    declarations(input);
    return;
  }
  std::string t = trim(input);
  bool expression = !t.empty() && t.back() != ';' && !(t.size() >= 3 && t.ends_with("end"));
  // `x = 2.0` typed without its `;` is meant as an assignment, not as an expression.
  if (expression && has_top_level_assignment(t)) {
    statements(input + ";", false, false);
    return;
  }
  statements(input, expression, false);
}

std::string Session::program_text() const {
  std::string text;
  for (const auto& f : file_texts_) text += f + "\n";
  return text + decls_;
}

std::unique_ptr<frontend::Compilation> Session::compile(const std::string& prefix,
                                                        const std::string& input,
                                                        const std::string& suffix,
                                                        int& input_offset) {
  std::string text = program_text() + "\n" + prefix;
  input_offset = static_cast<int>(text.size());
  text += input + "\n" + suffix;
  return frontend::compile_source("<repl>", std::move(text));
}

// Where the lines of a compiled text come from: each loaded file, the declarations typed
// at the prompt (`<declarations>`), and the current input (`<repl>`). The wrapper around
// the input has no line of its own: it counts as the input's first line.
std::vector<LineSegment> Session::segments(const frontend::SourceFile& file,
                                           int input_offset) const {
  auto line_of = [&](size_t offset) { return file.locate(static_cast<uint32_t>(offset)).line; };
  std::vector<LineSegment> out;
  size_t begin = 0;
  for (size_t k = 0; k < file_texts_.size(); ++k) {
    out.push_back({line_of(begin), files_[k], 1});
    begin += file_texts_[k].size() + 1;
  }
  if (!decls_.empty()) out.push_back({line_of(begin), "<declarations>", 1});
  if (input_offset >= 0 && static_cast<size_t>(input_offset) <= file.text().size()) {
    const int first = line_of(input_offset);
    const int header = line_of(begin + decls_.size());
    out.push_back({header, "<repl>", 1 - (first - header)});  // shown as line 1
    out.push_back({first, "<repl>", 1});
  }
  return out;
}

// A place in the compiled text, in the user's terms: `file:line:col`.
std::string Session::location(const frontend::SourceSpan& span, int input_offset) const {
  if (!span.valid()) return "";
  frontend::LineCol lc = span.start();
  LineMap::Place p = LineMap(segments(*span.file, input_offset)).place(lc.line);
  return p.file + ":" + std::to_string(std::max(1, p.line)) + ":" + std::to_string(lc.column);
}

// Diagnostics inside the input are shown with the input's own line numbers.
void Session::report(const frontend::Compilation& c, int input_offset) {
  for (const auto& d : c.diagnostics.items()) {
    if (!d.span.valid() || d.span.begin < static_cast<uint32_t>(input_offset))
      err_ << frontend::Diagnostics::render(d);
    else
      err_ << frontend::Diagnostics::render(d, location(d.span, input_offset));
  }
}

void Session::report_runtime(const interp::RuntimeError& e, int input_offset) {
  std::string where = location(e.where(), input_offset);
  err_ << (where.empty() ? "" : where + ": ") << "runtime error: " << e.message() << "\n";
  for (const auto& f : e.stack()) {
    // The wrapper function around the input is the input itself.
    err_ << "  in " << (f.func.starts_with("__repl_") ? std::string("<input>") : f.func);
    if (f.at.valid()) {
      std::string at = location(f.at, input_offset);
      err_ << " (" << at.substr(0, at.rfind(':')) << ")";
    }
    err_ << "\n";
  }
}

void Session::declarations(const std::string& input) {
  int offset = 0;
  auto c = compile("", input, "", offset);
  if (!c->ok()) {
    report(*c, offset);
    return;
  }
  decls_ += input;
  refresh_program();
  names_.clear();
  for (const auto& d : c->program->decls) {
    if (auto* f = dynamic_cast<const ast::FuncDecl*>(d.get())) names_.push_back(f->name);
    if (auto* e = dynamic_cast<const ast::ElementDecl*>(d.get())) names_.push_back(e->name);
    if (auto* e = dynamic_cast<const ast::ExternDecl*>(d.get())) names_.push_back(e->name);
    if (auto* e = dynamic_cast<const ast::ConstDecl*>(d.get())) names_.push_back(e->decl->name);
  }
}

api::EngineOptions Session::run_options() {
  api::EngineOptions o;
  o.out = &out_;
  o.float32 = options_.float32;
  o.check_finite = options_.check_finite;
  o.trap = &debugger_.trap();
  o.executor = options_.executor;  // checked by :set
  return o;
}

void Session::refresh_program() {
  int offset = 0;
  program_ = compile("", "", "", offset);
  restore_program();
}

void Session::restore_program() {
  if (program_ && program_->ok())
    debugger_.set_program(program_->program.get(), segments(*program_->source, -1));
  else
    debugger_.set_program(nullptr);
}

bool Session::debug_run(const frontend::Compilation& c, int input_offset,
                        const std::function<void()>& body) {
  debugger_.set_program(c.program.get(), segments(*c.source, input_offset));
  debugger_.begin_run();
  bool completed = true;
  try {
    body();
  } catch (const interp::Interrupted& e) {
    completed = false;
    if (!debugger_.end_run()) {
      err_ << "interrupted at " << location(e.where(), input_offset)
           << " (what ran so far stays done)\n";
    }
    restore_program();
    return false;
  } catch (const interp::RuntimeError& e) {
    completed = false;
    if (!debugger_.end_run()) report_runtime(e, input_offset);
    restore_program();
    return false;
  }
  debugger_.end_run();
  restore_program();
  return completed;
}

// The scene's sets and tensors go to the externs of the same names the program declares.
void Session::bind_scene(api::Engine& in, const ast::Program& program) {
  if (!scene_) return;
  for (const ast::Variable* g : program.globals) {
    if (g->kind != ast::Variable::Kind::Extern) continue;
    for (auto& [name, set] : scene_->sets)
      if (name == g->name) in.bind_set(*g, *set);
  }
  bind_scene_tensors(in, program);
}

void Session::bind_scene_tensors(api::Engine& in, const ast::Program& program) {
  if (!scene_) return;
  for (const ast::Variable* g : program.globals)
    for (auto& [name, value] : scene_->tensors)
      if (g->kind == ast::Variable::Kind::Extern && name == g->name) in.set_global(*g, value);
}

void Session::keep_scene_tensors(const api::Engine& in, const ast::Program& program) {
  if (!scene_) return;
  for (const ast::Variable* g : program.globals)
    for (auto& [name, value] : scene_->tensors)
      if (g->kind == ast::Variable::Kind::Extern && name == g->name) value = in.global(*g);
}

void Session::statements(const std::string& input, bool expression, bool type_only) {
  std::string name = "__repl_" + std::to_string(++counter_);
  std::string params, results, init;
  for (const auto& [n, v] : vars_) {
    params += (params.empty() ? "" : ", ") + ("__in_" + n) + " : " + v.type;
    results += (results.empty() ? "" : ", ") + n + " : " + v.type;
    init += n + " = __in_" + n + "; ";
  }
  auto header = [&](const std::string& extra) {
    std::string r = results;
    if (!extra.empty()) r += (r.empty() ? "" : ", ") + extra;
    return "func " + name + "(" + params + ")" + (r.empty() ? "" : " -> (" + r + ")") + "\n" +
           init + (expression ? "__it =" : "") + "\n";
  };
  std::string close = expression ? ";\n" : "";
  int offset = 0;
  auto first = compile(header(""), input, close + "end\n", offset);
  if (!first->ok()) {
    report(*first, offset);
    return;
  }
  // The variables the input declares at its top level, with their types.
  std::vector<std::pair<std::string, std::string>> fresh;
  const ast::FuncDecl* f = first->program->find_func(name);
  for (const auto& s : f->body) {
    std::vector<const ast::Variable*> declared;
    if (auto* d = dynamic_cast<const ast::VarDecl*>(s.get())) declared.push_back(d->var);
    if (auto* a = dynamic_cast<const ast::Assign*>(s.get()))
      for (const ast::Variable* v : a->declares) declared.push_back(v);
    for (const ast::Variable* v : declared)
      if (v && v->type) fresh.emplace_back(v->name, frontend::to_string(*v->type));
  }
  if (type_only) {
    for (const auto& [n, t] : fresh)
      if (n == "__it") out_ << t << "\n";
    return;
  }
  std::string extra, copy;
  for (const auto& [n, t] : fresh) {
    extra += (extra.empty() ? "" : ", ") + ("__out_" + n) + " : " + t;
    copy += "__out_" + n + " = " + n + "; ";
  }
  auto second = compile(header(extra), input, close + copy + "\nend\n", offset);
  if (!second->ok()) {
    report(*second, offset);
    return;
  }
  std::vector<interp::Value> res;
  bool ran = debug_run(*second, offset, [&] {
    api::Engine in(*second->program, run_options());
    bind_scene(in, *second->program);
    std::vector<interp::Value> args;
    for (const auto& [n, v] : vars_) args.push_back(v.value);
    res = in.call(*second->program->find_func(name), std::move(args));
    keep_scene_tensors(in, *second->program);
  });
  if (ran) {
    size_t i = 0;
    for (auto& [n, v] : vars_) v.value = res[i++];
    for (const auto& [n, t] : fresh) {
      interp::Value value = res[i++];
      if (n == "__it") {
        bool column = t.empty() || t.back() != '\'';
        out_ << interp::literal_text(value, column) << " : " << t << "\n";
      } else {
        vars_[n] = Var{t, value};
      }
    }
  }
}

void Session::run_function(const frontend::Compilation& c, const std::string& name, int times) {
  const ast::FuncDecl* f = c.program->find_func(name);
  if (!f) {
    err_ << ":run: no function '" << name << "'\n";
    return;
  }
  if (!f->params.empty()) {
    err_ << ":run: '" << name << "' takes parameters; call it in a statement instead\n";
    return;
  }
  using Clock = std::chrono::steady_clock;
  std::unique_ptr<api::Engine>& in = run_.engine;
  for (int k = 1; k <= times; ++k) {
    std::vector<interp::Value> res;
    const auto t0 = Clock::now();
    bool ran = debug_run(c, -1, [&] {
      if (!in) {
        in = std::make_unique<api::Engine>(*c.program, run_options());
        bind_scene(*in, *c.program);
      } else if (k == 1) {
        bind_scene_tensors(*in, *c.program);  // statements at the prompt may have set them
      }
      try {
        res = in->call(*f, {});
      } catch (...) {
        keep_scene_tensors(*in, *c.program);
        throw;
      }
      keep_scene_tensors(*in, *c.program);
    });
    if (!ran) {
      in.reset();
      if (times > 1) err_ << ":run: stopped in run " << k << " of " << times << "\n";
      return;
    }
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    std::ostringstream line;
    line.precision(1);
    if (times > 1) line << "[" << k << "/" << times << "] ";
    line << name << ": " << std::fixed << ms << " ms" << std::defaultfloat;
    for (size_t r = 0; r < f->results.size() && r < res.size(); ++r)
      line << ", " << f->results[r].name << " = " << interp::literal_text(res[r], false);
    out_ << line.str() << "\n" << std::flush;
  }
}

bool Session::load(const std::string& path, std::string& text) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    err_ << "cannot read '" << path << "'\n";
    return false;
  }
  std::stringstream ss;
  ss << in.rdbuf();
  text = ss.str();
  auto alone = frontend::compile_source(path, text);
  if (!alone->ok()) {
    err_ << alone->diagnostics.render_all();
    return false;
  }
  return true;
}

}  // namespace simit::repl
