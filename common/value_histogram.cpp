// Histogram and suggested range (see value_histogram.h).
#include "common/value_histogram.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

namespace tessera {

ValueHistogram::ValueHistogram(double lo_, double hi_, int bins, bool integral_)
    : lo(lo_), hi(hi_), integral(integral_), counts(std::max(bins, 1), 0) {}

void ValueHistogram::add(double v) {
  if (integral) v = std::round(v);
  const long long bins = (long long)counts.size();
  const long long b = hi > lo ? (long long)std::floor((v - lo) * (double)bins / (hi - lo)) : 0;
  ++counts[std::clamp(b, 0LL, bins - 1)];
  if (values.size() <= 16 && std::find(values.begin(), values.end(), v) == values.end()) values.push_back(v);
}

bool storesIntegers(const RawVolumeSpec& s) {
  auto integer = [](double x) { return x == std::round(x); };
  for (const SliceFile& d : s.slices)  // a DICOM series scales slice by slice
    if (!integer(d.slope) || !integer(d.inter)) return false;
  return s.type != VoxelType::Float32 && s.type != VoxelType::Float64 && integer(s.slope) && integer(s.inter);
}

uint64_t ValueHistogram::total() const { return std::accumulate(counts.begin(), counts.end(), uint64_t{0}); }

namespace {

std::string number(double x, int digits = 9) {
  char b[40];
  std::snprintf(b, sizeof b, "%.*g", digits, x);
  return b;
}

// The values bins [a, b] can hold: for integers the first and last integer in them.
std::array<double, 2> bounds(const ValueHistogram& h, size_t a, size_t b) {
  const bool top = b + 1 == h.counts.size();
  if (!h.integral) return {h.edge(a), top ? h.hi : h.edge(b + 1)};
  return {std::max(h.lo, std::ceil(h.edge(a))), top ? h.hi : std::ceil(h.edge(b + 1)) - 1};
}

// A cluster at the low end of bins [first, last] that lies apart from the rest: followed
// (towards the middle) by at least `gap` empty bins, and either a few outliers (under 0.1% of
// `total`) or padding (one bin: one value, as CT's -3024, under half of `total`). Returns the
// bins it spans. Data with gaps (bone well above soft tissue) is neither.
std::optional<std::array<size_t, 2>> apartAtLow(const std::vector<uint64_t>& c, size_t first, size_t last,
                                                size_t gap, uint64_t total) {
  uint64_t held = 0;
  for (size_t b = first; b <= last && 1000 * held < total; ++b) {
    if (c[b] == 0) continue;
    held += c[b];
    size_t empty = 0;
    while (b + 1 + empty <= last && c[b + 1 + empty] == 0) ++empty;
    if (empty < gap) continue;
    const bool outliers = 1000 * held < total, padding = b == first && 2 * held < total;
    return outliers || padding ? std::optional(std::array<size_t, 2>{first, b}) : std::nullopt;
  }
  return std::nullopt;
}

}  // namespace

int digitsToTell(double a, double b, int at_least) {
  int d = at_least;
  while (d < 17 && a != b && number(a, d) == number(b, d)) ++d;
  return d;
}

std::optional<RangeAdvice> suggestedRange(const ValueHistogram& h) {
  const std::vector<uint64_t>& c = h.counts;
  const uint64_t total = h.total();
  const size_t n = c.size();
  if (total == 0 || !(h.hi > h.lo)) return std::nullopt;
  // Labels: 16 values or fewer, counted as added (not as occupied bins: data squeezed into a
  // few wide bins by hot voxels far above it is what the advice is for).
  if (!h.values.empty() && h.values.size() <= 16) return std::nullopt;
  size_t first = 0, last = n - 1;
  while (c[first] == 0) ++first;
  while (c[last] == 0) --last;
  const size_t gap = n / 8;
  std::string why;
  uint64_t apart = 0;
  auto say = [&](size_t a, size_t b, const char* where) {
    uint64_t held = 0;
    for (size_t i = a; i <= b; ++i) held += c[i];
    apart += held;
    const auto [from, to] = bounds(h, a, b);
    const int d = std::max(digitsToTell(from, to), digitsToTell(h.lo, h.hi));
    const std::string at = from == to ? number(from, d) : number(from, d) + " .. " + number(to, d);
    char s[160];
    std::snprintf(s, sizeof s, "%s%.2g%% of the voxels lie apart %s, at %s", why.empty() ? "" : "; ",
                  100.0 * held / total, where, at.c_str());
    why += s;
  };
  if (auto low = apartAtLow(c, first, last, gap, total)) {
    say((*low)[0], (*low)[1], "below the rest");
    first = (*low)[1] + 1;
    while (c[first] == 0) ++first;
  }
  std::vector<uint64_t> reversed(c.rbegin(), c.rend());
  if (auto high = apartAtLow(reversed, n - 1 - last, n - 1 - first, gap, total)) {
    const size_t a = n - 1 - (*high)[1], b = n - 1 - (*high)[0];
    say(a, b, "above the rest");
    last = a - 1;
    while (c[last] == 0) --last;
  }
  // The outermost 0.01% of what is left, on either side.
  const uint64_t left = total - apart, tail = left / 10000;
  uint64_t cut = 0;
  size_t lo = first, hi = last;
  while (lo < hi && cut + c[lo] <= tail) cut += c[lo++];
  cut = 0;
  while (hi > lo && cut + c[hi] <= tail) cut += c[hi--];
  const auto [a, b] = bounds(h, lo, hi);
  if (why.empty() && (b - a) >= 0.5 * (h.hi - h.lo)) return std::nullopt;
  uint64_t inside = 0;
  for (size_t i = lo; i <= hi; ++i) inside += c[i];
  if (why.empty()) why = "the rest are a thin tail";
  return RangeAdvice{{a, b}, (double)inside / total, why};
}

}  // namespace tessera
