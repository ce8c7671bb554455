// Nearest known name (see closest.h).
#include "common/closest.h"

#include <algorithm>

namespace tessera {

size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

std::string closestName(const std::string& word, const std::vector<std::string>& choices, size_t within) {
  std::string best;
  for (const std::string& c : choices) {
    const size_t d = editDistance(word, c);
    if (d < within) within = d, best = c;
  }
  return best;
}

}  // namespace tessera
