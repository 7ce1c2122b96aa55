// The Debug Adapter Protocol's base framing (dap/framing.h): the incremental parser under
// every split of its input, each malformed case and its message, read_message over a pipe,
// and frame().
#include "dap/framing.h"

#include <gtest/gtest.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace simit::dap {
namespace {

// What a parser made of some input: the bodies in order, and the error if any.
struct Outcome {
  std::vector<std::string> bodies;
  std::string error;
  bool operator==(const Outcome&) const = default;
};

void drain(FrameParser& parser, Outcome& out) {
  while (std::optional<std::string> body = parser.next()) out.bodies.push_back(*body);
  out.error = parser.error();
}

// Feeds `pieces` one after the other, taking every body after each.
Outcome parse_pieces(const std::vector<std::string>& pieces) {
  FrameParser parser;
  Outcome out;
  for (const std::string& piece : pieces) {
    parser.feed(piece);
    drain(parser, out);
  }
  EXPECT_EQ(parser.malformed(), !out.error.empty());
  return out;
}

Outcome parse_whole(const std::string& input) { return parse_pieces({input}); }

Outcome parse_bytewise(const std::string& input) {
  std::vector<std::string> pieces;
  for (char c : input) pieces.emplace_back(1, c);
  return parse_pieces(pieces);
}

// The error that `input` gives, checking that a byte-at-a-time feed gives the same.
std::string error_of(const std::string& input) {
  Outcome whole = parse_whole(input);
  EXPECT_EQ(parse_bytewise(input), whole);
  return whole.error;
}

const std::string kInitialize =
    R"({"seq":1,"type":"request","command":"initialize","arguments":{"adapterID":"simit"}})";

TEST(FrameParser, BodyFedByteByByteComesOutAtItsLastByte) {
  // kInitialize is 83 bytes long (counted outside the test).
  std::string input = "Content-Length: 83\r\n\r\n" + kInitialize;
  ASSERT_EQ(kInitialize.size(), 83u);
  FrameParser parser;
  for (size_t i = 0; i + 1 < input.size(); ++i) {
    parser.feed(input.substr(i, 1));
    ASSERT_EQ(parser.next(), std::nullopt) << "after byte " << i;
    ASSERT_FALSE(parser.malformed());
  }
  parser.feed(input.substr(input.size() - 1));
  EXPECT_EQ(parser.next(), kInitialize);
  EXPECT_EQ(parser.next(), std::nullopt);
  EXPECT_FALSE(parser.malformed());
  EXPECT_EQ(parser.error(), "");
}

TEST(FrameParser, TwoMessagesInOneFeed) {
  std::string input = "Content-Length: 2\r\n\r\n{}Content-Length: 7\r\n\r\n[1,2,3]";
  Outcome out = parse_whole(input);
  EXPECT_EQ(out.bodies, (std::vector<std::string>{"{}", "[1,2,3]"}));
  EXPECT_EQ(out.error, "");
  EXPECT_EQ(parse_bytewise(input), out);
}

TEST(FrameParser, HeaderNowBodyLater) {
  FrameParser parser;
  parser.feed("Content-Length: 10\r\n\r\n");
  EXPECT_EQ(parser.next(), std::nullopt);
  parser.feed("0123");
  EXPECT_EQ(parser.next(), std::nullopt);
  parser.feed("456789Cont");
  EXPECT_EQ(parser.next(), "0123456789");
  EXPECT_EQ(parser.next(), std::nullopt);
  parser.feed("ent-Length: 1\r\n\r\nx");
  EXPECT_EQ(parser.next(), "x");
  EXPECT_FALSE(parser.malformed());
}

TEST(FrameParser, EmptyBody) {
  Outcome out = parse_whole("Content-Length: 0\r\n\r\nContent-Length: 0\r\n\r\n");
  EXPECT_EQ(out.bodies, (std::vector<std::string>{"", ""}));
  EXPECT_EQ(out.error, "");
}

TEST(FrameParser, LengthCountsBytesOfMultibyteUtf8) {
  // {"s":"é✓😀"}: 8 ASCII bytes, é = C3 A9, ✓ = E2 9C 93, 😀 = F0 9F 98 80: 17 bytes, 11
  // characters.
  std::string body = "{\"s\":\"\xc3\xa9\xe2\x9c\x93\xf0\x9f\x98\x80\"}";
  ASSERT_EQ(body.size(), 17u);
  std::string next = "Content-Length: 2\r\n\r\n{}";
  Outcome out = parse_whole("Content-Length: 17\r\n\r\n" + body + next);
  EXPECT_EQ(out.bodies, (std::vector<std::string>{body, "{}"}));
  EXPECT_EQ(out.error, "");
  // A length in characters (11) would cut the body inside the check mark and read the rest
  // as the next frame's header: the parser takes the number as bytes.
  FrameParser parser;
  parser.feed("Content-Length: 11\r\n\r\n" + body);
  EXPECT_EQ(parser.next(), body.substr(0, 11));
  EXPECT_EQ(parser.next(), std::nullopt);
}

TEST(FrameParser, OtherHeaderFieldsAreIgnored) {
  std::string input =
      "Content-Type: application/vscode-jsonrpc; charset=utf-8\r\n"
      "content-length:   2 \r\n"
      "X-Empty:\r\n"
      "X-Colons: a:b:c\r\n"
      "CONTENT-LENGTH:\t2\r\n"
      "\r\n"
      "{}"
      "X-First: before the length\r\n"
      "Content-Length: 4\r\n"
      "\r\n"
      "null";
  Outcome out = parse_whole(input);
  EXPECT_EQ(out.bodies, (std::vector<std::string>{"{}", "null"}));
  EXPECT_EQ(out.error, "");
  EXPECT_EQ(parse_bytewise(input), out);
}

TEST(FrameParser, BodyBytesAreNotHeaders) {
  std::string body = "\r\n\r\nContent-Length: 5\r\n\n\rno colon";
  Outcome out = parse_whole(frame(body) + frame("1"));
  EXPECT_EQ(out.bodies, (std::vector<std::string>{body, "1"}));
  EXPECT_EQ(out.error, "");
}

TEST(FrameParser, LargestLengthIsAccepted) {
  FrameParser parser;
  parser.feed("Content-Length: 67108864\r\n\r\n");
  EXPECT_EQ(parser.next(), std::nullopt);
  EXPECT_FALSE(parser.malformed());
}

TEST(FrameParserMalformed, NoContentLength) {
  EXPECT_EQ(error_of("Content-Type: application/json\r\n\r\n{}"),
            "frame 1: no Content-Length header");
  EXPECT_EQ(error_of("\r\n"), "frame 1: no Content-Length header");
}

TEST(FrameParserMalformed, LengthNotANumber) {
  EXPECT_EQ(error_of("Content-Length: x\r\n\r\n"), "frame 1: Content-Length 'x' is not a number");
  EXPECT_EQ(error_of("Content-Length:\r\n\r\n"), "frame 1: Content-Length '' is not a number");
  EXPECT_EQ(error_of("Content-Length: 12abc\r\n"),
            "frame 1: Content-Length '12abc' is not a number");
  EXPECT_EQ(error_of("Content-Length: +5\r\n"), "frame 1: Content-Length '+5' is not a number");
  EXPECT_EQ(error_of("Content-Length: 1 2\r\n"), "frame 1: Content-Length '1 2' is not a number");
  EXPECT_EQ(error_of("Content-Length: -\r\n"), "frame 1: Content-Length '-' is not a number");
  // Bytes outside printable ASCII are shown as \xNN; long values are cut at 32 bytes.
  EXPECT_EQ(error_of("Content-Length: \xff\x01\\\r\n"),
            "frame 1: Content-Length '\\xff\\x01\\x5c' is not a number");
  EXPECT_EQ(error_of("Content-Length: " + std::string(40, 'z') + "\r\n"),
            "frame 1: Content-Length '" + std::string(32, 'z') + "'... is not a number");
}

TEST(FrameParserMalformed, ErrorNamesTheFrame) {
  std::string input = frame("{}") + frame("[]") + "Content-Length: x\r\n\r\n";
  Outcome out = parse_whole(input);
  EXPECT_EQ(out.bodies, (std::vector<std::string>{"{}", "[]"}));
  EXPECT_EQ(out.error, "frame 3: Content-Length 'x' is not a number");
  EXPECT_EQ(parse_bytewise(input), out);
}

TEST(FrameParserMalformed, NegativeLength) {
  EXPECT_EQ(error_of("Content-Length: -5\r\n\r\n"), "frame 1: Content-Length '-5' is negative");
  EXPECT_EQ(error_of("Content-Length: -0\r\n\r\n"), "frame 1: Content-Length '-0' is negative");
}

TEST(FrameParserMalformed, LengthOverTheLimit) {
  // kMaxBody = 64 MiB = 67108864 bytes.
  EXPECT_EQ(error_of("Content-Length: 67108865\r\n\r\n"),
            "frame 1: Content-Length '67108865' is over the limit of 67108864 bytes");
  // Past 2^64, where a careless parse would wrap around to a small number.
  EXPECT_EQ(error_of("Content-Length: 18446744073709551618\r\n\r\n"),
            "frame 1: Content-Length '18446744073709551618' is over the limit of 67108864 bytes");
}

TEST(FrameParserMalformed, DuplicateLengthWithDifferentValues) {
  EXPECT_EQ(error_of("Content-Length: 2\r\ncontent-length: 3\r\n\r\n{}"),
            "frame 1: Content-Length given twice with different values, 2 and 3");
  // The same value twice (even spelled differently) is fine.
  Outcome out = parse_whole("Content-Length: 2\r\nContent-Length: 02\r\n\r\n{}");
  EXPECT_EQ(out.bodies, (std::vector<std::string>{"{}"}));
  EXPECT_EQ(out.error, "");
}

TEST(FrameParserMalformed, HeaderLineWithoutColon) {
  EXPECT_EQ(error_of("Content-Length 2\r\n\r\n{}"),
            "frame 1: header line 'Content-Length 2' has no ':'");
  // A body sent without its header: the JSON's first line has no ':' before its end.
  EXPECT_EQ(error_of(frame("{}") + "[1, 2]\r\n"), "frame 2: header line '[1, 2]' has no ':'");
}

TEST(FrameParserMalformed, HeaderBlockOverTheLimit) {
  // A block of exactly kMaxHeader = 8192 bytes: "Content-Length: 2\r\n" (19), "X: " (3), the
  // filler, "\r\n" (2) and the empty line (2).
  auto block = [](size_t filler) {
    return "Content-Length: 2\r\nX: " + std::string(filler, 'f') + "\r\n\r\n";
  };
  ASSERT_EQ(block(8166).size(), FrameParser::kMaxHeader);
  Outcome out = parse_whole(block(8166) + "{}");
  EXPECT_EQ(out.bodies, (std::vector<std::string>{"{}"}));
  EXPECT_EQ(out.error, "");
  EXPECT_EQ(error_of(block(8167) + "{}"), "frame 1: header block over 8192 bytes");

  // A line that never ends is refused at its 8193rd byte, without waiting for more.
  FrameParser parser;
  parser.feed(std::string(8192, 'a'));
  EXPECT_EQ(parser.next(), std::nullopt);
  EXPECT_FALSE(parser.malformed());
  parser.feed("a");
  EXPECT_EQ(parser.next(), std::nullopt);
  EXPECT_TRUE(parser.malformed());
  EXPECT_EQ(parser.error(), "frame 1: header block over 8192 bytes");
}

TEST(FrameParserMalformed, LineEndingsAreStrictCrLf) {
  EXPECT_EQ(error_of("Content-Length: 2\n\n{}"),
            "frame 1: header line ends with a bare LF (header lines end with CR LF)");
  EXPECT_EQ(error_of("Content-Length: 2\r\n\n{}"),
            "frame 1: header line ends with a bare LF (header lines end with CR LF)");
  EXPECT_EQ(error_of("Content-Length: 2\r\r\n\r\n{}"),
            "frame 1: header line has a CR not followed by LF (header lines end with CR LF)");
  // Refused at the byte after the CR, not later.
  FrameParser parser;
  parser.feed("Content-Length: 2\rX");
  EXPECT_EQ(parser.next(), std::nullopt);
  EXPECT_TRUE(parser.malformed());
}

TEST(FrameParserMalformed, StaysMalformed) {
  FrameParser parser;
  parser.feed("Content-Length: -1\r\n\r\n");
  EXPECT_EQ(parser.next(), std::nullopt);
  ASSERT_TRUE(parser.malformed());
  std::string error = parser.error();
  EXPECT_EQ(error, "frame 1: Content-Length '-1' is negative");
  parser.feed(frame("{}"));
  EXPECT_EQ(parser.next(), std::nullopt);
  EXPECT_TRUE(parser.malformed());
  EXPECT_EQ(parser.error(), error);
}

// Every split of a stream into two or three feeds gives what one feed gives: good frames
// around a multibyte body, then each kind of malformed tail.
TEST(FrameParser, AnySplitGivesTheSameOutcome) {
  std::string good = frame(kInitialize) + "X-A: 1\r\n" + frame("\"\xc3\xa9\"") + frame("");
  std::vector<std::string> tails = {"",
                                    "Content-Length: 3\r\n\r\n[1",
                                    "Content-Length: q\r\n\r\n{}",
                                    "Content-Length: 2\n\n{}",
                                    "Content-Length: 2\r\rx",
                                    "no colon\r\n\r\n",
                                    "Content-Length: 1\r\nContent-Length: 2\r\n\r\n{}",
                                    "X: y\r\n\r\n"};
  for (const std::string& tail : tails) {
    std::string input = good + tail;
    Outcome whole = parse_whole(input);
    EXPECT_EQ(whole.bodies.size(), 3u) << tail;
    for (size_t i = 0; i <= input.size(); ++i) {
      for (size_t j = i; j <= input.size(); j += 7) {
        Outcome split = parse_pieces({input.substr(0, i), input.substr(i, j - i), input.substr(j)});
        ASSERT_EQ(split, whole) << "tail " << tail << ", split at " << i << " and " << j;
      }
    }
  }
}

TEST(Frame, WritesTheLengthInBytes) {
  EXPECT_EQ(frame("{}"), "Content-Length: 2\r\n\r\n{}");
  EXPECT_EQ(frame(""), "Content-Length: 0\r\n\r\n");
  EXPECT_EQ(frame("\"\xe2\x9c\x93\""), "Content-Length: 5\r\n\r\n\"\xe2\x9c\x93\"");
}

TEST(Frame, RoundTripsThroughTheParser) {
  std::vector<std::string> bodies = {kInitialize, "", "\r\n\r\n", std::string(100000, 'b'),
                                     "{\"s\":\"\xf0\x9f\x98\x80\"}"};
  std::string stream;
  for (const std::string& body : bodies) stream += frame(body);
  Outcome out = parse_whole(stream);
  EXPECT_EQ(out.bodies, bodies);
  EXPECT_EQ(out.error, "");
}

// A pipe whose read end is closed at the end of the test.
class Pipe {
 public:
  Pipe() { EXPECT_EQ(pipe(fds_), 0); }
  ~Pipe() {
    close(fds_[0]);
    if (fds_[1] >= 0) close(fds_[1]);
  }
  int read_end() const { return fds_[0]; }
  // Writes `bytes` in pieces of `piece` bytes from another thread, then closes the write end.
  std::thread write_and_close(std::string bytes, size_t piece) {
    int fd = fds_[1];
    fds_[1] = -1;
    return std::thread([fd, bytes = std::move(bytes), piece] {
      for (size_t at = 0; at < bytes.size();) {
        size_t n = std::min(piece, bytes.size() - at);
        ssize_t written = write(fd, bytes.data() + at, n);
        if (written <= 0) break;
        at += static_cast<size_t>(written);
      }
      close(fd);
    });
  }

