// simit's own failures kept apart from the user's: see run_guarded in simit/commands.h.
#include <exception>
#include <new>

#include "frontend/diagnostics.h"
#include "simit/commands.h"

namespace simit::tools {

int run_guarded(const std::function<int()>& command, std::ostream& err) {
  try {
    return command();
  } catch (const std::bad_alloc&) {
    err << "simit: out of memory\n";
    return 1;
  } catch (const frontend::InternalError& e) {
    err << "simit: " << e.what() << "\nsimit: this is a bug in simit; please report it\n";
  } catch (const std::exception& e) {
    err << "simit: internal error: " << e.what()
        << "\nsimit: this is a bug in simit; please report it\n";
  }
  return 3;
}

}  // namespace simit::tools
