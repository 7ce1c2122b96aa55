// Reading source files and finding test files for the `simit` command.
#include "files.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace simit::tools {

namespace fs = std::filesystem;

std::optional<std::string> read_text_file(const std::string& path, std::string& error) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    error = "is a directory";
    return std::nullopt;
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error = std::strerror(errno);
    return std::nullopt;
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) {
    error = "read error";
    return std::nullopt;
  }
  return text.str();
}

FoundFiles find_test_files(const std::vector<std::string>& paths) {
  FoundFiles found;
  for (const auto& path : paths) {
    std::error_code ec;
    if (fs::is_regular_file(path, ec)) {
      found.files.push_back(path);
    } else if (fs::is_directory(path, ec)) {
      std::vector<std::string> in_folder;
      for (const auto& entry : fs::recursive_directory_iterator(path, ec))
        if (entry.is_regular_file() && entry.path().extension() == ".sim")
          in_folder.push_back(entry.path().generic_string());
      std::sort(in_folder.begin(), in_folder.end());
      found.files.insert(found.files.end(), in_folder.begin(), in_folder.end());
    } else {
      found.errors.push_back(path);
    }
  }
  return found;
}

bool in_illegal_folder(const std::string& path) {
  // The absolute path also covers `simit test x.sim` run inside an `illegal` folder.
  fs::path folder = fs::absolute(fs::path(path)).lexically_normal().parent_path();
  return std::any_of(folder.begin(), folder.end(),
                     [](const fs::path& part) { return part == "illegal"; });
}

}  // namespace simit::tools
