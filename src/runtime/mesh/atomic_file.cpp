// Temporary-file-and-rename writing with every failure reported.
#include "runtime/mesh/atomic_file.h"

#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>

#include "runtime/mesh/mesh.h"

namespace simit::runtime {

namespace {

// The temporaries being written, where a signal handler may read them: fixed buffers (a
// handler cannot touch std::string) and a flag per slot set only once the path is complete.
constexpr int kSlots = 8;
constexpr size_t kPathMax = 4096;
char g_temp_paths[kSlots][kPathMax];
// Claimed by compare-and-swap: a scene's frames are written on a thread of their own while
// the main thread may write another file (scene/frame_writer.h). Lock-free, so a handler may
// read them.
std::atomic<int> g_slot_used[kSlots];
static_assert(std::atomic<int>::is_always_lock_free);

// Creates the temporary (mkstemp) in a slot's buffer, so that a signal finds its name from the
// moment the file exists. Returns the descriptor (or -1) and sets `slot` (-1 when every slot
// is taken or the path is too long: the file is then only removed by the destructor).
int create_in_slot(std::string& temp, int& slot) {
  slot = -1;
  if (temp.size() < kPathMax)
    for (int i = 0; i < kSlots && slot < 0; ++i) {
      int free = 0;
      if (g_slot_used[i].compare_exchange_strong(free, 1)) slot = i;  // 1: claimed, no path yet
    }
  if (slot < 0) return mkstemp(temp.data());
  char* buffer = g_temp_paths[slot];
  std::memcpy(buffer, temp.c_str(), temp.size() + 1);
  std::atomic_signal_fence(std::memory_order_seq_cst);
  g_slot_used[slot].store(2);  // until then the handler ignores the buffer; after, it may see
                               // the template (no such file) or the name chosen
  const int fd = mkstemp(buffer);
  std::memcpy(temp.data(), buffer, temp.size());
  if (fd < 0) {
    g_slot_used[slot].store(0);
    slot = -1;
  }
  return fd;
}

void release_slot(int slot) {
  if (slot >= 0) g_slot_used[slot].store(0);
}

extern "C" void remove_temporaries_and_die(int sig) {
  for (int i = 0; i < kSlots; ++i)
    if (g_slot_used[i].load() == 2) unlink(g_temp_paths[i]);  // async-signal-safe
  // SA_RESETHAND restored the default action; the signal is delivered once the handler returns.
  raise(sig);
}

}  // namespace

void remove_temporaries_on_signals() {
  for (int sig : {SIGINT, SIGTERM}) {
    struct sigaction old {};
    if (sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    struct sigaction action {};
    action.sa_handler = remove_temporaries_and_die;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESETHAND;
    sigaction(sig, &action, nullptr);
  }
}

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)), temp_path_(path_ + ".XXXXXX") {
  int fd = create_in_slot(temp_path_, slot_);
  if (fd < 0) {
    temp_path_.clear();
    fail("cannot create a temporary file beside it");
  }
  // mkstemp makes the file private; the result is an ordinary output file.
  fchmod(fd, 0644);
  file_ = fdopen(fd, "wb");
  if (!file_) {
    int saved = errno;
    close(fd);
    std::remove(temp_path_.c_str());
    release_slot(slot_);  // the destructor does not run after a throwing constructor
    errno = saved;
    fail("cannot open the temporary file");
  }
}

AtomicFile::~AtomicFile() {
  if (file_) std::fclose(file_);
  if (!committed_ && !temp_path_.empty()) std::remove(temp_path_.c_str());
  release_slot(slot_);  // after the removal: a signal in between finds the file gone
}

void AtomicFile::write(const void* data, size_t bytes) {
  if (bytes == 0) return;
  if (std::fwrite(data, 1, bytes, file_) != bytes) fail("cannot write");
}

void AtomicFile::commit() {
  std::FILE* f = file_;
  file_ = nullptr;
  if (std::fclose(f) != 0) fail("cannot write");
  if (std::rename(temp_path_.c_str(), path_.c_str()) != 0)
    fail("cannot rename the temporary file onto it");
  committed_ = true;
}

void AtomicFile::fail(const char* what) {
  throw MeshError(path_, 0, std::string(what) + ": " + std::strerror(errno));
}

}  // namespace simit::runtime
