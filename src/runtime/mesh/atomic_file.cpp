// Temporary-file-and-rename writing with every failure reported.
#include "runtime/mesh/atomic_file.h"

#include <sys/stat.h>
#include <unistd.h>
#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "runtime/mesh/mesh.h"

namespace simit::runtime {

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)), temp_path_(path_ + ".XXXXXX") {
  int fd = mkstemp(temp_path_.data());
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
    errno = saved;
    fail("cannot open the temporary file");
  }
}

AtomicFile::~AtomicFile() {
  if (file_) std::fclose(file_);
  if (!committed_ && !temp_path_.empty()) std::remove(temp_path_.c_str());
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
