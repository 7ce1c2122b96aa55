// A file written under a temporary name in its destination folder and renamed into place only
// when complete, so a reader (or a crash) never sees a half-written file.
#pragma once

#include <cstddef>
#include <cstdio>
#include <string>
#include <string_view>

namespace simit::runtime {

class AtomicFile {
 public:
  // Creates PATH.XXXXXX beside `path`; throws MeshError when it cannot.
  explicit AtomicFile(std::string path);
  ~AtomicFile();  // removes the temporary file unless committed
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  void write(const void* data, size_t bytes);
  void write(std::string_view text) { write(text.data(), text.size()); }
  // Flushes, closes and renames onto the destination; throws MeshError on any failure.
  void commit();

 private:
  [[noreturn]] void fail(const char* what);

  std::string path_;
  std::string temp_path_;
  std::FILE* file_ = nullptr;
  bool committed_ = false;
  int slot_ = -1;  // where the signal handler finds temp_path_ (see remove_temporaries_on_signals)
};

// Installs SIGINT and SIGTERM handlers that remove the temporary files of the AtomicFiles being
// written at that moment and then end the process by the same signal, so that a killed run
// leaves no PATH.XXXXXX behind. A signal the process ignores (a background job's SIGINT) stays
// ignored. Call once, before writing; process-wide.
void remove_temporaries_on_signals();

}  // namespace simit::runtime
