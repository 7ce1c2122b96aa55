// The texts of the tracers' abort reasons (jit/trace/abort_reasons.h).
#include "jit/trace/abort_reasons.h"

#include "jit/ir_build.h"

namespace simit::jit {

const char* abort_text(AbortReason r) {
  switch (r) {
#define SIMIT_TRACE_ABORT_TEXT(name, text) \
  case AbortReason::name: return text;
    SIMIT_TRACE_ABORTS(SIMIT_TRACE_ABORT_TEXT)
#undef SIMIT_TRACE_ABORT_TEXT
  }
  return "an unknown reason";
}

std::string abort_message(AbortReason r, std::string_view a, std::string_view b) {
  const std::string_view text = abort_text(r);
  std::string out;
  std::string_view details[] = {a, b};
  size_t next = 0, from = 0;
  for (size_t at = text.find("{}"); at != std::string_view::npos; at = text.find("{}", from)) {
    out.append(text.substr(from, at - from));
    if (next < 2) out.append(details[next++]);
    from = at + 2;
  }
  out.append(text.substr(from));
  return out;
}

namespace trace_detail {

void give_up(const frontend::SourceSpan& at, AbortReason r, std::string_view a,
             std::string_view b) {
  jit::give_up(at, abort_message(r, a, b));
}

}  // namespace trace_detail

}  // namespace simit::jit
