// The colour map of every heat map (fivebar/colour.hpp).

#include "fivebar/colour.hpp"

#include <algorithm>
#include <array>
#include <cstddef>

namespace fivebar {

Rgb viridis(double v) {
  // matplotlib.cm.viridis at 0, 0.1, ..., 1 (values rounded to 6 decimals), linearly interpolated.
  static constexpr std::array<Rgb, 11> stops{{{0.267004, 0.004874, 0.329415},
                                              {0.282623, 0.140926, 0.457517},
                                              {0.253935, 0.265254, 0.529983},
                                              {0.206756, 0.371758, 0.553117},
                                              {0.163625, 0.471133, 0.558148},
                                              {0.127568, 0.566949, 0.550556},
                                              {0.134692, 0.658636, 0.517649},
                                              {0.266941, 0.748751, 0.440573},
                                              {0.477504, 0.821444, 0.318195},
                                              {0.741388, 0.873449, 0.149561},
                                              {0.993248, 0.906157, 0.143936}}};
  if (!(v > 0.0)) return stops.front();
  if (v >= 1.0) return stops.back();
  const double t = v * double(stops.size() - 1);
  const std::size_t k = std::min(std::size_t(t), stops.size() - 2);
  const double u = t - double(k);
  const Rgb& a = stops[k];
  const Rgb& b = stops[k + 1];
  return {a.r + u * (b.r - a.r), a.g + u * (b.g - a.g), a.b + u * (b.b - a.b)};
}

}  // namespace fivebar
