// A histogram of a volume's values in the file's units, and the `range` it suggests when the
// data's min..max would waste the transfer function: CT padding (-3024 around the scan), a
// few hot voxels far above the rest, a long thin tail.
#pragma once
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/volume.h"

namespace tessera {

struct ValueHistogram {
  double lo = 0, hi = 0;         // the data's min and max
  bool integral = false;         // integer values: each is rounded before it is binned
  std::vector<uint64_t> counts;  // equal-width bins over [lo, hi]; the last includes hi
  std::vector<double> values;    // the first 17 distinct values added: 16 or fewer are labels

  ValueHistogram(double lo_, double hi_, int bins, bool integral_);
  // Values read back from normalised floats are a rounding away from the file's: integers are
  // rounded, and a bin is floor((v - lo) * bins / (hi - lo)) (exact for integers, where the
  // width would not be), so a value on a bin's lower edge is in that bin.
  void add(double v);
  uint64_t total() const;
  double edge(size_t bin) const { return lo + (hi - lo) * (double)bin / counts.size(); }
};

// The fewest significant digits (at least `at_least`, at most 17) with which "%.*g" prints a
// and b differently: 1e9 and 1e9 + 4 need 10 (at 9 both read "1e+09": found by review).
int digitsToTell(double a, double b, int at_least = 9);

// Whether a file's values are integers: an integer type scaled by an integer slope and
// intercept (a NIfTI scl_slope of 0.01 makes an int16 file's values decimals; a DICOM
// series: every slice's).
bool storesIntegers(const RawVolumeSpec& s);

struct RangeAdvice {
  std::array<double, 2> range;  // what `range:` could say
  double inside = 1;            // share of voxels in it
  std::string why;              // what lies outside it, in words
};

// From a fine histogram (1024 bins or more): the range holding the data once values that lie
// apart (beyond an empty eighth of the span: under 0.1% of the voxels, or one value under
// half of them, at either end) and the outermost 0.01% of either tail are left out; nullopt
// unless it leaves out values apart or is under half the span. Nothing for data of 16
// values or fewer (labels, counted by add(): a float mask and labels spread wider than the bins
// are labels too).
std::optional<RangeAdvice> suggestedRange(const ValueHistogram& fine);

}  // namespace tessera
