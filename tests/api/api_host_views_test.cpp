// What the public API gives hosts that keep views of its data (Python's numpy arrays):
// Function::tensor_type, DenseResult::dims, Options::stop_on_interrupt (Ctrl-C as an
// Interrupted error the host survives) and Set::pin_fields (field_data pointers that runs
// never leave behind).
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <streambuf>
#include <string>
#include <thread>
#include <vector>

#include "api_test_util.h"
#include "simit/simit.h"

namespace {

using simit::testing::contains;
using simit::testing::message_of;

// --- tensor_type ------------------------------------------------------------------------

const char* kTypes = R"(
element Node
  x : vector[3](float);
end
extern nodes : set{Node};
extern s : float;
extern v : vector[3](float);
extern blocks : matrix[2,2](matrix[3,3](float));
extern counts : vector[4](int);

export func f(p : vector[2](vector[3](float)), q : vector[nodes](float), flag : bool)
    -> (c : complex, xs : vector[nodes](vector[3](float)))
  xs = (s + v(0) + blocks(1,1)(2,2) + p(1)(2)) * nodes.x;
  if flag and counts(3) > 0
    c = <1.0, 2.0>;
  end
end
)";

simit::Function compiled_types(int float_size) {
  simit::Options o;
  o.float_size = float_size;
  simit::Program p(o);
  p.load_string(kTypes, "types.sim");
  return p.compile("f");
}

TEST(ApiTensorType, ExternsParametersAndResults) {
  using simit::ComponentKind;
  using simit::FieldType;
  simit::Function f = compiled_types(8);
  EXPECT_EQ(f.tensor_type("s"), (FieldType{ComponentKind::Float, {}, false}));
  EXPECT_EQ(f.tensor_type("v"), (FieldType{ComponentKind::Float, {3}, false}));
  // Block levels follow their outer one.
  EXPECT_EQ(f.tensor_type("blocks"), (FieldType{ComponentKind::Float, {2, 2, 3, 3}, false}));
  EXPECT_EQ(f.tensor_type("counts"), (FieldType{ComponentKind::Int, {4}, false}));
  EXPECT_EQ(f.tensor_type("p"), (FieldType{ComponentKind::Float, {2, 3}, false}));
  EXPECT_EQ(f.tensor_type("flag"), (FieldType{ComponentKind::Bool, {}, false}));
  EXPECT_EQ(f.tensor_type("c"), (FieldType{ComponentKind::Complex, {}, false}));
  // A set, and tensors whose size depends on a set, have no fixed host type.
  EXPECT_EQ(f.tensor_type("nodes"), std::nullopt);
  EXPECT_EQ(f.tensor_type("q"), std::nullopt);
  EXPECT_EQ(f.tensor_type("xs"), std::nullopt);
  EXPECT_TRUE(contains(message_of<simit::BindError>([&] { (void)f.tensor_type("nope"); }),
                       "'nope' is not an extern of the program nor a parameter or result"));
}

TEST(ApiTensorType, FloatSizeFourStoresFloatsAsBinary32) {
  using simit::ComponentKind;
  using simit::FieldType;
  simit::Function f = compiled_types(4);
  EXPECT_EQ(f.tensor_type("s"), (FieldType{ComponentKind::Float, {}, true}));
  EXPECT_EQ(f.tensor_type("blocks"), (FieldType{ComponentKind::Float, {2, 2, 3, 3}, true}));
  EXPECT_EQ(f.tensor_type("c"), (FieldType{ComponentKind::Complex, {}, true}));
  // Ints and bools have one storage whatever the float size.
  EXPECT_EQ(f.tensor_type("counts"), (FieldType{ComponentKind::Int, {4}, false}));
  EXPECT_EQ(f.tensor_type("flag"), (FieldType{ComponentKind::Bool, {}, false}));
}

// --- DenseResult::dims ------------------------------------------------------------------

