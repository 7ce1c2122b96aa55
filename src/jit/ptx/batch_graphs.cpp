// A device program's loop batches as CUDA graphs (jit/ptx/batch_graphs.h).
#include "jit/ptx/batch_graphs.h"

#include <stdexcept>

namespace simit::jit::ptx {

namespace {

// cudaStreamCaptureModeThreadLocal (cuda.h, CUstreamCaptureMode_enum): a capture that only
// this thread's unsafe calls can invalidate, so another engine's thread on the same device
// does not break it.
constexpr cuda::CUstreamCaptureMode kCaptureThreadLocal = 1;

}  // namespace

BatchGraphs::BatchGraphs(cuda::Device& device, const cuda::StreamTable& streams)
    : device_(device), streams_(streams) {
  if (const char* missing = cuda::missing_stream_entry(streams_))
    throw std::invalid_argument(std::string("CUDA graphs need the driver's ") + missing);
  device_.check(streams_.cuStreamCreate(&stream_, 0), "cuStreamCreate");
}

BatchGraphs::~BatchGraphs() {
  // Errors are ignored here: a driver failing while the executor goes frees it all with the
  // context.
  for (auto& [key, exec] : graphs_) streams_.cuGraphExecDestroy(exec);
  if (stream_) streams_.cuStreamDestroy(stream_);
}

void BatchGraphs::launch(const GraphKey& key, const std::function<void()>& record) {
  auto found = graphs_.find(key);
  if (found == graphs_.end()) {
    device_.check(streams_.cuStreamBeginCapture(stream_, kCaptureThreadLocal),
                  "cuStreamBeginCapture");
    cuda::CUgraph graph = nullptr;
    try {
      record();
    } catch (...) {
      streams_.cuStreamEndCapture(stream_, &graph);  // ends the capture; the graph is invalid
      if (graph) streams_.cuGraphDestroy(graph);
      throw;
    }
    device_.check(streams_.cuStreamEndCapture(stream_, &graph), "cuStreamEndCapture");
    cuda::CUgraphExec exec = nullptr;
    const cuda::CUresult instantiated = streams_.cuGraphInstantiateWithFlags(&exec, graph, 0);
    streams_.cuGraphDestroy(graph);  // the instance keeps what it needs
    device_.check(instantiated, "cuGraphInstantiateWithFlags");
    found = graphs_.emplace(key, exec).first;
    ++captured_;
  }
  device_.check(streams_.cuGraphLaunch(found->second, stream_), "cuGraphLaunch");
  ++launched_;
}

}  // namespace simit::jit::ptx
