// Programs: loading and checking source, diagnostics, and compiling functions.
#include <fstream>
#include <optional>
#include <sstream>

#include "api/compiled_program.h"
#include "frontend/diagnostics.h"
#include "frontend/frontend.h"
#include "simit/program.h"

namespace simit {

namespace ast = frontend::ast;

Options init(const std::string& backend, int float_size) {
  Options o;
  std::string error;
  if (backend == "cpu")  // the original's name of its JIT-compiled native code
    o.executor.kind = ExecutorKind::Jit;
  else if (std::optional<ExecutorKind> kind = parse_executor_kind(backend, error))
    o.executor.kind = *kind;
  else
    throw Error(error + " (or cpu, the JIT)");
  if (std::string bad = executor_unavailable(o.executor); !bad.empty()) throw Error(bad);
  if (float_size != 4 && float_size != 8)
    throw Error("float size must be 4 or 8, not " + std::to_string(float_size));
  o.float_size = float_size;
  return o;
}

BindError::BindError(std::vector<std::string> problems)
    : Error([&] {
        std::string text;
        for (size_t i = 0; i < problems.size(); ++i) text += (i ? "\n" : "") + problems[i];
        return text;
      }()),
      problems_(std::move(problems)) {}

namespace {

std::vector<Diagnostic> convert(const frontend::Diagnostics& diags) {
  std::vector<Diagnostic> out;
  for (const frontend::Diagnostic& d : diags.items()) {
    frontend::LineCol at = d.span.start();
    out.push_back(Diagnostic{at.line, at.column, frontend::category_name(d), d.message,
                             frontend::Diagnostics::render(d)});
  }
  return out;
}

std::string render(const std::vector<Diagnostic>& diags) {
  std::string text;
  for (const Diagnostic& d : diags) text += d.rendered;
  return text;
}

}  // namespace

Program::Program(Options options) : options_(std::move(options)) {
  if (options_.float_size != 4 && options_.float_size != 8)
    throw Error("float size must be 4 or 8, not " + std::to_string(options_.float_size));
}
Program::~Program() = default;
Program::Program(Program&&) noexcept = default;
Program& Program::operator=(Program&&) noexcept = default;

// Compiles `text` (or the file `name` when text is null); 0 ok, 1 errors, 2 unreadable.
int Program::load(const std::string& name, const std::string* text) {
  std::string contents;
  if (!text) {
    std::ifstream in(name, std::ios::binary);
    if (!in) {
      diagnostics_ = {Diagnostic{0, 0, "io", "cannot read '" + name + "'",
                                 name + ": error: cannot read file\n"}};
      loaded_.reset();
      return 2;
    }
    std::stringstream ss;
    ss << in.rdbuf();
    contents = ss.str();
    text = &contents;
  }
  std::shared_ptr<const api::CompiledProgram> loaded =
      api::CompiledProgram::from_source(name, *text);
  diagnostics_ = convert(loaded->compilation()->diagnostics);
  if (!loaded->ok()) {
    loaded_.reset();
    return 1;
  }
  loaded_ = std::move(loaded);
  return 0;
}

void Program::load_string(const std::string& source, const std::string& name) {
  if (load(name, &source) != 0) throw CompileError(diagnostics_text(), diagnostics_);
}

void Program::load_file(const std::string& path) {
  if (load(path, nullptr) != 0) throw CompileError(diagnostics_text(), diagnostics_);
}

int Program::loadString(const std::string& source) { return load("<string>", &source); }
int Program::loadFile(const std::string& path) { return load(path, nullptr); }

bool Program::loaded() const { return loaded_ != nullptr; }

std::string Program::diagnostics_text() const { return render(diagnostics_); }

std::vector<std::string> Program::function_names() const {
  std::vector<std::string> names;
  if (!loaded_) return names;
  for (const auto& d : loaded_->program().decls)
    if (const auto* f = d->as<ast::FuncDecl>(); f && f->exported) names.push_back(f->name);
  return names;
}

}  // namespace simit
