// Lexical helpers over REPL input: see input_text.h.
#include "input_text.h"

#include <cctype>
#include <sstream>

namespace simit::repl {

std::string trim(const std::string& s) {
  size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  size_t e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> words(const std::string& text, int& brackets) {
  std::vector<std::string> out;
  brackets = 0;
  for (size_t i = 0; i < text.size();) {
    char c = text[i];
    if (c == '%') {
      while (i < text.size() && text[i] != '\n') ++i;
    } else if (c == '"') {
      ++i;
      while (i < text.size() && text[i] != '"') i += text[i] == '\\' ? 2 : 1;
      ++i;
    } else if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
      size_t b = i;
      while (i < text.size() &&
             (std::isalnum(static_cast<unsigned char>(text[i])) || text[i] == '_'))
        ++i;
      out.push_back(text.substr(b, i - b));
    } else {
      if (c == '(' || c == '[' || c == '{') ++brackets;
      if (c == ')' || c == ']' || c == '}') --brackets;
      ++i;
    }
  }
  return out;
}

std::string first_word(const std::string& text) {
  int b = 0;
  std::vector<std::string> w = words(text, b);
  return w.empty() ? "" : w[0];
}

bool has_top_level_assignment(const std::string& text) {
  int depth = 0;
  bool in_string = false;
  for (size_t i = 0; i < text.size(); ++i) {
    char c = text[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
      continue;
    }
    if (c == '%') return false;  // the rest is a comment
    if (c == '"')
      in_string = true;
    else if (c == '(' || c == '[')
      ++depth;
    else if (c == ')' || c == ']')
      --depth;
    else if (c == '=' && depth == 0) {
      char prev = i > 0 ? text[i - 1] : ' ';
      char next = i + 1 < text.size() ? text[i + 1] : ' ';
      if (next != '=' && prev != '=' && prev != '<' && prev != '>' && prev != '!') return true;
    }
  }
  return false;
}

std::vector<std::string> split_blanks(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> out;
  std::string w;
  while (in >> w) out.push_back(w);
  return out;
}

}  // namespace simit::repl
