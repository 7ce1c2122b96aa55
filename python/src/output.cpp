// What programs print, written to Python's sys.stdout line by line (so that notebooks and
// redirect_stdout see it), also while a run has released the GIL.
#include <mutex>
#include <streambuf>

#include "common.h"

namespace simit::python {

namespace {

class SysStdout : public std::streambuf {
 protected:
  int overflow(int c) override {
    if (c == traits_type::eof()) return 0;
    std::lock_guard<std::mutex> lock(mutex_);
    line_ += static_cast<char>(c);
    if (c == '\n') write_line();
    return c;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    std::lock_guard<std::mutex> lock(mutex_);
    for (std::streamsize i = 0; i < n; ++i) {
      line_ += s[i];
      if (s[i] == '\n') write_line();
    }
    return n;
  }
  int sync() override {
    std::lock_guard<std::mutex> lock(mutex_);
    write_line();
    return 0;
  }

 private:
  // Runs on the thread that runs the program, which may have released the GIL.
  void write_line() {
    if (line_.empty() || !Py_IsInitialized()) return;
    py::gil_scoped_acquire gil;
    try {
      py::module_::import("sys").attr("stdout").attr("write")(line_);
    } catch (const py::error_already_set&) {  // no usable sys.stdout: the text is dropped
    }
    line_.clear();
  }
  std::mutex mutex_;
  std::string line_;
};

}  // namespace

std::ostream& python_stdout() {
  // Never destroyed: runs may print until the interpreter exits.
  static auto* buf = new SysStdout();
  static auto* stream = new std::ostream(buf);
  return *stream;
}

}  // namespace simit::python
