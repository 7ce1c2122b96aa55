// The GPU probe: the driver's and the device's properties, then empty-kernel launches, a graph
// of kernels, a fill kernel and copies timed through the driver layer, printed as Markdown.
#include "jit/ptx/gpu_probe.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <optional>
#include <utility>

namespace simit::jit::cuda {
namespace {

const char* const kUsage =
    R"(Usage: gpu_probe [OPTIONS]
Prints the CUDA driver's version and the GPU's properties, then what launching kernels and
copying memory cost there, as Markdown tables.

Options:
  --driver PATH       the driver library to load (default libcuda.so.1)
  --device N          the GPU to probe (default 0)
  --launches N        empty kernels timed one by one, and per back-to-back batch (default 2000)
  --graph-kernels N   empty kernels in the timed graph (default 1000)
  --copy-mib N        the buffer of each copy and of the fill kernel, in MiB (default 256)
  --reps N            timed repetitions of each batch, graph launch and copy (default 7)
  -h, --help          print this and exit

Exit status: 0 when everything was measured, 1 when a driver call failed or a kernel wrote a
wrong value, 2 on a usage error, 77 when there is no driver or no such GPU (the reason is
printed).
)";

// PTX ISA 7.0 for sm_75: every driver since CUDA 11.0 takes it, and sm_75 is the oldest GPU
// that CUDA 13 still compiles for; the driver compiles it for the GPU it runs on.
const char* const kProbePtx = R"(.version 7.0
.target sm_75
.address_size 64

.visible .entry simit_probe_empty()
{
	ret;
}

.visible .entry simit_probe_fill(
	.param .u64 simit_probe_fill_out,
	.param .u32 simit_probe_fill_value,
	.param .u32 simit_probe_fill_n)
{
	.reg .pred %p<2>;
	.reg .b32 %r<8>;
	.reg .b64 %rd<5>;

	ld.param.u64 %rd1, [simit_probe_fill_out];
	ld.param.u32 %r1, [simit_probe_fill_value];
	ld.param.u32 %r2, [simit_probe_fill_n];
	mov.u32 %r3, %ctaid.x;
	mov.u32 %r4, %ntid.x;
	mov.u32 %r5, %tid.x;
	mad.lo.u32 %r6, %r3, %r4, %r5;
	setp.ge.u32 %p1, %r6, %r2;
	@%p1 bra DONE;
	cvta.to.global.u64 %rd2, %rd1;
	mul.wide.u32 %rd3, %r6, 4;
	add.s64 %rd4, %rd2, %rd3;
	add.u32 %r7, %r1, %r6;
	st.global.u32 [%rd4], %r7;
DONE:
	ret;
}
)";

// Runs `f` when the scope ends, also when an exception leaves it (releasing driver objects;
// their results are dropped there, as a destructor cannot report them).
class Defer {
 public:
  explicit Defer(std::function<void()> f) : f_(std::move(f)) {}
  ~Defer() {
    if (f_) f_();
  }
  Defer(const Defer&) = delete;
  Defer& operator=(const Defer&) = delete;

 private:
  std::function<void()> f_;
};

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string format(const char* spec, double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, spec, value);
  return buf;
}

std::string format_time(double seconds) {
  if (seconds < 1e-3) return format("%.2f µs", seconds * 1e6);
  if (seconds < 1.0) return format("%.3f ms", seconds * 1e3);
  return format("%.3f s", seconds);
}

std::string format_rate(double bytes_per_second) {
  return format("%.1f GB/s", bytes_per_second / 1e9);
}

// One row of the measurement table: every sample in seconds (times) or bytes per second.
struct Row {
  std::string what;
  std::vector<double> samples;
  bool rate = false;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

void print_rows(const std::vector<Row>& rows, std::ostream& out) {
  out << "| measurement | median | min | max | samples |\n"
      << "| --- | ---: | ---: | ---: | ---: |\n";
  for (const Row& r : rows) {
    const auto fmt = r.rate ? format_rate : format_time;
    const auto [lo, hi] = std::minmax_element(r.samples.begin(), r.samples.end());
    out << "| " << r.what << " | " << fmt(median(r.samples)) << " | " << fmt(*lo) << " | "
        << fmt(*hi) << " | " << r.samples.size() << " |\n";
  }
}

// ---- The command line

bool parse_int(const std::string& text, int lo, int hi, int& value) {
  int v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || v < lo || v > hi) return false;
  value = v;
  return true;
}

