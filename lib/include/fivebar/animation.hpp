#pragma once
/// Animations of a station's two linkages through a skin-deformation pattern (fivebar/pattern.hpp):
/// one self-contained SVG document (plain SVG and a little JavaScript, no external resource) with
/// two panels, the whole station and its tactor region enlarged, that show, behind everything, both
/// mechanisms' reachable regions and the fingertip target ellipse, and in front both linkages
/// O1-A1-P-A2-O2 moving through the pattern's samples at true speed
/// (the sample times of the pattern), the tactor paths drawn as they go, and, when the `simulate`
/// product's time series are given, the simulated tactor beside the reference (a hollow marker and
/// its own trace). A play/pause button and a time slider drive it; a URL fragment `#t=SECONDS`
/// (on the SVG file itself or on an HTML page that holds it inline) seeks every animation of the
/// document to that instant and pauses it.
///
/// Geometry of a frame (docs/conventions.md frames, mm): the elbows are the forward kinematics of
/// the sample's motor angles, A_i = O_i + L_i (cos theta_i, sin theta_i) (paper Sec. II-A), and the
/// tactor point P the closure of the loop on the design's assembly branch (fivebar/kinematics.hpp
/// fk()); a sample whose point is unreachable has no linkage in its frame.
///
/// The frames are stored in the document as JSON in a `<metadata class="fivebar-animation-data">`
/// element (units at the edges: `t_s`, points in mm), which the script reads and which tests and
/// other tools can read back: `views` (per panel its place on the page in pixels and its mapping,
/// page x = x_px + (x - xmin_mm) px_per_mm, page y = y_px + (ymax_mm - y) px_per_mm), per mechanism
/// `O1`, `O2`, `links_mm` and per frame `[A1x, A1y, Px, Py, A2x, A2y]` or null, the pattern target
/// per frame, and the simulated point per frame or null.
/// The static picture (no script run, e.g. through an <img>) shows the first frame.

#include <array>
#include <cstddef>
#include <cstdint>
#include <istream>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/pattern.hpp"

namespace fivebar {

/// One mechanism's simulated tactor motion (the `simulate` product's time series).
struct SimulatedTrack {
  std::string mechanism;       ///< "upper" or "lower"
  std::vector<double> time_s;  ///< increasing
  std::vector<Vec2> point_mm;  ///< simulated tactor point P at time_s
};

/// Bounds of a time series read back (docs/reliability.md "Resource bounds").
inline constexpr std::size_t kMaxSimulatedLine = 4096;                       ///< bytes a line
inline constexpr std::uintmax_t kMaxSimulatedBytes = std::uintmax_t{1} << 30;  ///< bytes in all
inline constexpr std::size_t kMaxSimulatedRows = 10'000'000;                 ///< data rows
/// Reads the time series CSV of write_time_series_csv() (fivebar/dynamics.hpp) through the bounded
/// reader of fivebar/csv_reader.hpp: one track per mechanism (`lower`, `upper`), in order of first
/// appearance. `name` names the file in messages; InputError "NAME:LINE: column ..." for a header
/// without the columns t_s, mechanism, x_mm, y_mm or with a duplicated one, a cell that is not a
/// finite decimal number, a coordinate beyond 1e12 mm, a time going back, or a bound passed.
std::vector<SimulatedTrack> read_simulated_tracks(std::istream& in, std::string_view name);

struct AnimationOptions {
  double width_px = 1100.0;           ///< width of the picture (both panels); the height follows the view
  double tactor_diameter_mm = 0.0;    ///< > 0: the tactor disks at their true size (geometry:)
  std::size_t max_frames = 1500;      ///< longer patterns are shown every k-th sample (k as small as fits)
  std::vector<SimulatedTrack> simulated;  ///< empty: the reference motion only
  std::string id;                     ///< id of the root element; empty: from the station and pattern
};

/// One frame as drawn (the JSON above, in numbers).
struct AnimationFrame {
  double time_s = 0.0;
  std::size_t sample = 0;  ///< index into PatternResult::samples
  /// Per mechanism (upper, lower): elbows and tactor, when the sample's point is reachable.
  struct Linkage {
    bool drawn = false;
    Vec2 A1{0.0, 0.0}, P{0.0, 0.0}, A2{0.0, 0.0};
  };
  std::array<Linkage, 2> linkage;
};

/// The frames of `result` on `station` (both mechanisms): every sample, or every k-th when there are
/// more than `max_frames` (the last sample always included).
std::vector<AnimationFrame> animation_frames(const Station& station, const PatternResult& result,
                                             std::size_t max_frames = 1500);

/// The animation as one SVG document (see above). InputError when the station lacks a mechanism or
/// the result has no sample.
std::string animate_pattern_svg(const Station& station, const PatternResult& result,
                                const AnimationOptions& options = {});

}  // namespace fivebar
