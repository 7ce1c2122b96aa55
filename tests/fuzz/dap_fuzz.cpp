// libFuzzer target of the Debug Adapter Protocol's framing (dap/framing.h): the input after its
// first bytes is a byte stream fed to a FrameParser in pieces whose sizes the first bytes give;
// every body is parsed as JSON. The pieces must not matter: one feed of the whole stream gives
// the same bodies and the same error.
//
// Input: byte 0 = n (mod 16), bytes 1..n = piece sizes (0 = an empty feed), used in turn
// until the stream is consumed; the stream is the rest.
#include <algorithm>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "dap/framing.h"
#include "fuzz_support.h"

namespace {

using simit::dap::FrameParser;

constexpr const char* kHarness = "dap_fuzz";

struct Outcome {
  std::vector<std::string> bodies;
  bool malformed = false;
  std::string error;
  bool operator==(const Outcome&) const = default;
};

void drain(FrameParser& parser, Outcome& out) {
  while (std::optional<std::string> body = parser.next()) out.bodies.push_back(std::move(*body));
  out.malformed = parser.malformed();
  out.error = parser.error();
}

Outcome parse_in_pieces(std::string_view stream, const std::vector<size_t>& sizes) {
  FrameParser parser;
  Outcome out;
  size_t total = 0;
  for (size_t size : sizes) total += size;
  if (total == 0) {
    // Only empty pieces (or none): feed those once, then the stream whole.
    for (size_t i = 0; i < sizes.size(); ++i) parser.feed({});
    parser.feed(stream);
    drain(parser, out);
  } else {
    for (size_t at = 0, k = 0; at < stream.size(); ++k) {
      std::string_view piece = stream.substr(at, sizes[k % sizes.size()]);
      at += piece.size();
      parser.feed(piece);
      drain(parser, out);
    }
  }
  // Once malformed, more input changes nothing.
  if (out.malformed) {
    parser.feed(simit::dap::frame("{}"));
    if (parser.next() || !parser.malformed() || parser.error() != out.error)
      simit::fuzz::invariant_broken(kHarness, "a malformed parser took more input");
  }
  return out;
}

void check_outcome(const Outcome& out, std::string_view stream) {
  if (out.malformed != !out.error.empty())
    simit::fuzz::invariant_broken(kHarness, "malformed() and error() disagree: " + out.error);
  if (out.malformed) {
    if (out.error.rfind("frame ", 0) != 0)
      simit::fuzz::invariant_broken(kHarness, "the error names no frame: " + out.error);
    // The message may travel back to the client inside JSON: printable ASCII only.
    for (char c : out.error)
      if (c < 0x20 || c > 0x7e)
        simit::fuzz::invariant_broken(kHarness, "unprintable byte in the error: " + out.error);
    simit::fuzz::note_rejected(kHarness, out.error);
  }
  size_t body_bytes = 0;
  for (const std::string& body : out.bodies) {
    body_bytes += body.size();
    // The body framed again comes back alone and whole.
    FrameParser again;
    again.feed(simit::dap::frame(body));
    std::optional<std::string> round = again.next();
    if (!round || *round != body || again.next() || again.malformed())
      simit::fuzz::invariant_broken(kHarness, "frame() of a body does not parse back to it");
    // What the server does next with a body; a parse error is an answer, not a crash.
    nlohmann::json json = nlohmann::json::parse(body, nullptr, false);
    if (json.is_discarded()) simit::fuzz::note_rejected(kHarness, "body is not JSON");
  }
  if (body_bytes > stream.size())
    simit::fuzz::invariant_broken(kHarness, "the bodies hold more bytes than the stream");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view input = simit::fuzz::as_text(data, size);
  if (input.empty()) return 0;
  size_t count = std::min<size_t>(static_cast<unsigned char>(input[0]) % 16, input.size() - 1);
  std::vector<size_t> sizes;
  for (size_t i = 1; i <= count; ++i) sizes.push_back(static_cast<unsigned char>(input[i]));
  std::string_view stream = input.substr(1 + count);

  Outcome split = parse_in_pieces(stream, sizes);
  check_outcome(split, stream);
  Outcome whole = parse_in_pieces(stream, {});
  if (!(split == whole))
    simit::fuzz::invariant_broken(
        kHarness,
        "the split of the input changed the outcome: " + std::to_string(split.bodies.size()) +
            " bodies, '" + split.error + "' in pieces; " + std::to_string(whole.bodies.size()) +
            " bodies, '" + whole.error + "' whole");
  return 0;
}