// nullopt after printing the error (and a hint) on `err`.
std::optional<ProbeOptions> parse_args(const std::vector<std::string>& args, std::ostream& err,
                                       bool& help) {
  ProbeOptions o;
  struct IntOption {
    const char* name;
    int* value;
    int lo, hi;
  };
  // The fill kernel's count is a u32 of 4-byte elements: at most 4 GiB.
  const IntOption ints[] = {{"--device", &o.device, 0, 1023},
                            {"--launches", &o.launches, 1, 1000000},
                            {"--graph-kernels", &o.graph_kernels, 1, 100000},
                            {"--copy-mib", &o.copy_mib, 1, 4096},
                            {"--reps", &o.reps, 1, 1000}};
  for (std::size_t i = 0; i < args.size(); ++i) {
    std::string name = args[i], value;
    bool has_value = false;
    if (const auto eq = name.find('='); name.rfind("--", 0) == 0 && eq != std::string::npos) {
      value = name.substr(eq + 1);
      name.resize(eq);
      has_value = true;
    }
    if (name == "-h" || name == "--help") {
      help = true;
      return o;
    }
    const IntOption* int_option = nullptr;
    for (const IntOption& io : ints)
      if (name == io.name) int_option = &io;
    if (!int_option && name != "--driver") {
      err << "gpu_probe: unknown argument '" << args[i] << "' (see --help)\n";
      return std::nullopt;
    }
    if (!has_value) {
      if (i + 1 == args.size()) {
        err << "gpu_probe: " << name << " needs a value (see --help)\n";
        return std::nullopt;
      }
      value = args[++i];
    }
    if (!int_option) {
      if (value.empty()) {
        err << "gpu_probe: --driver needs a library path\n";
        return std::nullopt;
      }
      o.driver = value;
    } else if (!parse_int(value, int_option->lo, int_option->hi, *int_option->value)) {
      err << "gpu_probe: " << name << " takes a whole number from " << int_option->lo << " to "
          << int_option->hi << ", not '" << value << "'\n";
      return std::nullopt;
    }
  }
  return o;
}

// ---- The measurements

class Measure {
 public:
  Measure(const DriverTable& d, const std::optional<StreamTable>& s, Device& dev,
          const ProbeOptions& o, std::ostream& err)
      : d_(d), s_(s), dev_(dev), o_(o), err_(err) {}

  // Every measurement in turn; a failed driver call throws CudaError (the rows measured
  // before it stay). A kernel or a copy that gives wrong values is listed in `problems`.
  void run() {
    const CUmodule module = dev_.load_module(probe_ptx());
    empty_ = dev_.function(module, "simit_probe_empty");
    fill_ = dev_.function(module, "simit_probe_fill");
    Defer destroy_events([&] {
      if (start_) s_->cuEventDestroy(start_);
      if (stop_) s_->cuEventDestroy(stop_);
    });
    if (s_) {
      dev_.check(s_->cuEventCreate(&start_, CU_EVENT_DEFAULT), "cuEventCreate");
      dev_.check(s_->cuEventCreate(&stop_, CU_EVENT_DEFAULT), "cuEventCreate");
    }
    launches();
    if (s_) graph();
    fill_and_copies();
  }

  std::vector<Row> rows;
  std::vector<std::string> notes;     // what was not measured, and why
  std::vector<std::string> problems;  // wrong values: the probe fails

 private:
  void progress(const std::string& what) { err_ << "gpu_probe: " << what << "\n" << std::flush; }

  void launch_empty() { dev_.launch(empty_, {}, {}, {}); }

  // Seconds that the work `enqueue` puts on the legacy default stream takes: between two
  // events on the GPU where the stream table is there (the host's clock would add a launch and
  // a synchronize to work of well under a millisecond), else by the host's clock up to the
  // end of a synchronize.
  double gpu_seconds(const std::function<void()>& enqueue) {
    if (!stop_) {
      const auto t0 = Clock::now();
      enqueue();
      dev_.synchronize();
      return seconds_since(t0);
    }
    dev_.check(s_->cuEventRecord(start_, nullptr), "cuEventRecord");
    enqueue();
    dev_.check(s_->cuEventRecord(stop_, nullptr), "cuEventRecord");
    dev_.check(s_->cuEventSynchronize(stop_), "cuEventSynchronize");
    float ms = 0;
    dev_.check(s_->cuEventElapsedTime(&ms, start_, stop_), "cuEventElapsedTime");
    // An elapsed time of 0 (below the events' resolution, or a fake clock) counts as 1 ns.
    return std::max(ms * 1e-3, 1e-9);
  }

