// The `%@` directives of a test section (TESTFORMAT.md §7): expected diagnostics and
// self-contained graph tests, parsed and validated before anything runs.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "literal.h"

namespace simit::tools {

// `%@ error <category>`, `%@ error-line N`, `%@ error-contains "text"` (§7.2).
struct ErrorExpectation {
  std::string category;     // empty when only error-line / error-contains were given
  std::optional<int> line;  // relative to the section: its header line is line 1
  std::vector<std::string> contains;
  bool runtime() const { return category == "runtime"; }
};

// `%@ set S = n` (vertex set) or `%@ set S(A, B) = (i,j), ...` (edge set).
struct SetDirective {
  std::string name;
  std::vector<std::string> endpoint_sets;  // empty for a vertex set
  int size = 0;                            // vertex sets
  std::vector<std::vector<int>> edges;     // edge sets: endpoint indices per element
  bool is_edge_set() const { return !endpoint_sets.empty(); }
};

// `%@ grid G(P) = n0, n1, ...`
struct GridDirective {
  std::string name;
  std::string point_set;
  std::vector<int> extents;
};

// `%@ field S.f = v0, v1, ...`
struct FieldDirective {
  std::string set;
  std::string field;
  std::vector<Literal> values;
};

// `%@ tensor x = literal` (an extern tensor) or `%@ arg p = literal` (an entry-point parameter).
struct ValueDirective {
  enum class Target { ExternTensor, Argument };
  Target target = Target::ExternTensor;
  std::string name;
  Literal value;
};

// `%@ run f [N]`
struct RunDirective {
  std::string func;
  int times = 1;
};

// `%@ expect S.f = ...`, `%@ expect S.f[k] = v`, `%@ expect x = literal`, and the
// `expect-near ... tol=T` forms.
struct ExpectDirective {
  std::string set;             // empty for `expect x = literal`
  std::string field;           // empty for `expect x = literal`
  std::string name;            // `expect x = literal`: an extern tensor or a result of the last run
  std::optional<int> element;  // `S.f[k]`
  std::vector<Literal> values;
  std::optional<double> tolerance;  // expect-near: absolute tolerance
  bool is_field() const { return !set.empty(); }
};

// `%@ expect-output "text"`
struct ExpectOutputDirective {
  std::string text;
};

using GraphAction = std::variant<SetDirective, GridDirective, FieldDirective, ValueDirective,
                                 RunDirective, ExpectDirective, ExpectOutputDirective>;

// One graph directive with the section-relative line it was written on (header = 1).
struct GraphStep {
  int line = 1;
  GraphAction action;
};

struct DirectiveError {
  int line = 1;  // section-relative
  std::string message;
};

// Everything the `%@` lines of one section say, in textual order.
struct SectionDirectives {
  std::optional<ErrorExpectation> error;  // present: a must-fail section (§7.2)
  std::vector<GraphStep> graph;           // processed in order (§7.3)
  std::vector<DirectiveError> errors;     // malformed or unknown directives
  bool has_graph() const { return !graph.empty(); }
  bool has_runs() const;
};

// Parses every line of `source` whose first non-blank characters are `%@`.
SectionDirectives parse_directives(std::string_view source);

}  // namespace simit::tools
