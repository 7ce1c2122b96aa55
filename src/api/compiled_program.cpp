// Compiling a program once and looking up its declarations.
#include "api/compiled_program.h"

namespace simit::api {

namespace ast = frontend::ast;

std::shared_ptr<const CompiledProgram> CompiledProgram::from_file(const std::string& path) {
  return adopt(frontend::compile_file(path));
}

std::shared_ptr<const CompiledProgram> CompiledProgram::from_source(std::string name,
                                                                    std::string text) {
  return adopt(frontend::compile_source(std::move(name), std::move(text)));
}

std::shared_ptr<const CompiledProgram> CompiledProgram::adopt(
    std::unique_ptr<frontend::Compilation> c) {
  auto p = std::make_shared<CompiledProgram>();
  p->compilation_ = std::move(c);
  return p;
}

std::shared_ptr<const CompiledProgram> CompiledProgram::borrow(const ast::Program& program) {
  auto p = std::make_shared<CompiledProgram>();
  p->borrowed_ = &program;
  return p;
}

const ast::FuncDecl* CompiledProgram::find_func(const std::string& name) const {
  return program().find_func(name);
}

const ast::Variable* CompiledProgram::find_extern(const std::string& name) const {
  for (const ast::Variable* g : program().globals)
    if (g && g->name == name && g->kind == ast::Variable::Kind::Extern) return g;
  return nullptr;
}

}  // namespace simit::api
