// What the interpreter's assembly tests share (tests/interp/assembly_test.cpp,
// assembly_errors_test.cpp, conjugate_gradient_test.cpp): a program with its interpreter and
// host sets bound by extern name, results as Eigen matrices and vectors, and a tolerance check.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "runtime/set.h"
#include "runtime/sparse_convert.h"
#include "test_util.h"

namespace simit::interp::assembly_support {

namespace ast = frontend::ast;
using Eigen::MatrixXd;
using Eigen::VectorXd;

// A compiled program, its interpreter, and helpers to bind host sets by extern name.
class Harness {
 public:
  explicit Harness(const std::string& text) : c_(testing::compile(text, "assembly.sim")) {
    if (c_->ok()) in_ = std::make_unique<Interpreter>(*c_->program);
  }
  bool ok() const { return in_ != nullptr; }
  Interpreter& interp() { return *in_; }

  const ast::Variable& global(const std::string& name) const {
    for (const ast::Variable* v : c_->program->globals)
      if (v && v->name == name && v->kind == ast::Variable::Kind::Extern) return *v;
    throw std::runtime_error("no extern " + name);
  }
  // Adds every field of the extern's element type (zero) and binds the set. Add elements
  // first: field arrays move when a set grows.
  void bind(const std::string& name, runtime::Set& s) {
    const ast::Variable& v = global(name);
    for (const ast::FieldDecl& f : v.type->element->fields)
      if (s.field_index(f.name) < 0) s.add_field(f.name, field_type_of(*f.type));
    in_->bind_set(v, s);
  }
  std::vector<Value> run(const std::string& f, std::vector<Value> args = {}) {
    return in_->call(testing::func(*c_, f), std::move(args));
  }

 private:
  std::unique_ptr<frontend::Compilation> c_;
  std::unique_ptr<Interpreter> in_;
};

inline double* field(runtime::Set& s, const char* name) { return s.field(name).data<double>(); }

inline MatrixXd dense(const Value& v) {
  EXPECT_EQ(v.kind(), Value::Kind::Matrix);
  return runtime::to_dense(*v.matrix());
}

inline VectorXd vec(const Value& v) {
  EXPECT_TRUE(v.is_tensor());
  const Tensor& t = v.tensor();
  return Eigen::Map<const VectorXd>(t.floats(), static_cast<Eigen::Index>(t.size()));
}

// A field's values, element after element, as one vector.
inline VectorXd vec(runtime::Set& s, const char* name) {
  const runtime::Field& f = s.field(name);
  return Eigen::Map<const VectorXd>(f.data<double>(),
                                    static_cast<Eigen::Index>(f.components() * s.size()));
}

#define EXPECT_MATRIX_NEAR(actual, expected, tol)                                             \
  do {                                                                                        \
    const MatrixXd a_ = (actual), e_ = (expected);                                            \
    ASSERT_EQ(a_.rows(), e_.rows());                                                          \
    ASSERT_EQ(a_.cols(), e_.cols());                                                          \
    EXPECT_LE((a_ - e_).cwiseAbs().maxCoeff(), (tol)*std::max(1.0, e_.cwiseAbs().maxCoeff())) \
        << "actual:\n"                                                                        \
        << a_ << "\nexpected:\n"                                                              \
        << e_;                                                                                \
  } while (0)

// Distinct (row, col) element pairs, for pattern sizes.
using Pairs = std::set<std::pair<int, int>>;

}  // namespace simit::interp::assembly_support
