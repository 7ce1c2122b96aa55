// Scratch files and invariant reports for the libFuzzer harnesses.
#include "fuzz_support.h"

#include <unistd.h>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace simit::fuzz {

namespace fs = std::filesystem;

namespace {

// Removes the folder at exit: a fuzzing run executes the harness millions of times, and a
// replay under ctest should leave the temporary folder as it found it.
struct ScratchFolder {
  std::string path;
  ScratchFolder() {
    std::string pattern = (fs::temp_directory_path() / "simit-fuzz-XXXXXX").string();
    if (!mkdtemp(pattern.data())) throw std::runtime_error("cannot make a scratch folder");
    path = pattern;
  }
  ~ScratchFolder() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

}  // namespace

std::string_view as_text(const uint8_t* data, size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

std::vector<std::string_view> split_parts(std::string_view text, char separator, size_t max_parts) {
  std::vector<std::string_view> parts;
  while (parts.size() + 1 < max_parts) {
    size_t at = text.find(separator);
    if (at == std::string_view::npos) break;
    parts.push_back(text.substr(0, at));
    text.remove_prefix(at + 1);
  }
  parts.push_back(text);
  return parts;
}

const std::string& scratch_folder() {
  static ScratchFolder folder;
  return folder.path;
}

std::string write_scratch(const std::string& name, std::string_view bytes) {
  std::string path = scratch_folder() + "/" + name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) invariant_broken("fuzz_support", "cannot write the scratch file " + path);
  return path;
}

void remove_scratch(const std::string& name) {
  std::error_code ec;
  fs::remove(scratch_folder() + "/" + name, ec);
}

void note_rejected(const char* harness, const std::string& why) {
  static const bool verbose = std::getenv("SIMIT_FUZZ_VERBOSE") != nullptr;
  if (verbose) std::fprintf(stderr, "%s: rejected: %s\n", harness, why.c_str());
}

void invariant_broken(const char* harness, const std::string& what) {
  std::fprintf(stderr, "%s: %s\n", harness, what.c_str());
  std::abort();
}

}  // namespace simit::fuzz
