// The interpreter's side of a distributed run (interp/distribution.h), through a stand-in
// for the ranks: reductions over a set hand the ranks their element sums, assembled vectors and
// matrix-vector products ask for their ghosts, and what needs other ranks' rows is refused with a
// message at its statement.
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "interp/distribution.h"
#include "interp/set_binding.h"
#include "runtime/set.h"
#include "test_util.h"

namespace simit::interp {
namespace {

namespace ast = frontend::ast;

// One rank that owns nodes 0, 2 and 4 (1 and 3 are ghosts, between them, as the whole set's
// order puts them); its "other ranks" add 1000 to the owned element sums, and a refresh
// writes -7 into every ghost entry, so that both show in the results.
class FakeRanks : public Distribution {
 public:
  const runtime::Set* nodes = nullptr;
  std::vector<int32_t> owned_nodes = {0, 2, 4};
  mutable int refreshes = 0;
  mutable std::vector<std::vector<double>> sums;

  const std::vector<int32_t>* owned(const runtime::Set& set) const override {
    return &set == nodes ? &owned_nodes : nullptr;
  }
  bool split(const runtime::Set& set) const override { return &set == nodes; }
  double blocked_sum(const runtime::Set& set, std::span<const double> element_sums) const override {
    EXPECT_EQ(&set, nodes);
    sums.emplace_back(element_sums.begin(), element_sums.end());
    double total = 1000.0;
    for (int32_t i : owned_nodes) total += element_sums[static_cast<size_t>(i)];
    return total;
  }
  void refresh(const runtime::Set& set, std::span<std::byte> values,
               size_t element_bytes) const override {
    ++refreshes;
    EXPECT_EQ(&set, nodes);
    EXPECT_EQ(element_bytes, sizeof(double));
    const double ghost = -7.0;
    for (int e : {1, 3})
      std::memcpy(values.data() + static_cast<size_t>(e) * element_bytes, &ghost, sizeof ghost);
  }
};

const char* kProgram = R"(
element Node
  u : float;
end
element Spring
end
extern nodes : set{Node};
extern springs : set{Spring}(nodes, nodes);

func stiff(s : Spring, p : (Node * 2)) -> K : matrix[nodes,nodes](float)
  K(p(0), p(0)) = 2.0;
  K(p(1), p(1)) = 2.0;
  K(p(0), p(1)) = -1.0;
  K(p(1), p(0)) = -1.0;
end
func ends(s : Spring, p : (Node * 2)) -> f : vector[nodes](float)
  f(p(0)) = 1.0;
  f(p(1)) = 1.0;
end
export func inner() -> (r : float, d : float, n : float)
  r = nodes.u' * nodes.u;
  d = dot(nodes.u, nodes.u);
  n = norm(nodes.u);
end
export func product() -> y : vector[nodes](float)
  K = map stiff to springs reduce +;
  y = K * nodes.u;
end
export func assembled() -> f : vector[nodes](float)
  f = map ends to springs reduce +;
end
export func transposed() -> y : vector[nodes](float)
  K = map stiff to springs reduce +;
  y = K' * nodes.u;
end
export func solved() -> y : vector[nodes](float)
  K = map stiff to springs reduce +;
  y = K \ nodes.u;
end
export func product_of_matrices() -> y : vector[nodes](float)
  K = map stiff to springs reduce +;
  L = K * K;
  y = L * nodes.u;
end
)";

class DistributionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    c_ = testing::compile(kProgram, "distribution.sim");
    ASSERT_TRUE(c_->ok());
    nodes_.add_many(5);
    for (int i = 0; i + 1 < 5; ++i) springs_.add({i, i + 1});  // a chain
    ranks_.nodes = &nodes_;
    Options o;
    o.distribution = &ranks_;
    in_ = std::make_unique<Interpreter>(*c_->program, o);
    for (const ast::Variable* v : c_->program->globals) {
      if (!v || v->kind != ast::Variable::Kind::Extern) continue;
      runtime::Set& s = v->name == "nodes" ? nodes_ : springs_;
      for (const ast::FieldDecl& f : v->type->element->fields)
        if (s.field_index(f.name) < 0) s.add_field(f.name, field_type_of(*f.type));
      in_->bind_set(*v, s);
    }
    double* u = nodes_.field("u").data<double>();
    for (int i = 0; i < 5; ++i) u[i] = 1.0 + i;  // 1 2 3 4 5
  }
  std::vector<Value> run(const std::string& f) { return in_->call(testing::func(*c_, f), {}); }
  std::string error_of(const std::string& f) {
    try {
      run(f);
    } catch (const RuntimeError& e) {
      return e.message();
    }
    return "";
  }

  std::unique_ptr<frontend::Compilation> c_;
  runtime::Set nodes_{"nodes"};
  runtime::Set springs_{"springs", {&nodes_, &nodes_}};
  FakeRanks ranks_;
  std::unique_ptr<Interpreter> in_;
};

TEST_F(DistributionTest, ReductionsHandTheRanksTheirElementSums) {
  const std::vector<Value> r = run("inner");
  // Owned: 1 3 5, so 1 + 9 + 25 = 35; the other ranks add 1000.
  EXPECT_EQ(r.at(0).as_float(), 1035.0);
  EXPECT_EQ(r.at(1).as_float(), 1035.0);
  EXPECT_EQ(r.at(2).as_float(), std::sqrt(1035.0));
  const std::vector<double> squares = {1.0, 4.0, 9.0, 16.0, 25.0};
  EXPECT_EQ(ranks_.sums, (std::vector<std::vector<double>>(3, squares)));
}

TEST_F(DistributionTest, AMatrixVectorProductRefreshesItsGhosts) {
  const Value y = run("product").at(0);
  // The chain's stiffness (diagonal 2 per spring at a node) times 1..5: owned rows
  // 2*1 - 2 = 0, -2 + 4*3 - 4 = 6, -4 + 2*5 = 6; the ghost rows come from the "owners" (-7).
  const double* v = y.tensor().floats();
  EXPECT_EQ(std::vector<double>(v, v + 5), (std::vector<double>{0.0, -7.0, 6.0, -7.0, 6.0}));
  EXPECT_EQ(ranks_.refreshes, 1);
}

TEST_F(DistributionTest, AnAssembledVectorRefreshesItsGhosts) {
  const Value f = run("assembled").at(0);
  const double* v = f.tensor().floats();
  // Each node's count of springs: 1 2 1 (owned), the ghosts their owners' values.
  EXPECT_EQ(std::vector<double>(v, v + 5), (std::vector<double>{1.0, -7.0, 2.0, -7.0, 1.0}));
  EXPECT_EQ(ranks_.refreshes, 1);
}

TEST_F(DistributionTest, WhatNeedsOtherRanksRowsIsRefused) {
  EXPECT_NE(error_of("transposed")
                .find("a distributed run cannot compute the transpose of a system matrix yet"),
            std::string::npos);
  EXPECT_NE(error_of("solved").find("a distributed run cannot compute a direct solve"),
            std::string::npos);
  EXPECT_NE(error_of("product_of_matrices")
                .find("a distributed run cannot compute a product of two system matrices yet"),
            std::string::npos);
}

}  // namespace
}  // namespace simit::interp
