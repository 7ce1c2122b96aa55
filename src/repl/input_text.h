// Lexical helpers over REPL input: trimming, words outside comments and strings, and the
// assignment form `a = e` typed without its `;`.
#pragma once

#include <string>
#include <vector>

namespace simit::repl {

std::string trim(const std::string& s);
// The words of `text` outside comments and strings, and the bracket depth at its end.
std::vector<std::string> words(const std::string& text, int& brackets);
std::string first_word(const std::string& text);
// True when `text` has an `=` outside brackets and strings that is not part of `==`, `<=`,
// `>=` or `!=`: the statement form `a = e` or `a, b = f(x)`.
bool has_top_level_assignment(const std::string& text);
// Splits `text` at blanks.
std::vector<std::string> split_blanks(const std::string& text);

}  // namespace simit::repl
