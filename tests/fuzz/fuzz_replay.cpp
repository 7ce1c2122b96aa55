// Replays input files and deterministic mutations of them through a fuzz target (linked in
// beside this driver), so that ordinary builds (any compiler, no libFuzzer) exercise every
// harness and its invariants, and every regression input stays fixed.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace {

namespace fs = std::filesystem;

constexpr unsigned kSeed = 20240611;
constexpr int kFlipVariants = 12;
constexpr int kTruncations = 8;
// Bytes that tend to reach interesting parser and lexer states in every format fuzzed:
// Simit, TOML, mesh files, literals, debugger commands.
constexpr std::string_view kAlphabet = "%!{}[]()<>;,.:'\"=+-*/\\^#$@ \n\t0123456789eE_azZvf";

void feed(const std::string& text) {
  LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

// Every file under `roots` (files or folders) whose extension is one of `extensions` (any
// extension when there are none).
std::vector<std::string> input_files(const std::vector<std::string>& roots,
                                     const std::vector<std::string>& extensions) {
  auto wanted = [&](const fs::path& p) {
    return extensions.empty() || std::find(extensions.begin(), extensions.end(),
                                           p.extension().string()) != extensions.end();
  };
  std::vector<std::string> files;
  for (const auto& root : roots) {
    if (fs::is_regular_file(root)) files.push_back(root);
    if (!fs::is_directory(root)) continue;
    for (const auto& e : fs::recursive_directory_iterator(root))
      if (e.is_regular_file() && wanted(e.path())) files.push_back(e.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Prefixes of the text: cut mid-token, mid-statement, mid-comment.
int feed_truncations(const std::string& text) {
  for (int i = 1; i <= kTruncations; ++i)
    feed(text.substr(0, text.size() * i / (kTruncations + 1)));
  return kTruncations;
}

// Copies with a few bytes replaced, deleted or duplicated.
int feed_mutations(const std::string& text, std::mt19937& rng) {
  if (text.empty()) return 0;
  for (int v = 0; v < kFlipVariants; ++v) {
    std::string m = text;
    int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits && !m.empty(); ++e) {
      size_t at = rng() % m.size();
      switch (rng() % 4) {
        case 0: m[at] = kAlphabet[rng() % kAlphabet.size()]; break;
        case 1: m.erase(at, 1 + rng() % 8); break;
        case 2: m.insert(at, m.substr(rng() % m.size(), 1 + rng() % 16)); break;
        default: m[at] = static_cast<char>(rng() & 0xff); break;
      }
    }
    feed(m);
  }
  return kFlipVariants;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string name = fs::path(argv[0]).filename().string();
  std::vector<std::string> roots, extensions;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--ext" && i + 1 < argc)
      extensions.push_back(argv[++i]);
    else
      roots.push_back(a);
  }
  if (roots.empty()) {
    std::cerr << "usage: " << name << " [--ext .EXT]... PATH...  (files or folders)\n";
    return 2;
  }
  std::vector<std::string> files = input_files(roots, extensions);
  if (files.empty()) {
    std::cerr << name << ": no input files found\n";
    return 1;
  }
  std::mt19937 rng(kSeed);
  long inputs = 0;
  for (const auto& file : files) {
    std::string text = read(file);
    feed(text);
    inputs += 1 + feed_truncations(text) + feed_mutations(text, rng);
  }
  std::cout << name << ": " << inputs << " inputs from " << files.size() << " files, no crash\n";
  return 0;
}
