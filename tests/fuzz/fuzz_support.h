// What the libFuzzer harnesses share: a scratch folder for readers that take paths, splitting
// one input into several files, and stopping with a message when an invariant breaks.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace simit::fuzz {

// The input as text (any bytes, NULs included).
std::string_view as_text(const uint8_t* data, size_t size);

// Splits `text` at every `separator`; the last part takes the rest once there are `max_parts`.
std::vector<std::string_view> split_parts(std::string_view text, char separator, size_t max_parts);

// A folder of this process, made on first use and removed when the process exits.
const std::string& scratch_folder();
// Writes `bytes` to scratch_folder()/name, replacing the file; returns the path.
std::string write_scratch(const std::string& name, std::string_view bytes);
// Removes scratch_folder()/name if it is there.
void remove_scratch(const std::string& name);

// With SIMIT_FUZZ_VERBOSE set, prints why an input was rejected (for checking that seeds
// reach past the first error); otherwise nothing.
void note_rejected(const char* harness, const std::string& why);

// Reports a broken invariant of `harness` and aborts, which libFuzzer records as a crash.
[[noreturn]] void invariant_broken(const char* harness, const std::string& what);

}  // namespace simit::fuzz
