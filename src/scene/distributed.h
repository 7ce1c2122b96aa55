// A scene run on MPI ranks (`simit run --distributed`): the seam between the scene, which
// builds the whole sets from the meshes and writes the output, and the distributed layer
// (src/dist), which splits the sets over the ranks and moves data between them. Each rank runs
// the program over its own part of every set (interp/distribution.h); rank 0 alone writes.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "interp/distribution.h"
#include "runtime/set.h"

namespace simit::scene {

class Distributed : public interp::Distribution {
 public:
  virtual int rank() const = 0;
  virtual int ranks() const = 0;
  // This rank's part of each of `whole` (vertex sets, and edge sets whose endpoints all lie in
  // one of them), in the same order: the elements it owns and ghosts, in the whole set's order
  // (owned() lists the owned ones); fields copied,
  // endpoints renumbered, mesh numbers kept. Only rank 0 has the whole sets (the others pass
  // nulls): it cuts them and sends each rank its part. Throws std::runtime_error on rank 0 for
  // sets it cannot split (the others then wait for its abort).
  virtual std::vector<std::unique_ptr<runtime::Set>> localize(
      const std::vector<runtime::Set*>& whole) = 0;
  // Every field of each of `local` (as localize made them) put together in the matching set of
  // `whole` on rank 0; the others' `whole` are left alone. Collective.
  virtual void gather(const std::vector<runtime::Set*>& local,
                      const std::vector<runtime::Set*>& whole) const = 0;
  // Rank 0's report of the parts, one line per rank: each set of `local` (as localize made
  // them) with the elements the rank owns and the ghosts it holds, and the entries it sends
  // per refresh; "" on the other ranks. Collective.
  virtual std::string describe_parts(const std::vector<runtime::Set*>& local) const = 0;
  // Rank 0's report of what the ranks exchanged so far, one line per rank: ghost refreshes,
  // bytes and messages sent, sums across ranks; "" on the other ranks. Collective.
  virtual std::string describe_traffic() const = 0;
  // Each of `values` replaced by its least over the ranks, on every rank. Collective.
  virtual void least(std::vector<int64_t>& values) const = 0;
  // `text` as rank 0 holds it, on every rank. Collective.
  virtual void broadcast(std::string& text) const = 0;
  // Whether `flag` holds on any rank (on every rank). Collective.
  virtual bool any(bool flag) const = 0;
  // Ends every rank of the run with `status`: one rank's error, while the others may be
  // waiting for it. Not collective.
  [[noreturn]] virtual void abort(int status) const = 0;
  // Waits for another rank's abort (a failure every rank meets alike, which rank 0 reports).
  [[noreturn]] virtual void wait_for_abort() const = 0;
};

}  // namespace simit::scene
