// Reading source files and finding test files for the `simit` command.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace simit::tools {

// The whole file, or nullopt with a reason in `error`.
std::optional<std::string> read_text_file(const std::string& path, std::string& error);

struct FoundFiles {
  std::vector<std::string> files;   // in argument order; each folder's files sorted
  std::vector<std::string> errors;  // paths that are neither a file nor a folder
};

// Each path is a file (taken as is) or a folder (searched recursively for `*.sim`).
FoundFiles find_test_files(const std::vector<std::string>& paths);

// True when some folder above `path` is named `illegal` (TESTFORMAT.md §5).
bool in_illegal_folder(const std::string& path);

}  // namespace simit::tools