  void launches() {
    progress("empty kernels");
    for (int i = 0; i < 20; ++i) {  // the first launches load the module onto the GPU
      launch_empty();
      dev_.synchronize();
    }
    Row one{"empty kernel: launch, then synchronize", {}, false};
    for (int i = 0; i < o_.launches; ++i) {
      const auto t0 = Clock::now();
      launch_empty();
      dev_.synchronize();
      one.samples.push_back(seconds_since(t0));
    }
    rows.push_back(one);
    Row batch{"empty kernel: " + std::to_string(o_.launches) +
                  " launches back to back, then one synchronize (per launch)",
              {},
              false};
    for (int r = 0; r < o_.reps; ++r) {
      const auto t0 = Clock::now();
      for (int i = 0; i < o_.launches; ++i) launch_empty();
      dev_.synchronize();
      batch.samples.push_back(seconds_since(t0) / o_.launches);
    }
    rows.push_back(batch);
  }

  // N empty kernels captured from a stream into a graph, instantiated once and launched whole;
  // beside it the same N launched one by one on that stream.
  void graph() {
    const StreamTable& s = *s_;
    const int n = o_.graph_kernels;
    progress("a graph of " + std::to_string(n) + " empty kernels");
    CUstream stream = nullptr;
    dev_.check(s.cuStreamCreate(&stream, CU_STREAM_NON_BLOCKING), "cuStreamCreate");
    Defer destroy_stream([&] { s.cuStreamDestroy(stream); });
    auto launch_on_stream = [&] {
      dev_.check(d_.cuLaunchKernel(empty_, 1, 1, 1, 1, 1, 1, 0, stream, nullptr, nullptr),
                 "cuLaunchKernel", "(on a stream)");
    };
    Row stream_batch{"empty kernel: " + std::to_string(n) +
                         " launches back to back on a stream, then one synchronize (per launch)",
                     {},
                     false};
    for (int r = 0; r < o_.reps; ++r) {
      const auto t0 = Clock::now();
      for (int i = 0; i < n; ++i) launch_on_stream();
      dev_.check(s.cuStreamSynchronize(stream), "cuStreamSynchronize");
      stream_batch.samples.push_back(seconds_since(t0) / n);
    }
    rows.push_back(stream_batch);

    dev_.check(s.cuStreamBeginCapture(stream, CU_STREAM_CAPTURE_MODE_THREAD_LOCAL),
               "cuStreamBeginCapture");
    CUgraph graph = nullptr;
    {
      // A capture that a failed launch leaves open is ended (and its graph dropped) here.
      bool capturing = true;
      Defer end_capture([&] {
        if (!capturing) return;
        CUgraph dropped = nullptr;
        if (s.cuStreamEndCapture(stream, &dropped) == CUDA_SUCCESS && dropped)
          s.cuGraphDestroy(dropped);
      });
      for (int i = 0; i < n; ++i) launch_on_stream();
      capturing = false;
      dev_.check(s.cuStreamEndCapture(stream, &graph), "cuStreamEndCapture");
    }
    Defer destroy_graph([&] { s.cuGraphDestroy(graph); });
    CUgraphExec exec = nullptr;
    const auto t0 = Clock::now();
    dev_.check(s.cuGraphInstantiateWithFlags(&exec, graph, 0), "cuGraphInstantiateWithFlags");
    rows.push_back({"graph of " + std::to_string(n) + " empty kernels: instantiate",
                    {seconds_since(t0)},
                    false});
    Defer destroy_exec([&] { s.cuGraphExecDestroy(exec); });
    auto launch_graph = [&] {
      dev_.check(s.cuGraphLaunch(exec, stream), "cuGraphLaunch");
      dev_.check(s.cuStreamSynchronize(stream), "cuStreamSynchronize");
    };
    launch_graph();  // its first launch uploads it
    Row whole{
        "graph of " + std::to_string(n) + " empty kernels: launch, then synchronize", {}, false};
    for (int r = 0; r < o_.reps; ++r) {
      const auto t1 = Clock::now();
      launch_graph();
      whole.samples.push_back(seconds_since(t1));
    }
    Row per_kernel = whole;
    per_kernel.what += " (per kernel)";
    for (double& v : per_kernel.samples) v /= n;
    rows.push_back(whole);
    rows.push_back(per_kernel);
  }

