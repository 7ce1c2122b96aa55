// Parsing and validation of `%@` directives (TESTFORMAT.md §7).
#include "directives.h"

#include <cctype>
#include <climits>
#include <cstdlib>
#include <stdexcept>

namespace simit::tools {
namespace {

// A malformed directive; turned into a DirectiveError for its line.
struct BadDirective : std::runtime_error {
  using std::runtime_error::runtime_error;
};

[[noreturn]] void bad(const std::string& message) { throw BadDirective(message); }

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::string quoted(std::string_view s) { return "'" + std::string(s) + "'"; }

std::string identifier(std::string_view text, const char* what) {
  std::string_view s = trim(text);
  bool ok = !s.empty() && (std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_');
  for (char c : s) ok = ok && (std::isalnum(static_cast<unsigned char>(c)) || c == '_');
  if (!ok) bad(std::string("expected ") + what + ", found " + quoted(s));
  return std::string(s);
}

int integer(std::string_view text, int min, const char* what) {
  std::string s(trim(text));
  bool digits = !s.empty() && s.size() <= 10;
  for (char c : s) digits = digits && std::isdigit(static_cast<unsigned char>(c));
  long long v = digits ? std::strtoll(s.c_str(), nullptr, 10) : -1;
  if (!digits || v < min || v > INT_MAX)
    bad(std::string("expected ") + what + ", found " + quoted(s));
  return static_cast<int>(v);
}

// `lhs = rhs`, split at the first `=`.
std::pair<std::string_view, std::string_view> assignment(std::string_view rest) {
  size_t eq = rest.find('=');
  if (eq == std::string_view::npos) bad("expected '=' in " + quoted(trim(rest)));
  return {trim(rest.substr(0, eq)), trim(rest.substr(eq + 1))};
}

// `name(a, b, ...)`; `args` stays empty when there are no parentheses.
struct CallForm {
  std::string name;
  std::vector<std::string> args;
  bool has_parens = false;
};

CallForm call_form(std::string_view text, const char* what) {
  CallForm form;
  size_t open = text.find('(');
  if (open == std::string_view::npos) {
    form.name = identifier(text, what);
    return form;
  }
  if (text.back() != ')') bad("expected ')' at the end of " + quoted(text));
  form.name = identifier(text.substr(0, open), what);
  form.has_parens = true;
  for (const auto& a : split_top_level(text.substr(open + 1, text.size() - open - 2)))
    form.args.push_back(identifier(a, "a set name"));
  if (form.args.empty()) bad("expected set names inside the parentheses of " + quoted(text));
  return form;
}

Literal literal(std::string_view text) {
  LiteralResult r = parse_literal(trim(text));
  if (!r.literal) bad(r.error);
  return std::move(*r.literal);
}

std::vector<Literal> literal_list(std::string_view text) {
  std::vector<Literal> values;
  for (const auto& part : split_top_level(text)) {
    if (part.empty()) bad("empty value in the list " + quoted(text));
    values.push_back(literal(part));
  }
  return values;
}

std::string string_argument(std::string_view text) {
  if (trim(text).substr(0, 1) != "\"") bad("expected a quoted string, found " + quoted(trim(text)));
  Literal lit = literal(text);
  if (lit.kind != frontend::ScalarKind::String) bad("expected one quoted string");
  return lit.string_value;
}

// `S.f` or `S.f[k]`
void field_target(std::string_view lhs, ExpectDirective& e) {
  size_t dot = lhs.find('.');
  std::string_view field = lhs.substr(dot + 1);
  size_t open = field.find('[');
  if (open != std::string_view::npos) {
    if (field.back() != ']') bad("expected ']' at the end of " + quoted(lhs));
    e.element = integer(field.substr(open + 1, field.size() - open - 2), 0, "an element index");
    field = field.substr(0, open);
  }
  e.set = identifier(lhs.substr(0, dot), "a set name");
  e.field = identifier(field, "a field name");
}

// ---------------------------------------------------------------------------
// One function per directive keyword.

ErrorExpectation& error_expectation(SectionDirectives& out) {
  if (!out.error) out.error.emplace();
  return *out.error;
}

const std::vector<std::string>& error_categories() {
  static const std::vector<std::string> categories = {
      "lexical", "syntax",    "semantic",     "undeclared",       "redefinition",
      "type",    "dimension", "not-writable", "literal-required", "generic-unresolved",
      "arity",   "runtime"};
  return categories;
}

void parse_error(std::string_view rest, SectionDirectives& out, int /*line*/) {
  std::string category(trim(rest));
  bool known = false;
  for (const auto& c : error_categories()) known = known || c == category;
  if (!known) bad("unknown error category " + quoted(category));
  ErrorExpectation& e = error_expectation(out);
  if (!e.category.empty()) bad("a second '%@ error' line (the first said " + e.category + ")");
  e.category = category;
}

void parse_error_line(std::string_view rest, SectionDirectives& out, int /*line*/) {
  ErrorExpectation& e = error_expectation(out);
  if (e.line) bad("a second '%@ error-line' line");
  e.line = integer(rest, 1, "a line number (the header line is 1)");
}

void parse_error_contains(std::string_view rest, SectionDirectives& out, int /*line*/) {
  error_expectation(out).contains.push_back(string_argument(rest));
}

std::vector<int> edge_tuple(const std::string& text, size_t arity) {
  if (text.size() < 2 || text.front() != '(' || text.back() != ')')
    bad("expected an endpoint tuple like (0,1), found " + quoted(text));
  std::vector<int> ends;
  for (const auto& i : split_top_level(std::string_view(text).substr(1, text.size() - 2)))
    ends.push_back(integer(i, 0, "an endpoint index"));
  if (ends.size() != arity)
    bad("the tuple " + text + " has " + std::to_string(ends.size()) + " endpoints, the set " +
        std::to_string(arity));
  return ends;
}

GraphAction parse_set(std::string_view rest) {
  auto [lhs, rhs] = assignment(rest);
  CallForm form = call_form(lhs, "a set name");
  SetDirective s;
  s.name = form.name;
  s.endpoint_sets = form.args;
  if (!form.has_parens) {
    s.size = integer(rhs, 0, "an element count");
    return s;
  }
  for (const auto& t : split_top_level(rhs)) s.edges.push_back(edge_tuple(t, form.args.size()));
  return s;
}

GraphAction parse_grid(std::string_view rest) {
  auto [lhs, rhs] = assignment(rest);
  CallForm form = call_form(lhs, "a grid name");
  if (form.args.size() != 1) bad("a grid names exactly one point set: G(P)");
  GridDirective g{form.name, form.args[0], {}};
  for (const auto& n : split_top_level(rhs)) g.extents.push_back(integer(n, 1, "a grid extent"));
  if (g.extents.empty()) bad("a grid needs at least one extent");
  return g;
}

GraphAction parse_field(std::string_view rest) {
  auto [lhs, rhs] = assignment(rest);
  size_t dot = lhs.find('.');
  if (dot == std::string_view::npos) bad("expected S.f, found " + quoted(lhs));
  FieldDirective f;
  f.set = identifier(lhs.substr(0, dot), "a set name");
  f.field = identifier(lhs.substr(dot + 1), "a field name");
  f.values = literal_list(rhs);
  return f;
}

GraphAction parse_value(std::string_view rest, ValueDirective::Target target) {
  auto [lhs, rhs] = assignment(rest);
  ValueDirective v;
  v.target = target;
  v.name = identifier(
      lhs, target == ValueDirective::Target::Argument ? "a parameter name" : "a tensor name");
  v.value = literal(rhs);
  return v;
}

GraphAction parse_run(std::string_view rest) {
  std::string_view s = trim(rest);
  size_t space = s.find_first_of(" \t");
  RunDirective r;
  r.func = identifier(s.substr(0, space), "a function name");
  if (space != std::string_view::npos) r.times = integer(s.substr(space), 1, "a run count");
  return r;
}

// Removes a trailing `tol=T` (after blanks or a comma) and returns T.
std::optional<double> take_tolerance(std::string_view& rhs) {
  size_t at = rhs.rfind("tol=");
  if (at == std::string_view::npos ||
      (at > 0 && !std::isspace(static_cast<unsigned char>(rhs[at - 1])) && rhs[at - 1] != ','))
    return std::nullopt;
  std::string number(trim(rhs.substr(at + 4)));
  char* end = nullptr;
  double tol = std::strtod(number.c_str(), &end);
  if (number.empty() || *end != '\0' || !(tol >= 0)) bad("bad tolerance " + quoted(number));
  rhs = trim(rhs.substr(0, at));
  if (!rhs.empty() && rhs.back() == ',') rhs = trim(rhs.substr(0, rhs.size() - 1));
  return tol;
}

GraphAction parse_expect(std::string_view rest, bool near) {
  auto [lhs, rhs] = assignment(rest);
  ExpectDirective e;
  e.tolerance = take_tolerance(rhs);
  if (near && !e.tolerance) bad("expect-near needs a trailing tol=T");
  if (!near && e.tolerance) bad("tol= belongs to expect-near");
  if (lhs.find('.') != std::string_view::npos) {
    field_target(lhs, e);
    e.values = literal_list(rhs);
  } else {
    e.name = identifier(lhs, "a tensor or result name");
    e.values.push_back(literal(rhs));
  }
  if (e.element && e.values.size() != 1) bad("S.f[k] takes exactly one value");
  return e;
}

GraphAction parse_expect_output(std::string_view rest) {
  return ExpectOutputDirective{string_argument(rest)};
}

GraphAction parse_tensor(std::string_view rest) {
  return parse_value(rest, ValueDirective::Target::ExternTensor);
}
GraphAction parse_arg(std::string_view rest) {
  return parse_value(rest, ValueDirective::Target::Argument);
}
GraphAction parse_expect_exact(std::string_view rest) { return parse_expect(rest, false); }
GraphAction parse_expect_near(std::string_view rest) { return parse_expect(rest, true); }

// Graph directives are kept in order with their line.
template <GraphAction (*Parse)(std::string_view)>
void graph_step(std::string_view rest, SectionDirectives& out, int line) {
  out.graph.push_back({line, Parse(rest)});
}

using KeywordParser = void (*)(std::string_view rest, SectionDirectives& out, int line);

KeywordParser keyword_parser(std::string_view keyword) {
  static const std::pair<std::string_view, KeywordParser> table[] = {
      {"error", parse_error},
      {"error-line", parse_error_line},
      {"error-contains", parse_error_contains},
      {"set", graph_step<parse_set>},
      {"grid", graph_step<parse_grid>},
      {"field", graph_step<parse_field>},
      {"tensor", graph_step<parse_tensor>},
      {"arg", graph_step<parse_arg>},
      {"run", graph_step<parse_run>},
      {"expect", graph_step<parse_expect_exact>},
      {"expect-near", graph_step<parse_expect_near>},
      {"expect-output", graph_step<parse_expect_output>},
  };
  for (const auto& [name, parse] : table)
    if (name == keyword) return parse;
  return nullptr;
}

// `%@ keyword rest`: the keyword is the run of letters and dashes after `%@`.
void parse_directive_line(std::string_view text, int line, SectionDirectives& out) {
  std::string_view body = trim(text.substr(2));
  size_t end = 0;
  while (end < body.size() &&
         (std::isalpha(static_cast<unsigned char>(body[end])) || body[end] == '-'))
    ++end;
  std::string keyword(body.substr(0, end));
  if (keyword.empty()) bad("expected a directive keyword after '%@'");
  KeywordParser parse = keyword_parser(keyword);
  if (!parse) bad("unknown directive '%@ " + keyword + "'");
  try {
    parse(body.substr(end), out, line);
  } catch (const BadDirective& e) {
    bad("'%@ " + keyword + "': " + e.what());
  }
}

}  // namespace

bool SectionDirectives::has_runs() const {
  for (const auto& step : graph)
    if (std::holds_alternative<RunDirective>(step.action)) return true;
  return false;
}

SectionDirectives parse_directives(std::string_view source) {
  SectionDirectives out;
  int line = 1;
  size_t begin = 0;
  while (begin <= source.size()) {
    size_t end = source.find_first_of("\r\n", begin);
    if (end == std::string_view::npos) end = source.size();
    std::string_view text = trim(source.substr(begin, end - begin));
    if (text.substr(0, 2) == "%@") {
      try {
        parse_directive_line(text, line, out);
      } catch (const BadDirective& e) {
        out.errors.push_back({line, e.what()});
      }
    }
    if (end == source.size()) break;
    begin = end + (source.compare(end, 2, "\r\n") == 0 ? 2 : 1);
    ++line;
  }
  return out;
}

}  // namespace simit::tools
