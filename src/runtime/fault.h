// The one exception the runtime throws: a run-time condition of the program (a singular
// matrix, a shape mismatch found only at run time). Executors add the source location.
#pragma once

#include <stdexcept>

namespace simit::runtime {

class Fault : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace simit::runtime
