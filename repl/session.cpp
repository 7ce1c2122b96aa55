// The REPL session: see session.h.
#include "session.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>

#include "frontend/ast.h"
#include "frontend/types.h"
#include "interp/interpreter.h"
#include "interp/printing.h"
#include "interp/runtime_error.h"

namespace simit::repl {
namespace {

namespace ast = frontend::ast;

const char* const kCommands[] = {"help", "load", "reload", "type", "reset", "quit"};

const char* const kIntrinsics[] = {"abs", "sqrt", "sin", "cos", "tan", "asin", "acos", "atan2",
                                   "exp", "log", "pow", "norm", "dot", "cross", "det", "inv",
                                   "solve", "trace", "print", "println"};

std::string trim(const std::string& s) {
  size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  size_t e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

// The words of `text` outside comments and strings, and the bracket depth at its end.
std::vector<std::string> words(const std::string& text, int& brackets) {
  std::vector<std::string> out;
  brackets = 0;
  for (size_t i = 0; i < text.size();) {
    char c = text[i];
    if (c == '%') {
      while (i < text.size() && text[i] != '\n') ++i;
    } else if (c == '"') {
      ++i;
      while (i < text.size() && text[i] != '"') i += text[i] == '\\' ? 2 : 1;
      ++i;
    } else if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
      size_t b = i;
      while (i < text.size() && (std::isalnum(static_cast<unsigned char>(text[i])) || text[i] == '_'))
        ++i;
      out.push_back(text.substr(b, i - b));
    } else {
      if (c == '(' || c == '[' || c == '{') ++brackets;
      if (c == ')' || c == ']' || c == '}') --brackets;
      ++i;
    }
  }
  return out;
}

std::string first_word(const std::string& text) {
  int b = 0;
  std::vector<std::string> w = words(text, b);
  return w.empty() ? "" : w[0];
}

const char* kHelp =
    "Enter declarations (element, extern, func, const) or statements; an expression without a\n"
    "trailing ';' prints its value and type. Variables assigned at the prompt persist.\n"
    "Commands (unambiguous prefixes work):\n"
    "  :help [topic]   this text, or help on a command\n"
    "  :load FILE.sim  add the declarations of a file\n"
    "  :reload         read the loaded files again\n"
    "  :type EXPR      the type of an expression\n"
    "  :reset          forget every declaration and variable\n"
    "  :quit           leave (Ctrl-D too)\n";

}  // namespace

Session::Session(std::ostream& out, std::ostream& err) : out_(out), err_(err) {}
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
  if (buffer_.empty() && trim(line).empty()) return true;
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

namespace {
// True when `text` has an `=` outside brackets and strings that is not part of `==`, `<=`,
// `>=` or `!=`: the statement form `a = e` or `a, b = f(x)`.
bool has_top_level_assignment(const std::string& text) {
  int depth = 0;
  bool in_string = false;
  for (size_t i = 0; i < text.size(); ++i) {
    char c = text[i];
    if (in_string) {
      if (c == '\\') ++i;
      else if (c == '"') in_string = false;
      continue;
    }
    if (c == '%') return false;  // the rest is a comment
    if (c == '"') in_string = true;
    else if (c == '(' || c == '[') ++depth;
    else if (c == ')' || c == ']') --depth;
    else if (c == '=' && depth == 0) {
      char prev = i > 0 ? text[i - 1] : ' ';
      char next = i + 1 < text.size() ? text[i + 1] : ' ';
      if (next != '=' && prev != '=' && prev != '<' && prev != '>' && prev != '!') return true;
    }
  }
  return false;
}
}  // namespace

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

// Diagnostics inside the input are shown with the input's own line numbers.
void Session::report(const frontend::Compilation& c, int input_offset) {
  const frontend::SourceFile* file = c.source.get();
  int base = file->locate(static_cast<uint32_t>(input_offset)).line;
  for (const auto& d : c.diagnostics.items()) {
    if (!d.span.valid() || d.span.begin < static_cast<uint32_t>(input_offset)) {
      err_ << frontend::Diagnostics::render(d);
      continue;
    }
    frontend::Diagnostic copy = d;
    frontend::LineCol lc = d.span.start();
    std::string line(file->line_text(lc.line));
    err_ << "<repl>:" << (lc.line - base + 1) << ":" << lc.column << ": error: " << d.message
         << "\n  " << line << "\n  ";
    for (int i = 0; i + 1 < lc.column && i < static_cast<int>(line.size()); ++i)
      err_ << (line[i] == '\t' ? '\t' : ' ');
    size_t first = static_cast<size_t>(lc.column - 1);
    size_t width = d.span.end > d.span.begin ? d.span.end - d.span.begin : 1;
    width = std::max<size_t>(1, std::min(width, line.size() > first ? line.size() - first : 1));
    err_ << '^' << std::string(width - 1, '~') << "\n";
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
  names_.clear();
  for (const auto& d : c->program->decls) {
    if (auto* f = dynamic_cast<const ast::FuncDecl*>(d.get())) names_.push_back(f->name);
    if (auto* e = dynamic_cast<const ast::ElementDecl*>(d.get())) names_.push_back(e->name);
    if (auto* e = dynamic_cast<const ast::ExternDecl*>(d.get())) names_.push_back(e->name);
    if (auto* e = dynamic_cast<const ast::ConstDecl*>(d.get())) names_.push_back(e->decl->name);
  }
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
  try {
    interp::Options options;
    options.out = &out_;
    interp::Interpreter in(*second->program, options);
    std::vector<interp::Value> args;
    for (const auto& [n, v] : vars_) args.push_back(v.value);
    std::vector<interp::Value> res = in.call(*second->program->find_func(name), std::move(args));
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
  } catch (const interp::RuntimeError& e) {
    err_ << e.render();
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

void Session::command(const std::string& line) {
  size_t sp = line.find_first_of(" \t");
  std::string word = line.substr(1, sp == std::string::npos ? std::string::npos : sp - 1);
  std::string arg = sp == std::string::npos ? "" : trim(line.substr(sp));
  std::vector<std::string> matches;
  for (const char* c : kCommands) {
    if (word == c) {
      matches = {c};
      break;
    }
    if (!word.empty() && std::string(c).starts_with(word)) matches.push_back(c);
  }
  if (matches.empty()) {
    err_ << "unknown command ':" << word << "' (:help lists the commands)\n";
    return;
  }
  if (matches.size() > 1) {
    err_ << "ambiguous command ':" << word << "': could be";
    for (const auto& m : matches) err_ << " :" << m;
    err_ << "\n";
    return;
  }
  const std::string& cmd = matches[0];
  if (cmd == "quit") {
    quit_ = true;
  } else if (cmd == "help") {
    if (arg.empty()) {
      out_ << kHelp;
    } else {
      std::string topic = arg[0] == ':' ? arg.substr(1) : arg;
      std::istringstream lines(kHelp);
      std::string l;
      bool found = false;
      while (std::getline(lines, l))
        if (l.starts_with("  :" + topic)) out_ << trim(l) << "\n", found = true;
      if (!found) out_ << "no help on '" << arg << "'\n";
    }
  } else if (cmd == "reset") {
    files_.clear();
    file_texts_.clear();
    decls_.clear();
    vars_.clear();
    names_.clear();
  } else if (cmd == "type") {
    if (arg.empty()) err_ << ":type needs an expression\n";
    else statements(arg, true, true);
  } else if (cmd == "load" || cmd == "reload") {
    std::vector<std::string> files = files_;
    if (cmd == "load") {
      if (arg.empty()) {
        err_ << ":load needs a file name\n";
        return;
      }
      files.push_back(arg);
    }
    std::vector<std::string> texts;
    for (const auto& path : files) {
      std::string text;
      if (!load(path, text)) return;
      texts.push_back(text);
    }
    std::swap(files, files_);
    std::swap(texts, file_texts_);
    int offset = 0;
    auto c = compile("", "", "", offset);
    if (!c->ok()) {
      err_ << c->diagnostics.render_all();
      std::swap(files, files_);
      std::swap(texts, file_texts_);
      return;
    }
    declarations("");  // refreshes the names
    out_ << (cmd == "load" ? "loaded " + arg : "reloaded " + std::to_string(files_.size()) + " file(s)")
         << "\n";
  }
}

std::vector<std::string> Session::completions(const std::string& prefix) const {
  std::vector<std::string> out;
  if (!prefix.empty() && prefix[0] == ':') {
    for (const char* c : kCommands)
      if ((":" + std::string(c)).starts_with(prefix)) out.push_back(":" + std::string(c));
    return out;
  }
  auto add = [&](const std::string& n) {
    if (n.starts_with(prefix) && !n.starts_with("__")) out.push_back(n);
  };
  for (const auto& n : names_) add(n);
  for (const auto& [n, v] : vars_) add(n);
  for (const char* n : kIntrinsics) add(n);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace simit::repl