TEST(ApiDenseResult, DimsOfScalarsVectorsAndGlobalVectorsOfBlocks) {
  simit::Program p;
  p.load_string(R"(
element Point
  x : vector[3](float);
  w : float;
end
extern points : set{Point};
export func shapes() -> (s : float, n : int, v : vector[3](float), m : matrix[2,3](float),
                         xs : vector[points](vector[3](float)), ms : vector[points](float))
  s = 1.5;
  n = 7;
  v = [1.0, 2.0, 3.0]';
  m = [1.0, 2.0, 3.0; 4.0, 5.0, 6.0];
  xs = 2.0 * points.x;
  ms = 2.0 * points.w;
end
)",
                "shapes.sim");
  simit::Function f = p.compile("shapes");
  simit::Set points("points");
  auto x = points.add_field<double, 3>("x");
  auto w = points.add_field<double>("w");
  for (int i = 0; i < 10; ++i) {
    simit::ElementRef e = points.add();
    x(e) = {1.0 * i, 2.0 * i, 3.0 * i};
    w.set(e, 0.25 * i);
  }
  f.bind("points", points);
  f.run();
  EXPECT_EQ(f.result("s").dims(), std::vector<int>{});
  EXPECT_EQ(f.result("s").size(), 1u);
  EXPECT_EQ(f.result("n").dims(), std::vector<int>{});
  EXPECT_EQ(f.result("n").ints()[0], 7);
  EXPECT_EQ(f.result("v").dims(), std::vector<int>{3});
  EXPECT_EQ(f.result("m").dims(), (std::vector<int>{2, 3}));
  EXPECT_EQ(f.result("m").floats()[3], 4.0);  // row-major
  EXPECT_EQ(f.result("ms").dims(), std::vector<int>{10});
  EXPECT_EQ(f.result("ms").floats()[6], 3.0);
  const simit::DenseResult xs = f.result("xs");
  EXPECT_EQ(xs.dims(), (std::vector<int>{10, 3}));
  ASSERT_EQ(xs.size(), 30u);
  EXPECT_EQ(xs.floats()[3 * 7 + 2], 2.0 * 3.0 * 7);  // block after block
}

// --- stop_on_interrupt ------------------------------------------------------------------

// The SIGINT handler a test installs as "what SIGINT did before": it counts instead of
// ending the test program, so a signal that reaches it is seen and survives.
std::atomic<int> g_counted_sigints{0};
extern "C" void count_sigint(int) { g_counted_sigints.fetch_add(1); }

using Handler = void (*)(int);
Handler current_sigint_handler() {
  struct sigaction now {};
  sigaction(SIGINT, nullptr, &now);
  return now.sa_handler;
}

// Installs count_sigint for the scope of a test, and puts the previous handler back.
class CountingSigint {
 public:
  CountingSigint() {
    g_counted_sigints = 0;
    struct sigaction action {};
    action.sa_handler = count_sigint;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &previous_);
  }
  ~CountingSigint() { sigaction(SIGINT, &previous_, nullptr); }
  CountingSigint(const CountingSigint&) = delete;
  CountingSigint& operator=(const CountingSigint&) = delete;

 private:
  struct sigaction previous_ {};
};

// outer × inner iterations: 10^8 at most, half a minute interpreted, so that a run the
// interrupt fails to stop ends (and fails the test) instead of hanging it.
const char* kSpin = R"(
export func spin(outer : int, inner : int) -> s : float
  println "spinning";
  var i = 0;
  while i < outer
    var j = 0;
    while j < inner
      s = s + 1.0;
      j = j + 1;
    end
    i = i + 1;
  end
end
)";

// An output stream that records the SIGINT handler in place whenever the program prints:
// what the run installed, seen from inside the run without sending a signal.
class HandlerProbe : public std::streambuf {
 public:
  std::vector<Handler> seen;

 protected:
  int overflow(int c) override {
    seen.push_back(current_sigint_handler());
    return c == traits_type::eof() ? traits_type::not_eof(c) : c;
  }
  std::streamsize xsputn(const char*, std::streamsize n) override {
    seen.push_back(current_sigint_handler());
    return n;
  }
};

