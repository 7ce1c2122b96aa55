// Reading a scene file: TOML syntax, the top-level keys, and the program compiled once.
#include "scene/scene_file.h"

#include <iterator>

#include <fstream>

#include <cstring>

#include <filesystem>
#include <limits>
#include <sstream>

namespace simit::scene {

namespace ast = frontend::ast;
namespace fs = std::filesystem;

namespace {

std::string located(const std::string& file, const toml::source_region& at,
                    const std::string& what) {
  std::ostringstream s;
  s << file;
  if (at.begin.line > 0) s << ':' << at.begin.line << ':' << at.begin.column;
  s << ": error: " << what;
  return s.str();
}

// `init` and `step` name exported procedures without parameters.
const ast::FuncDecl* find_procedure(const SceneFile& file, const std::string& key,
                                    const std::string& name) {
  const ast::FuncDecl* f = file.program->find_func(name);
  if (!f) file.fail(file.doc.get(key), key + ": the program has no function '" + name + "'");
  if (!f->exported)
    file.fail(file.doc.get(key), key + ": '" + name + "' is not an exported function");
  if (!f->params.empty())
    file.fail(file.doc.get(key), key + ": '" + name +
                                     "' takes parameters; a scene can only run "
                                     "procedures without parameters");
  return f;
}

void compile_program(SceneFile& file) {
  if (!fs::exists(file.program_path))
    file.fail(file.doc.get("program"), "program: no such file '" + file.program_path + "'");
  file.program = api::CompiledProgram::from_file(file.program_path);
  if (!file.program->ok())
    throw SceneError(file.program->compilation()->diagnostics.render_all() + file.path +
                     ": error: the program '" + file.program_path + "' does not compile");
  if (!file.init_name.empty()) find_procedure(file, "init", file.init_name);
  const ast::FuncDecl* step = find_procedure(file, "step", file.step_name);
  for (const ast::Param& r : step->results)
    if (r.var && r.var->type && r.var->type->is_scalar() &&
        r.var->type->scalar != frontend::ScalarKind::String)
      file.stat_names.push_back(r.name);
}

void read_frames(SceneFile& file) {
  if (const toml::node* n = file.doc.get("frames")) {
    if (!n->is_integer() || *n->value<int64_t>() < 0 ||
        *n->value<int64_t>() > std::numeric_limits<int>::max())
      file.fail(n, "frames: expected a whole number from 0 to " +
                       std::to_string(std::numeric_limits<int>::max()));
    file.frames = static_cast<int>(*n->value<int64_t>());
  } else {
    file.fail(nullptr, "the scene: missing key 'frames'");
  }
  if (const toml::node* n = file.doc.get("frame_time")) {
    if (!n->is_number() || !(n->value<double>().value() > 0))
      file.fail(n, "frame_time: expected a positive number (seconds between frames in the .pvd)");
    file.frame_time = *n->value<double>();
  }
  if (const toml::node* n = file.doc.get("finite_check")) {
    if (!n->is_boolean()) file.fail(n, "finite_check: expected true or false");
    file.finite_check = *n->value<bool>();
  }
}

// `reorder = true | false | "rcm" | "hilbert"`: how the meshes are renumbered for locality.
void read_reorder(SceneFile& file) {
  const toml::node* n = file.doc.get("reorder");
  if (!n) return;
  const std::string expected = "reorder: expected true, false, \"rcm\" or \"hilbert\"";
  if (n->is_boolean()) {
    file.reorder = *n->value<bool>() ? kDefaultReorder : Reorder::Off;
  } else if (n->is_string()) {
    const std::string v = *n->value<std::string>();
    if (v == "rcm")
      file.reorder = Reorder::Rcm;
    else if (v == "hilbert")
      file.reorder = Reorder::Hilbert;
    else
      file.fail(n, expected + ", not \"" + v + "\"");
  } else {
    file.fail(n, expected);
  }
}

// `executor = "interpreter" | "jit"`, `threads = N | "all"` and `jit_cache = "off" | FOLDER`
// (relative to the scene's folder), parsed as the command line parses `--executor`,
// `--threads` and `--jit-cache`.
void read_executor(SceneFile& file) {
  std::string error;
  if (const toml::node* n = file.doc.get("executor")) {
    if (!n->is_string()) file.fail(n, "executor: expected a string: interpreter or jit");
    file.executor = parse_executor_kind(*n->value<std::string>(), error);
    if (!file.executor) file.fail(n, "executor: " + error);
  }
  if (const toml::node* n = file.doc.get("threads")) {
    // A number is read as the command line reads its text, so both say the same of it.
    if (n->is_integer())
      file.threads = parse_threads(std::to_string(*n->value<int64_t>()), error);
    else if (n->is_string())
      file.threads = parse_threads(*n->value<std::string>(), error);
    else
      file.fail(n, "threads: expected a whole number from 1 to " + std::to_string(kMaxThreads) +
                       ", or \"all\"");
    if (!file.threads) file.fail(n, "threads: " + error);
  }
  if (const toml::node* n = file.doc.get("jit_cache")) {
    if (!n->is_string()) file.fail(n, "jit_cache: expected a string: \"off\" or a folder");
    file.jit_cache = parse_jit_cache(*n->value<std::string>(), error);
    if (!file.jit_cache) file.fail(n, "jit_cache: " + error);
    if (*file.jit_cache != "off") file.jit_cache = file.resolve(*file.jit_cache);
  }
}

}  // namespace

void SceneFile::fail(const toml::node* at, const std::string& what) const {
  throw SceneError(located(path, at ? at->source() : toml::source_region{}, what));
}

void SceneFile::check_keys(const toml::table& t, const std::string& table_name,
                           const std::set<std::string>& allowed) const {
  for (auto&& [key, value] : t) {
    if (allowed.count(std::string(key.str()))) continue;
    std::string list;
    for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
    fail(&value, "unknown key '" + std::string(key.str()) + "' in " + table_name +
                     " (expected one of: " + list + ")");
  }
}

std::optional<std::string> SceneFile::optional_string(const toml::table& t,
                                                      const std::string& table_name,
                                                      const std::string& key) const {
  const toml::node* n = t.get(key);
  if (!n) return std::nullopt;
  if (!n->is_string()) fail(n, table_name + " " + key + ": expected a string");
  return n->value<std::string>();
}

std::string SceneFile::required_string(const toml::table& t, const std::string& table_name,
                                       const std::string& key) const {
  std::optional<std::string> v = optional_string(t, table_name, key);
  if (!v) fail(nullptr, table_name + ": missing key '" + key + "'");
  return *v;
}

std::string SceneFile::resolve(const std::string& relative) const {
  fs::path p(relative);
  if (p.is_absolute() || dir.empty()) return p.lexically_normal().string();
  return (fs::path(dir) / p).lexically_normal().string();
}

namespace {

// Where a byte outside ASCII stands outside a string or comment: TOML allows none there, and
// toml++ 3.3 (Debian 12) reaches unreachable code on some of them instead of reporting it
// (upstream issues 190 and 295), so they are refused before it sees the text.
void screen_non_ascii(const std::string& path, const std::string& text) {
  int line = 1, col = 1;
  enum class In { Code, Comment, Basic, Literal, MultiBasic, MultiLiteral } in = In::Code;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    const auto at = [&](const char* s) { return text.compare(i, std::strlen(s), s) == 0; };
    if (in == In::Code && static_cast<unsigned char>(c) >= 0x80) {
      toml::source_region where;
      where.begin = {static_cast<toml::source_index>(line), static_cast<toml::source_index>(col)};
      throw SceneError(located(path, where,
                               "a character outside ASCII outside a string or comment (TOML allows "
                               "them only in strings and comments)"));
    }
    switch (in) {
      case In::Code:
        if (c == '#')
          in = In::Comment;
        else if (at("\"\"\""))
          in = In::MultiBasic, i += 2, col += 2;
        else if (at("'''"))
          in = In::MultiLiteral, i += 2, col += 2;
        else if (c == '"')
          in = In::Basic;
        else if (c == '\'')
          in = In::Literal;
        break;
      case In::Comment:
        if (c == '\n') in = In::Code;
        break;
      case In::Basic:
      case In::MultiBasic:
        if (c == '\\' && i + 1 < text.size() && text[i + 1] != '\n')
          ++i, ++col;
        else if (in == In::Basic && (c == '"' || c == '\n'))
          in = In::Code;
        else if (in == In::MultiBasic && at("\"\"\""))
          in = In::Code, i += 2, col += 2;
        break;
      case In::Literal:
        if (c == '\'' || c == '\n') in = In::Code;
        break;
      case In::MultiLiteral:
        if (at("'''")) in = In::Code, i += 2, col += 2;
        break;
    }
    if (text[i] == '\n')
      line += 1, col = 1;
    else
      ++col;
  }
}

}  // namespace

