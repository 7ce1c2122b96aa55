// The Debug Adapter Protocol's base framing: "Content-Length: N\r\n\r\n" then N bytes of
// JSON, parsed incrementally from a byte stream and written around outgoing bodies.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace simit::dap {

// An incremental parser: bytes in as they arrive (any split), whole message bodies out.
//
// A frame is a header block then a body. The header block is a sequence of lines, each ended
// by "\r\n", closed by an empty line; every line is "Name: value". Content-Length (the name in
// any case) gives the body's size in bytes; other fields are ignored; a repeated
// Content-Length must repeat the same value. Line endings are strict: a '\n' without '\r'
// before it, or a '\r' without '\n' after it, makes the stream malformed at once (rather than
// waiting for a "\r\n\r\n" that a client ending lines with "\n" would never send).
//
// The stream is also malformed when a frame has no Content-Length, a Content-Length that is
// not a decimal number, negative or over kMaxBody, a header line without ':', or a header
// block (its lines and the closing empty line, with their "\r\n") over kMaxHeader bytes.
// A malformed stream stays malformed: there is no way to find the next frame's start.
//
// The outcome does not depend on how the bytes are split between feed() calls: the header is
// read a byte at a time and each error is reported at the first byte that shows it.
class FrameParser {
 public:
  static constexpr size_t kMaxBody = 64 << 20;  // larger Content-Length: malformed
  static constexpr size_t kMaxHeader = 8192;    // a header block longer: malformed

  // Buffers `bytes`; parsing happens in next(). Ignored once malformed.
  void feed(std::string_view bytes);
  // The next complete body, if one is buffered. Once malformed, always nullopt.
  std::optional<std::string> next();
  bool malformed() const { return malformed_; }
  // What was wrong, e.g. "frame 3: Content-Length 'x' is not a number"; empty while the
  // stream is well formed. Frames are counted from 1.
  const std::string& error() const { return error_; }

 private:
  // Reads header bytes from the buffer; true once the header block is complete.
  bool read_header();
  // Handles one complete header line (without its "\r\n"); false once malformed.
  bool header_line(std::string_view line);
  void fail(const std::string& what);

  std::string buffer_;  // bytes fed and not yet consumed start at pos_
  size_t pos_ = 0;
  size_t frame_ = 1;  // the frame being read, counted from 1

  // The current frame's header, read so far.
  std::string line_;              // the current line's bytes before any '\r'
  bool after_cr_ = false;         // the last header byte was '\r'
  size_t header_bytes_ = 0;       // bytes of the header block consumed
  bool in_body_ = false;          // the header block is complete
  std::optional<size_t> length_;  // Content-Length, once given

  bool malformed_ = false;
  std::string error_;
};

// Content-Length header + body.
std::string frame(std::string_view body);

// Reads from file descriptor `fd` (blocking, read(2), EINTR retried) until the parser
// yields a body: the body; nullopt at end of input or on a malformed frame (parser.malformed()
// tells which; error() says why). Bodies already buffered in the parser come first, without a
// read. A read error other than EINTR counts as end of input, as does an end of input in the
// middle of a frame (the partial frame is dropped).
std::optional<std::string> read_message(int fd, FrameParser& parser);

}  // namespace simit::dap
