// The Debug Adapter Protocol's base framing: the incremental frame parser, frame() and
// read_message().
#include "dap/framing.h"

#include <unistd.h>

#include <array>
#include <cerrno>

namespace simit::dap {

namespace {

constexpr std::string_view kContentLength = "content-length";

bool is_blank(char c) { return c == ' ' || c == '\t'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

bool equals_ignoring_case(std::string_view a, std::string_view lower) {
  if (a.size() != lower.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    char c = a[i];
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    if (c != lower[i]) return false;
  }
  return true;
}

// `text` in single quotes for an error message: at most 32 bytes, and every byte outside
// printable ASCII as \xNN, so that the message is valid UTF-8 (it may be sent back to the
// client inside JSON) and one line.
std::string quote(std::string_view text) {
  constexpr size_t kShown = 32;
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out = "'";
  for (size_t i = 0; i < text.size() && i < kShown; ++i) {
    unsigned char c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f && c != '\\') {
      out += static_cast<char>(c);
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0xf];
    }
  }
  out += '\'';
  if (text.size() > kShown) out += "...";
  return out;
}

// Content-Length's value (blanks trimmed): the length, or the reason it is not one.
struct ParsedLength {
  std::optional<size_t> value;
  std::string why;
};

ParsedLength parse_length(std::string_view text) {
  bool negative = !text.empty() && text.front() == '-';
  std::string_view digits = negative ? text.substr(1) : text;
  bool numeric = !digits.empty();
  bool too_large = false;
  size_t value = 0;
  for (char c : digits) {
    if (c < '0' || c > '9') {
      numeric = false;
      break;
    }
    // Stop accumulating past the limit: the digits that follow only make it larger.
    if (!too_large) {
      value = value * 10 + static_cast<size_t>(c - '0');
      too_large = value > FrameParser::kMaxBody;
    }
  }
  if (!numeric) return {std::nullopt, "Content-Length " + quote(text) + " is not a number"};
  if (negative) return {std::nullopt, "Content-Length " + quote(text) + " is negative"};
  if (too_large)
    return {std::nullopt, "Content-Length " + quote(text) + " is over the limit of " +
                              std::to_string(FrameParser::kMaxBody) + " bytes"};
  return {value, ""};
}

}  // namespace

void FrameParser::feed(std::string_view bytes) {
  if (malformed_) return;
  // Drop what is consumed before growing the buffer, so that it holds one partial frame
  // and whatever follows it, not the whole history.
  if (pos_ > 0) {
    buffer_.erase(0, pos_);
    pos_ = 0;
  }
  buffer_.append(bytes);
}

std::optional<std::string> FrameParser::next() {
  if (malformed_) return std::nullopt;
  if (!in_body_ && !read_header()) return std::nullopt;
  if (buffer_.size() - pos_ < *length_) return std::nullopt;
  std::string body = buffer_.substr(pos_, *length_);
  pos_ += *length_;
  ++frame_;
  line_.clear();
  after_cr_ = false;
  header_bytes_ = 0;
  in_body_ = false;
  length_.reset();
  return body;
}

bool FrameParser::read_header() {
  // A byte at a time, so that each error shows at the byte that reveals it whatever the
  // split of the input between feeds. line_ never holds more than kMaxHeader bytes.
  while (pos_ < buffer_.size()) {
    char c = buffer_[pos_++];
    if (++header_bytes_ > kMaxHeader) {
      fail("header block over " + std::to_string(kMaxHeader) + " bytes");
      return false;
    }
    if (c == '\n') {
      if (!after_cr_) {
        fail("header line ends with a bare LF (header lines end with CR LF)");
        return false;
      }
      after_cr_ = false;
      if (line_.empty()) {
        if (!length_) {
          fail("no Content-Length header");
          return false;
        }
        in_body_ = true;
        return true;
      }
      bool ok = header_line(line_);
      line_.clear();
      if (!ok) return false;
    } else if (after_cr_) {
      fail("header line has a CR not followed by LF (header lines end with CR LF)");
      return false;
    } else if (c == '\r') {
      after_cr_ = true;
    } else {
      line_ += c;
    }
  }
  return false;
}

bool FrameParser::header_line(std::string_view line) {
  size_t colon = line.find(':');
  if (colon == std::string_view::npos) {
    fail("header line " + quote(line) + " has no ':'");
    return false;
  }
  if (!equals_ignoring_case(trim(line.substr(0, colon)), kContentLength)) return true;
  ParsedLength parsed = parse_length(trim(line.substr(colon + 1)));
  if (!parsed.value) {
    fail(parsed.why);
    return false;
  }
  if (length_ && *length_ != *parsed.value) {
    fail("Content-Length given twice with different values, " + std::to_string(*length_) + " and " +
         std::to_string(*parsed.value));
    return false;
  }
  length_ = parsed.value;
  return true;
}

void FrameParser::fail(const std::string& what) {
  malformed_ = true;
  error_ = "frame " + std::to_string(frame_) + ": " + what;
  // Nothing more will be read: free the buffered input.
  buffer_.clear();
  buffer_.shrink_to_fit();
  pos_ = 0;
  line_.clear();
}

std::string frame(std::string_view body) {
  std::string out = "Content-Length: " + std::to_string(body.size()) + "\r\n\r\n";
  out.append(body);
  return out;
}

std::optional<std::string> read_message(int fd, FrameParser& parser) {
  std::array<char, 1 << 16> chunk;
  for (;;) {
    if (std::optional<std::string> body = parser.next()) return body;
    if (parser.malformed()) return std::nullopt;
    ssize_t n = ::read(fd, chunk.data(), chunk.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return std::nullopt;
    parser.feed(std::string_view(chunk.data(), static_cast<size_t>(n)));
  }
}

}  // namespace simit::dap
