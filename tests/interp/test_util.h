// Helpers shared by the interpreter's unit tests: compiling a program text, calling one
// of its functions, building tensors.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "frontend/frontend.h"
#include "interp/interpreter.h"

namespace simit::interp::testing {

// A program compiled for a test; fails the test when it has diagnostics.
inline std::unique_ptr<frontend::Compilation> compile(const std::string& text,
                                                      const std::string& name = "test.sim") {
  auto c = frontend::compile_source(name, text);
  EXPECT_TRUE(c->ok()) << c->diagnostics.render_all();
  return c;
}

inline const frontend::ast::FuncDecl& func(const frontend::Compilation& c,
                                           const std::string& name) {
  const frontend::ast::FuncDecl* f = c.program->find_func(name);
  if (!f) throw std::runtime_error("no function " + name);
  return *f;
}

inline Value matrix(int rows, int cols, const std::vector<double>& values) {
  Tensor t(ComponentKind::Float, Shape{rows, cols});
  for (size_t i = 0; i < values.size(); ++i) t.mutable_floats()[i] = values[i];
  return Value::of_tensor(std::move(t));
}

inline Value vector(const std::vector<double>& values) {
  Tensor t(ComponentKind::Float, Shape{static_cast<int>(values.size())});
  for (size_t i = 0; i < values.size(); ++i) t.mutable_floats()[i] = values[i];
  return Value::of_tensor(std::move(t));
}

inline Value ivector(const std::vector<int>& values) {
  Tensor t(ComponentKind::Int, Shape{static_cast<int>(values.size())});
  for (size_t i = 0; i < values.size(); ++i) t.mutable_ints()[i] = values[i];
  return Value::of_tensor(std::move(t));
}

}  // namespace simit::interp::testing
