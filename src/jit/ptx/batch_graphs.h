// A device program's loop batches as CUDA graphs: the steps of 1, 2, 4, ... iterations that
// the GPU executor launches between two reads of the context (jit/ptx/gpu_executor.cpp) are
// captured once from a stream into a graph, instantiated, and from then on launched with one
// call, so a batch of 32 iterations of 8 steps costs one launch on the host instead of 256.
// A graph is keyed by everything its launches hold: the program, the batch, the context's
// device address and the sizes (which fix each step's units).
#pragma once

#include <compare>
#include <cstdint>
#include <functional>
#include <map>
#include <vector>

#include "jit/ptx/cuda_driver.h"

namespace simit::jit::ptx {

struct GraphKey {
  const void* program = nullptr;  // the kernel whose steps the batch launches
  int batch = 0;                  // iterations
  cuda::CUdeviceptr context = 0;  // the context array the steps are passed
  std::vector<int64_t> sizes;     // the program's sizes (each step's units)
  auto operator<=>(const GraphKey&) const = default;
};

class BatchGraphs {
 public:
  // A stream of `streams` on `device` (cuStreamCreate, blocking: it waits for the work
  // launched before on the legacy stream, and that stream's later work waits for it).
  BatchGraphs(cuda::Device& device, const cuda::StreamTable& streams);
  ~BatchGraphs();
  BatchGraphs(const BatchGraphs&) = delete;
  BatchGraphs& operator=(const BatchGraphs&) = delete;

  // The stream that `record` must launch into while a graph is captured.
  cuda::CUstream stream() const { return stream_; }
  // Launches the graph of `key` on the stream, returning without waiting; the first time,
  // captures it from `record` (which launches the batch's steps into stream()) and
  // instantiates it. A failed capture ends it before the CudaError goes on.
  void launch(const GraphKey& key, const std::function<void()>& record);

  long captured() const { return captured_; }
  long launched() const { return launched_; }

 private:
  cuda::Device& device_;
  cuda::StreamTable streams_;
  cuda::CUstream stream_ = nullptr;
  std::map<GraphKey, cuda::CUgraphExec> graphs_;
  long captured_ = 0, launched_ = 0;
};

}  // namespace simit::jit::ptx