  // The value the pattern puts at byte i of the copied buffers.
  static unsigned char pattern(std::size_t i) {
    return static_cast<unsigned char>((i * 131 + 7) ^ (i >> 12));
  }
  // "" when `bytes` hold the pattern, else where they first do not.
  static std::string check_pattern(const unsigned char* bytes, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i)
      if (bytes[i] != pattern(i))
        return "byte " + std::to_string(i) + " is " + std::to_string(bytes[i]) + ", not " +
               std::to_string(pattern(i));
    return "";
  }

  // Times `copy` o_.reps times (each followed by a synchronize) as a rate of `bytes`.
  Row copy_row(const std::string& what, std::size_t bytes, const std::function<void()>& copy) {
    Row row{what, {}, true};
    copy();  // the first copy of a buffer maps its pages
    dev_.synchronize();
    for (int r = 0; r < o_.reps; ++r) {
      const auto t0 = Clock::now();
      copy();
      dev_.synchronize();
      row.samples.push_back(static_cast<double>(bytes) / seconds_since(t0));
    }
    return row;
  }

  void fill_and_copies() {
    const std::size_t bytes = static_cast<std::size_t>(o_.copy_mib) << 20;
    const std::string size = std::to_string(o_.copy_mib) + " MiB";
    const auto n = static_cast<std::uint32_t>(bytes / 4);
    DeviceArray a = dev_.alloc(nullptr, bytes);
    Defer free_a([&] { d_.cuMemFree(a.device); });

    progress("the fill kernel over " + size);
    const Dim3 block{256, 1, 1};
    const Dim3 grid{(n + block.x - 1) / block.x, 1, 1};
    std::uint32_t value = 0;
    auto launch_fill = [&](std::uint32_t v) {
      const KernelArg args[] = {KernelArg::pointer(a), KernelArg::of(v), KernelArg::of(n)};
      dev_.launch(fill_, grid, block, args);
      value = v;
    };
    gpu_seconds([&] { launch_fill(1); });
    Row fill{"fill kernel: write " + size + " (4 bytes per thread)", {}, true};
    for (int r = 0; r < o_.reps; ++r) {
      const std::uint32_t v = 0x9E3779B9u * static_cast<std::uint32_t>(r + 2);
      fill.samples.push_back(static_cast<double>(bytes) / gpu_seconds([&] { launch_fill(v); }));
    }
    rows.push_back(fill);
    std::vector<std::uint32_t> written(n);
    dev_.check(d_.cuMemcpyDtoH(written.data(), a.device, bytes), "cuMemcpyDtoH");
    for (std::uint32_t i = 0; i < n; ++i)
      if (written[i] != value + i) {
        problems.push_back("the fill kernel wrote " + std::to_string(written[i]) + " at index " +
                           std::to_string(i) + ", not " + std::to_string(value + i));
        break;
      }
    written = {};

    progress("copies of " + size);
    std::vector<unsigned char> pageable(bytes);
    for (std::size_t i = 0; i < bytes; ++i) pageable[i] = pattern(i);
    rows.push_back(copy_row("host to device, pageable host memory, " + size, bytes, [&] {
      dev_.check(d_.cuMemcpyHtoD(a.device, pageable.data(), bytes), "cuMemcpyHtoD");
    }));
    std::fill(pageable.begin(), pageable.end(), 0);
    rows.push_back(copy_row("device to host, pageable host memory, " + size, bytes, [&] {
      dev_.check(d_.cuMemcpyDtoH(pageable.data(), a.device, bytes), "cuMemcpyDtoH");
    }));
    if (const std::string bad = check_pattern(pageable.data(), bytes); !bad.empty())
      problems.push_back("a round trip through pageable memory came back changed: " + bad);
    pageable = {};
    if (!s_) return;

    const StreamTable& s = *s_;
    void* pinned = nullptr;
    dev_.check(s.cuMemAllocHost(&pinned, bytes), "cuMemAllocHost");
    Defer free_pinned([&] { s.cuMemFreeHost(pinned); });
    auto* host = static_cast<unsigned char*>(pinned);
    for (std::size_t i = 0; i < bytes; ++i) host[i] = pattern(i);
    rows.push_back(copy_row("host to device, pinned host memory, " + size, bytes, [&] {
      dev_.check(d_.cuMemcpyHtoD(a.device, pinned, bytes), "cuMemcpyHtoD");
    }));
    std::fill(host, host + bytes, 0);
    rows.push_back(copy_row("device to host, pinned host memory, " + size, bytes, [&] {
      dev_.check(d_.cuMemcpyDtoH(pinned, a.device, bytes), "cuMemcpyDtoH");
    }));
    if (const std::string bad = check_pattern(host, bytes); !bad.empty())
      problems.push_back("a round trip through pinned memory came back changed: " + bad);

    DeviceArray b = dev_.alloc(nullptr, bytes);
    Defer free_b([&] { d_.cuMemFree(b.device); });
    auto copy = [&] { dev_.check(s.cuMemcpyDtoD(b.device, a.device, bytes), "cuMemcpyDtoD"); };
    gpu_seconds(copy);
    Row d2d{"device to device, " + size + " (bytes copied; twice as many move)", {}, true};
    for (int r = 0; r < o_.reps; ++r)
      d2d.samples.push_back(static_cast<double>(bytes) / gpu_seconds(copy));
    rows.push_back(d2d);
    std::fill(host, host + bytes, 0);
    dev_.check(d_.cuMemcpyDtoH(pinned, b.device, bytes), "cuMemcpyDtoH");
    if (const std::string bad = check_pattern(host, bytes); !bad.empty())
      problems.push_back("the device-to-device copy came out changed: " + bad);
  }

  const DriverTable& d_;
  const std::optional<StreamTable>& s_;
  Device& dev_;
  const ProbeOptions& o_;
  std::ostream& err_;
  CUfunction empty_ = nullptr, fill_ = nullptr;
  CUevent start_ = nullptr, stop_ = nullptr;  // with the stream table only
};

