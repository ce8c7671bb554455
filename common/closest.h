// "Did you mean ...?" for names a user typed: the known name nearest by edit distance.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

namespace tessera {

// Levenshtein distance (insertions, deletions, substitutions each cost 1).
size_t editDistance(const std::string& a, const std::string& b);
// The choice nearest to `word`, if fewer than `within` edits away; "" otherwise.
std::string closestName(const std::string& word, const std::vector<std::string>& choices, size_t within = 4);

}  // namespace tessera