TEST(ApiStopOnInterrupt, ASigintStopsTheRunWhichCanRunAgain) {
  CountingSigint counting;
  HandlerProbe probe;
  std::ostream out(&probe);
  simit::Options o;
  o.stop_on_interrupt = true;
  o.out = &out;
  simit::Program p(o);
  p.load_string(kSpin, "spin.sim");
  simit::Function f = p.compile("spin");
  simit::Tensor<int> outer{100}, inner{1000000};
  f.bind("outer", outer);
  f.bind("inner", inner);

  // The signal goes out ~100 ms after the run's handler is in place (never before: it would
  // reach count_sigint and not stop the run).
  std::atomic<bool> run_over{false}, sent{false};
  std::thread sender([&] {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (!run_over && std::chrono::steady_clock::now() < deadline) {
      if (current_sigint_handler() != count_sigint) {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        sent = true;
        kill(getpid(), SIGINT);
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  });
  std::string message;
  int line = 0;
  try {
    f.run();
  } catch (const simit::Interrupted& e) {
    message = e.what();
    line = e.line();
  } catch (...) {
    run_over = true;
    sender.join();
    throw;
  }
  run_over = true;
  sender.join();
  ASSERT_TRUE(sent) << "the run never installed its SIGINT handler";
  ASSERT_FALSE(message.empty()) << "the run was not interrupted";
  EXPECT_TRUE(contains(message, "spin.sim:")) << message;
  EXPECT_GE(line, 5) << message;  // a statement of the loops
  EXPECT_LE(line, 11) << message;
  EXPECT_EQ(g_counted_sigints, 0);  // the run's handler took it, not the previous one
  EXPECT_EQ(current_sigint_handler(), count_sigint);  // put back after the run
  ASSERT_FALSE(probe.seen.empty());
  EXPECT_NE(probe.seen.front(), count_sigint);  // the run's own handler while it ran

  // The function runs again, to completion, from a fresh start.
  outer = 3;
  inner = 1000;
  f.run();
  EXPECT_EQ(f.result("s").floats()[0], 3000.0);
  // Between runs SIGINT does what it did before.
  kill(getpid(), SIGINT);
  EXPECT_EQ(g_counted_sigints, 1);
}

TEST(ApiStopOnInterrupt, WithoutTheOptionNoHandlerIsInstalled) {
  CountingSigint counting;
  HandlerProbe probe;
  std::ostream out(&probe);
  simit::Options o;  // stop_on_interrupt off
  o.out = &out;
  simit::Program p(o);
  p.load_string(kSpin, "spin.sim");
  simit::Function f = p.compile("spin");
  simit::Tensor<int> outer{2}, inner{10};
  f.bind("outer", outer);
  f.bind("inner", inner);
  f.run();
  EXPECT_EQ(f.result("s").floats()[0], 20.0);
  ASSERT_FALSE(probe.seen.empty());
  for (Handler h : probe.seen) EXPECT_EQ(h, count_sigint);
  EXPECT_EQ(current_sigint_handler(), count_sigint);
  EXPECT_EQ(g_counted_sigints, 0);
}

// --- pinned sets ------------------------------------------------------------------------

const char* kPinned = R"(
element Node
  x : vector[3](float);
  m : float;
end
extern nodes : set{Node};

func scale(inout n : Node)
  n.x(2) = n.m * n.x(2);
end

export func step() -> before : vector[nodes](vector[3](float))
  before = nodes.x;
  nodes.x = nodes.x + 1.0;
  nodes.m = nodes.m + 1.0;
  apply scale to nodes;
end

export func store(c : float)
  y = c * nodes.x - nodes.x;
  nodes.x = y;
end
)";

TEST(ApiPinnedSet, GrowthThrowsAndTheSetIsUnchanged) {
  simit::Set nodes("nodes");
  simit::Set bars("bars", nodes, nodes);
  auto x = nodes.add_field<double, 3>("x");
  bars.add_field<double>("k");
  nodes.add_many(4);
  bars.add(simit::ElementRef(0), simit::ElementRef(1));
  EXPECT_FALSE(nodes.fields_pinned());
  nodes.pin_fields();
  bars.pin_fields();
  EXPECT_TRUE(nodes.fields_pinned());
  EXPECT_TRUE(bars.fields_pinned());
  EXPECT_TRUE(contains(message_of<simit::Error>([&] { nodes.add(); }), "pinned"));
  EXPECT_THROW(nodes.add_many(2), simit::Error);
  EXPECT_THROW(bars.add(simit::ElementRef(1), simit::ElementRef(2)), simit::Error);
  EXPECT_EQ(nodes.size(), 4);
  EXPECT_EQ(bars.size(), 1);
  // The elements there are still read and written in place.
  x(simit::ElementRef(3)) = {1.0, 2.0, 3.0};
  EXPECT_EQ(static_cast<double*>(nodes.field_data("x"))[11], 3.0);
}

class ApiPinnedRun : public ::testing::TestWithParam<simit::ExecutorKind> {};

TEST_P(ApiPinnedRun, RunsKeepTheFieldDataPointers) {
  if (GetParam() == simit::ExecutorKind::Jit && !simit::jit_available())
    GTEST_SKIP() << "this build has no JIT";
  constexpr int kSize = 40;  // larger than a tensor's inline storage
  simit::Options o;
  o.executor.kind = GetParam();
  o.executor.threshold = 0;  // the JIT compiles the apply at once
  o.executor.jit_cache = "off";
  simit::Program p(o);
  p.load_string(kPinned, "pinned.sim");
  simit::Function step = p.compile("step");
  simit::Function store = p.compile("store");
  simit::Set nodes("nodes");
  auto x = nodes.add_field<double, 3>("x");
  auto m = nodes.add_field<double>("m");
  for (int e = 0; e < kSize; ++e) {
    simit::ElementRef n = nodes.add();
    x(n) = {1.0 * e, 10.0 * e, 100.0 * e};
    m.set(n, 0.5 * e);
  }
  nodes.pin_fields();
  const double* px = static_cast<double*>(nodes.field_data("x"));
  const double* pm = static_cast<double*>(nodes.field_data("m"));
  step.bind("nodes", nodes);
  store.bind("nodes", nodes);

  step.run();
  EXPECT_EQ(step.executor().kind, GetParam());
  EXPECT_EQ(nodes.field_data("x"), px);
  EXPECT_EQ(nodes.field_data("m"), pm);
  for (int e = 0; e < kSize; ++e) {
    ASSERT_EQ(px[3 * e], 1.0 * e + 1.0) << e;
    ASSERT_EQ(px[3 * e + 1], 10.0 * e + 1.0) << e;
    ASSERT_EQ(px[3 * e + 2], (0.5 * e + 1.0) * (100.0 * e + 1.0)) << e;
    ASSERT_EQ(pm[e], 0.5 * e + 1.0) << e;
  }
  const simit::DenseResult before = step.result("before");
  EXPECT_EQ(before.floats()[3 * 5 + 1], 50.0);

  // x = c x - x with c = 3: each component doubles.
  std::vector<double> was(px, px + 3 * kSize);
  simit::Tensor<double> c{3.0};
  store.bind("c", c);
  store.run();
  EXPECT_EQ(nodes.field_data("x"), px);
  for (int i = 0; i < 3 * kSize; ++i) ASSERT_EQ(px[i], 3.0 * was[i] - was[i]) << i;
  // The result read from the field before keeps the values it was read with.
  EXPECT_EQ(before.floats()[3 * 5 + 1], 50.0);
}

INSTANTIATE_TEST_SUITE_P(Executors, ApiPinnedRun,
                         ::testing::Values(simit::ExecutorKind::Interpreter,
                                           simit::ExecutorKind::Jit),
                         [](const auto& info) {
                           return std::string(simit::executor_name(info.param));
                         });

}  // namespace
