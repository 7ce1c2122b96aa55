// --check-ptx and --dump=ptx (jit/ptx/ptx_check.h): the GPU target per architecture, ptxas
// run as a child process on a temporary file, and the process's tally.
#include "jit/ptx/ptx_check.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>

#include "jit/ptx/ptx_target.h"

extern char** environ;

namespace simit::jit::ptx {

namespace {

namespace fs = std::filesystem;

constexpr const char* kToolkitPtxas = "/usr/local/cuda/bin/ptxas";

bool executable(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(path.c_str(), X_OK) == 0;
}

struct Tally {
  std::mutex mu;
  long assembled = 0;
  long rejected = 0;                    // by ptxas (the run stops at the first)
  std::map<std::string, long> refused;  // by reason
};

Tally& tally() {
  static Tally t;
  return t;
}

void note_refused(const std::string& why) {
  std::lock_guard<std::mutex> lock(tally().mu);
  ++tally().refused[why];
}

// The GPU target for `arch`, made once per architecture; null with `error`.
Target* target_for(const std::string& arch, std::string& error) {
  static std::mutex mu;
  static std::map<std::string, std::pair<std::unique_ptr<Target>, std::string>> targets;
  std::lock_guard<std::mutex> lock(mu);
  auto it = targets.find(arch);
  if (it == targets.end()) {
    std::string why;
    auto t = make_ptx_target(arch, why);
    it = targets.emplace(arch, std::make_pair(std::move(t), why)).first;
  }
  error = it->second.second;
  return it->second.first.get();
}

// A temporary folder, removed with its files.
struct TempFolder {
  std::string path;
  TempFolder() {
    std::string pattern = (fs::temp_directory_path() / "simit_ptxas_XXXXXX").string();
    if (::mkdtemp(pattern.data())) path = pattern;
  }
  ~TempFolder() {
    std::error_code ec;
    if (!path.empty()) fs::remove_all(path, ec);
  }
};

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string trimmed(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

template <class T>
std::string check(const T& t, const std::string& site, const CheckOptions& o) {
  const std::string arch = o.gpu_arch.empty() ? kDefaultGpuArch : o.gpu_arch;
  std::string error;
  Target* target = target_for(arch, error);
  if (!target) return "--check-ptx: no GPU target: " + error;
  if (std::string why = gpu_refusal(t); !why.empty()) {
    note_refused(why);
    if (o.dump) *o.dump << "// " << site << ": not compiled for the GPU: " << why << "\n";
    return "";
  }
  std::unique_ptr<Kernel> k = target->compile(t, false, error);
  const auto* kernel = dynamic_cast<const PtxKernel*>(k.get());
  if (!kernel) return "--check-ptx: " + site + " did not compile for the GPU: " + error;
  if (o.dump) *o.dump << "// PTX of " << site << "\n" << kernel->ptx;
  if (!o.assemble) return "";
  std::string why;
  const std::string ptxas = find_ptxas(why);
  if (ptxas.empty()) return "--check-ptx: " + why;
  std::string message;
  const bool accepted = assemble(ptxas, kernel->ptx, arch, message);
  std::lock_guard<std::mutex> lock(tally().mu);
  if (!accepted) {
    ++tally().rejected;
    return "--check-ptx: ptxas rejected the PTX of " + site + ": " + message;
  }
  ++tally().assembled;
  return "";
}

}  // namespace

std::string find_ptxas(std::string& why) {
  if (const char* given = std::getenv("SIMIT_PTXAS"); given && *given) {
    if (executable(given)) return given;
    why = std::string("SIMIT_PTXAS=") + given + " is not an executable file";
    return "";
  }
  if (const char* path = std::getenv("PATH")) {
    std::stringstream dirs(path);
    for (std::string dir; std::getline(dirs, dir, ':');) {
      const std::string candidate = (dir.empty() ? std::string(".") : dir) + "/ptxas";
      if (executable(candidate)) return candidate;
    }
  }
  if (executable(kToolkitPtxas)) return kToolkitPtxas;
  why = std::string("ptxas not found ($SIMIT_PTXAS, PATH, ") + kToolkitPtxas +
        "): --check-ptx needs the CUDA toolkit's PTX assembler (set SIMIT_PTXAS to it)";
  return "";
}

bool assemble(const std::string& ptxas, const std::string& ptx, const std::string& gpu_arch,
              std::string& message) {
  TempFolder dir;
  if (dir.path.empty()) {
    message = std::string("cannot make a temporary folder: ") + std::strerror(errno);
    return false;
  }
  const std::string in = dir.path + "/kernel.ptx", out = dir.path + "/kernel.o",
                    log = dir.path + "/ptxas.log";
  {
    std::ofstream f(in, std::ios::binary);
    f << ptx;
    if (!f.flush()) {
      message = "cannot write " + in;
      return false;
    }
  }
  // A whole module (the math functions linked in, jit/ptx/device_math.h) is assembled as a
  // program; one that still calls an external function only as relocatable code (-c).
  std::vector<std::string> args = {ptxas, "--gpu-name", gpu_arch, in, "-o", out};
  if (ptx.find(".extern .func") != std::string::npos) args.insert(args.begin() + 3, "-c");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, ptxas.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    message = "cannot run " + ptxas + ": " + std::strerror(spawned);
    return false;
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) {
      message = std::string("waiting for ptxas: ") + std::strerror(errno);
      return false;
    }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return true;
  message = trimmed(read_file(log));
  if (message.empty())
    message = WIFSIGNALED(status)
                  ? "ptxas was killed by signal " + std::to_string(WTERMSIG(status))
                  : "ptxas exited with status " + std::to_string(WEXITSTATUS(status));
  return false;
}

std::string check_trace(const Trace& t, const std::string& site, const CheckOptions& o) {
  return check(t, site, o);
}

// A system trace runs on the GPU as a device program (jit/device_program.h): checked so,
// whichever executor this run compiled it for.
std::string check_trace(const SystemTrace& t, const std::string& site, const CheckOptions& o) {
  if (t.device) return check(t, site, o);
  SystemTrace device = t;
  device.device = true;
  return check(device, site, o);
}

std::string tally_summary() {
  std::lock_guard<std::mutex> lock(tally().mu);
  long refused = 0;
  std::string reasons;
  for (const auto& [why, n] : tally().refused) {
    refused += n;
    reasons += (reasons.empty() ? "" : "; ") + std::to_string(n) + ": " + why;
  }
  std::string s = "check-ptx: " + std::to_string(tally().assembled) + " trace" +
                  (tally().assembled == 1 ? "" : "s") + " assembled by ptxas, " +
                  std::to_string(refused) + " not compiled for the GPU";
  if (!reasons.empty()) s += " (" + reasons + ")";
  if (tally().rejected > 0) s += ", " + std::to_string(tally().rejected) + " rejected by ptxas";
  if (tally().assembled == 0 && refused == 0 && tally().rejected == 0)
    s += " (the run compiled no trace: the JIT compiles them under --executor jit)";
  return s;
}

void reset_tally() {
  std::lock_guard<std::mutex> lock(tally().mu);
  tally().assembled = 0;
  tally().rejected = 0;
  tally().refused.clear();
}

}  // namespace simit::jit::ptx
