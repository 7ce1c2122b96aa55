// The CPUs this process may run on: its CPU affinity mask (so taskset and a container's cpuset
// count; a CPU quota does not), else what the standard library reports; at least 1.
#pragma once

namespace simit::runtime {

int usable_cpus();

}  // namespace simit::runtime
