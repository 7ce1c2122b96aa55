// A program compiled once (lexed, parsed, checked), shared by the engines and Functions that
// run it; immutable from here on.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "frontend/ast.h"
#include "frontend/frontend.h"

namespace simit::api {

class CompiledProgram {
 public:
  // Compiles a file or a text; the result may hold errors (see ok() and compilation()).
  static std::shared_ptr<const CompiledProgram> from_file(const std::string& path);
  static std::shared_ptr<const CompiledProgram> from_source(std::string name, std::string text);
  // Takes over a compilation made elsewhere.
  static std::shared_ptr<const CompiledProgram> adopt(std::unique_ptr<frontend::Compilation> c);
  // Refers to a program checked and owned elsewhere, which must outlive every user.
  static std::shared_ptr<const CompiledProgram> borrow(const frontend::ast::Program& program);

  bool ok() const { return borrowed_ || (compilation_ && compilation_->ok()); }
  // Null for a borrowed program.
  const frontend::Compilation* compilation() const { return compilation_.get(); }
  const frontend::ast::Program& program() const {
    return borrowed_ ? *borrowed_ : *compilation_->program;
  }
  // The function named `name`, or null.
  const frontend::ast::FuncDecl* find_func(const std::string& name) const;
  // The extern declared as `name`, or null.
  const frontend::ast::Variable* find_extern(const std::string& name) const;

 private:
  std::unique_ptr<frontend::Compilation> compilation_;
  const frontend::ast::Program* borrowed_ = nullptr;
};

}  // namespace simit::api