std::unique_ptr<SceneFile> read_scene_file(const std::string& path) {
  auto file = std::make_unique<SceneFile>();
  file->path = path;
  try {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw SceneError(path + ": error: cannot read the scene file");
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    screen_non_ascii(path, text);
    file->doc = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    throw SceneError(located(path, e.source(), std::string(e.description())));
  }
  file->dir = fs::path(path).parent_path().string();
  file->check_keys(file->doc, "the scene",
                   {"program", "init", "step", "frames", "frame_time", "finite_check", "executor",
                    "threads", "jit_cache", "reorder", "sets", "tensors", "output"});
  file->program_path = file->resolve(file->required_string(file->doc, "the scene", "program"));
  file->init_name = file->optional_string(file->doc, "the scene", "init").value_or("");
  file->step_name = file->required_string(file->doc, "the scene", "step");
  read_frames(*file);
  read_reorder(*file);
  read_executor(*file);
  compile_program(*file);
  return file;
}

std::map<std::string, const ast::Variable*> program_externs(const SceneFile& file, bool sets) {
  std::map<std::string, const ast::Variable*> out;
  for (const ast::Variable* g : file.program->program().globals)
    if (g->kind == ast::Variable::Kind::Extern && g->type &&
        (sets ? g->type->kind == frontend::Type::Kind::Set : g->type->is_tensor()))
      out[g->name] = g;
  return out;
}

}  // namespace simit::scene