 private:
  int fds_[2] = {-1, -1};
};

TEST(ReadMessage, ReadsBodiesFromAPipeUntilEndOfInput) {
  // The large body is over a pipe's buffer (64 KiB on Linux), so the writer blocks until the
  // reader drains it, and the body arrives over several reads.
  std::string large = "[" + std::string(200000, '1') + "]";
  std::vector<std::string> bodies = {kInitialize, large, "{}", "\"\xc3\xa9\""};
  std::string stream;
  for (const std::string& body : bodies) stream += frame(body);
  for (size_t piece : {size_t{1}, size_t{5}, size_t{4096}, stream.size()}) {
    Pipe pipe;
    std::thread writer = pipe.write_and_close(stream, piece);
    FrameParser parser;
    std::vector<std::string> read;
    while (std::optional<std::string> body = read_message(pipe.read_end(), parser))
      read.push_back(*body);
    writer.join();
    EXPECT_EQ(read, bodies) << "pieces of " << piece;
    EXPECT_FALSE(parser.malformed());
    EXPECT_EQ(parser.error(), "");
    // After the end of input, more calls give the end again.
    EXPECT_EQ(read_message(pipe.read_end(), parser), std::nullopt);
  }
}

TEST(ReadMessage, EndOfInputInsideAFrameIsNotMalformed) {
  Pipe pipe;
  std::thread writer = pipe.write_and_close(frame("{}") + "Content-Length: 10\r\n\r\n{\"a\"", 3);
  FrameParser parser;
  EXPECT_EQ(read_message(pipe.read_end(), parser), "{}");
  EXPECT_EQ(read_message(pipe.read_end(), parser), std::nullopt);
  writer.join();
  EXPECT_FALSE(parser.malformed());
}

TEST(ReadMessage, MalformedFrameStopsTheReading) {
  Pipe pipe;
  std::thread writer =
      pipe.write_and_close(frame("{}") + "Content-Length: 2\r\nbroken\r\n\r\n{}" + frame("[]"), 2);
  FrameParser parser;
  EXPECT_EQ(read_message(pipe.read_end(), parser), "{}");
  EXPECT_EQ(read_message(pipe.read_end(), parser), std::nullopt);
  EXPECT_TRUE(parser.malformed());
  EXPECT_EQ(parser.error(), "frame 2: header line 'broken' has no ':'");
  EXPECT_EQ(read_message(pipe.read_end(), parser), std::nullopt);
  writer.join();
}

std::atomic<int> signals_seen{0};
void count_signal(int) { signals_seen.fetch_add(1); }

TEST(ReadMessage, RetriesAReadInterruptedByASignal) {
  // A handler installed without SA_RESTART makes a blocked read(2) fail with EINTR.
  struct sigaction action = {}, previous = {};
  action.sa_handler = count_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;
  ASSERT_EQ(sigaction(SIGUSR1, &action, &previous), 0);
  signals_seen = 0;

  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  pthread_t reader = pthread_self();
  std::thread writer([&] {
    // The reader is blocked in read(2) well before these (it has nothing else to do).
    for (int i = 0; i < 3; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(30));
      pthread_kill(reader, SIGUSR1);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
    std::string bytes = frame("{}");
    EXPECT_EQ(write(fds[1], bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  });
  FrameParser parser;
  std::optional<std::string> body = read_message(fds[0], parser);
  writer.join();
  close(fds[0]);
  close(fds[1]);
  sigaction(SIGUSR1, &previous, nullptr);
  EXPECT_EQ(signals_seen.load(), 3);
  EXPECT_EQ(body, "{}");
  EXPECT_FALSE(parser.malformed());
}

}  // namespace
}  // namespace simit::dap