std::string cuda_version(int v) {
  return std::to_string(v / 1000) + "." + std::to_string(v % 1000 / 10);
}

}  // namespace

const std::string& probe_ptx() {
  static const std::string ptx = kProbePtx;
  return ptx;
}

int run_probe(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
              const GetProcAddress* get) {
  bool help = false;
  const std::optional<ProbeOptions> parsed = parse_args(args, err, help);
  if (!parsed) return kProbeUsage;
  if (help) {
    out << kUsage;
    return kProbeOk;
  }
  const ProbeOptions& o = *parsed;

  // No driver, or no such device: the reason, and the status that says "skipped".
  auto no_gpu = [&](const std::string& why) {
    out << "No GPU probed: " << why << "\n";
    return kProbeNoGpu;
  };
  std::string why;
  std::optional<GetProcAddress> opened;
  if (!get) {
    opened = open_driver_library(o.driver, why);
    if (!opened) return no_gpu(why);
    get = &*opened;
  }
  const std::optional<DriverTable> driver = resolve_driver(*get, why);
  if (!driver) return no_gpu(why);
  std::string streams_why;
  const std::optional<StreamTable> streams = resolve_streams(*get, streams_why);

  Device device(*driver);
  try {
    device.open(o.device);
  } catch (const std::exception& e) {
    return no_gpu(std::string("no usable CUDA device: ") + e.what());
  }
  int version = 0;
  const bool has_version = driver->cuDriverGetVersion(&version) == CUDA_SUCCESS;
  out << "| property | value |\n| --- | --- |\n"
      << "| driver | "
      << (has_version ? "CUDA " + cuda_version(version) + " (" + std::to_string(version) + ")"
                      : std::string("version not reported"))
      << " |\n"
      << "| device " << o.device << " | " << device.name() << " |\n"
      << "| memory | "
      << format("%.1f GiB", static_cast<double>(device.total_memory()) / (1ull << 30)) << " ("
      << device.total_memory() << " bytes) |\n"
      << "| multiprocessors | " << device.multiprocessors() << " |\n"
      << "| compute capability | " << device.compute_major() << "." << device.compute_minor()
      << " |\n\n"
      << std::flush;

  Measure measure(*driver, streams, device, o, err);
  if (!streams)
    measure.notes.push_back("no graph, pinned copies or device-to-device copy: " + streams_why);
  std::string stopped;
  try {
    measure.run();
  } catch (const std::exception& e) {
    stopped = e.what();
  }
  if (!measure.rows.empty()) {
    print_rows(measure.rows, out);
    out << "\nThe fill kernel and the device-to-device copy are timed "
        << (streams ? "between two events on the GPU" : "by the host's clock")
        << "; the rest by the host's clock, from the first call to the end of the synchronize.\n";
  }
  for (const std::string& note : measure.notes) out << "\nNot measured: " << note << "\n";
  for (const std::string& problem : measure.problems) out << "\nWRONG: " << problem << "\n";
  if (!stopped.empty()) out << "\nStopped: " << stopped << "\n";
  out << std::flush;
  return stopped.empty() && measure.problems.empty() ? kProbeOk : kProbeFailed;
}

}  // namespace simit::jit::cuda
