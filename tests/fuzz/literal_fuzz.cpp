// libFuzzer target of the literal reader of `%@` directives: parse the input whole, split it
// at top-level commas, and parse each part.
#include <string>

#include "fuzz_support.h"
#include "testing/literal.h"

namespace {

using simit::frontend::ScalarKind;
using simit::tools::Literal;

// A literal holds one component per element of its shape, in the vector of its kind.
size_t stored_components(const Literal& lit) {
  switch (lit.kind) {
    case ScalarKind::Int:
    case ScalarKind::Bool: return lit.ints.size();
    case ScalarKind::Float: return lit.floats.size();
    case ScalarKind::Complex: return lit.complexes.size();
    case ScalarKind::String: return 1;
  }
  return 0;
}

void parse_and_check(std::string_view text) {
  simit::tools::LiteralResult r = simit::tools::parse_literal(text);
  if (!r.literal) {
    if (r.error.empty()) simit::fuzz::invariant_broken("literal_fuzz", "rejected without an error");
    simit::fuzz::note_rejected("literal_fuzz", std::string(text) + ": " + r.error);
    return;
  }
  if (stored_components(*r.literal) != r.literal->size())
    simit::fuzz::invariant_broken("literal_fuzz",
                                  "components do not fill the shape: " + std::string(text));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view text = simit::fuzz::as_text(data, size);
  parse_and_check(text);
  for (const std::string& part : simit::tools::split_top_level(text)) parse_and_check(part);
  return 0;
}
