// The kernel cache's target-neutral half: the text a compiled kernel is keyed by (every field
// of a trace that decides its code), and the entry files of the cache folder (their format,
// their checks, and writes that no reader ever sees half done). A target hashes the key text
// together with what it compiles for and keeps its object code here (docs/jit.md, "Kernel
// cache").
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "jit/loop_ir.h"
#include "jit/target.h"

namespace simit::jit {

// Bumped whenever the code generated for the same trace changes (the emitter, the pipeline,
// the calling convention), so that no run loads the code of an older generator.
inline constexpr int kKernelFormatVersion = 14;
// The cache folder's size limit: a store that takes it above this removes the entries used
// least recently (a load marks an entry used) until the folder holds three quarters of it.
inline constexpr uint64_t kKernelCacheMaxBytes = uint64_t{256} << 20;

// Every field of a trace that decides its code, as text: structure, types, constants (their
// exact bits), slots and flags; not its name, source spans or error messages (a kernel reports
// an error by its index), so a kernel keeps its key when the lines above it move. A node that
// several expressions share is written once and then referred to by number: the emitter
// computes a shared node once, so sharing decides code too.
std::string kernel_key_text(const Trace& t);
std::string kernel_key_text(const SystemTrace& t);

// One entry: the name of the kernel's function, its relocatable object code, and what its
// compile found of its loops (simd_report_text), which a kernel loaded from the cache reports.
struct CacheEntry {
  std::string symbol;
  std::string object;
  std::string simd = {};
};

// A kernel's SimdReport as an entry keeps it (lines of text), and read back: false when the
// text is not one.
std::string simd_report_text(const SimdReport& r);
bool read_simd_report(const std::string& text, SimdReport& r);

// A folder of entries, one file per key digest: `<folder>/<64 hex digits>.o`. The file holds a
// header (magic, file format version, the lengths, an FNV-1a 64 checksum of the symbol, object
// and report, the key digest again), the symbol, the report, then the object. A reader takes
// a file only when all of these agree; anything else (truncated, garbage, another key, an
// older file format) is no entry.
class KernelCache {
 public:
  static constexpr size_t kDigestBytes = 32;

  // An empty folder: no cache (load finds nothing, store writes nothing).
  explicit KernelCache(std::string folder) : folder_(std::move(folder)) {}

  bool enabled() const { return !folder_.empty(); }
  const std::string& folder() const { return folder_; }
  // The entry file of a digest of kDigestBytes bytes.
  std::string path_of(const std::string& digest) const;

  // The entry stored for `digest`, or nullopt when there is none or it is corrupt.
  std::optional<CacheEntry> load(const std::string& digest) const;
  // Writes the entry for `digest` atomically: into a temporary file of a unique name in the
  // same folder (made, with its parents, when missing), then renamed over the entry's name, so
  // a reader sees the old file or the whole new one, and concurrent writers of the same key
  // leave one whole entry. False with `error` set when something could not be written (the
  // temporary file is removed).
  bool store(const std::string& digest, const CacheEntry& entry, std::string& error) const;
  // Keeps the folder within `max_bytes` (store calls it with kKernelCacheMaxBytes): removes
  // entries, the least recently used first, until it holds at most three quarters of it, and
  // temporary files a killed writer left more than an hour ago. Returns the entries removed.
  int prune(uint64_t max_bytes) const;

 private:
  std::string folder_;
};

// Lower-case hex of bytes.
std::string hex_of(const std::string& bytes);
// FNV-1a, 64 bits (the entries' payload checksum).
uint64_t fnv1a64(const char* data, size_t size, uint64_t seed = 0xcbf29ce484222325ull);

}  // namespace simit::jit
