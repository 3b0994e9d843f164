#pragma once
/// Manufacturing tolerance and sensing error of a five-bar: how far the
/// printed device's tactor can be from where the controller believes it is.
///
/// The controller computes the joint angles by the nominal IK and drives the motors there; the
/// printed device, whose lengths, base positions and joint angle offsets differ from the design,
/// then puts the tactor at FK_printed(theta_nominal). Ten parameters q are perturbed, in the order
/// of ToleranceParameter: L1, L2, L3, L4 (mm), O1x, O1y, O2x, O2y (mm), theta1, theta2 (rad, the
/// offset of the true joint angle from the one the controller believes).
///
/// First order, closed form. Each leg closes the loop
///   P = A_i + L_{i+2} u_i,   A_i = O_i + L_i e(theta_i),   u_i = e(phi_i) = (P - A_i) / L_{i+2},
/// with e(a) = (cos a, sin a) and e'(a) = (-sin a, cos a). Differentiating,
///   dP = dO_i + dL_i e(theta_i) + L_i e'(theta_i) dtheta_i + dL_{i+2} u_i + L_{i+2} e'(phi_i) dphi_i.
/// The distal angle phi_i is unknown; u_i . e'(phi_i) = 0 eliminates it: dotting with u_i,
///   u_i . dP = u_i . dO_i + (u_i . e(theta_i)) dL_i + L_i cross(e(theta_i), u_i) dtheta_i + dL_{i+2},
/// (cross(a, b) = a_x b_y - a_y b_x), one row per leg: the 2x2 system M dP = R dq with
/// M = [u_1^T; u_2^T]. det M = cross(u_1, u_2) is the sine of the tactor angle, so M is singular
/// exactly on the type II singularity (distal links collinear); there the first-order model breaks
/// down and a Status says so. Sensitivity S = dP/dq = M^{-1} R (2x10), checked against central
/// finite differences of fk() in test/test_tolerance.cpp.
///
/// With independent parameter errors of standard deviations sigma_j, the tactor covariance is
/// C = S diag(sigma^2) S^T; the 3-sigma ellipse has semi-axes 3 sqrt(eig(C)). The worst case puts
/// every parameter at the edge of its +-3 sigma band with the worst sign: to first order the tactor
/// displacements of the box |dq_j| <= 3 sigma_j form the zonotope Z = { sum_j s_j g_j : |s_j| <= 1 }
/// with generators g_j = 3 sigma_j S_j, and the worst case is its farthest point from P, a vertex:
/// with the generators turned into the upper half plane and sorted by angle, the 2n vertices are
/// -sum g + 2 (g_(1) + ... + g_(k)) and their negatives (zonotope_farthest(), exact, O(n log n);
/// checked against all 2^n corners in test/test_tolerance.cpp). It is at least the 3-sigma
/// ellipse's major semi-axis (l1 >= l2 norm of the projections u . g_j) and at most the sum of the
/// separate effects sum_j |g_j| (triangle inequality), which is also reported, under that name.
/// The resolution is the tactor step of one ADC count on one joint: max_i |J_i| dtheta_count.
///
/// Clearance as a set (tolerance_play()). A pin of diameter d in a hole of d + 2c lets the joint
/// centre move anywhere within c; gear backlash b lets a proximal link turn within +-b/2, which
/// moves its elbow within a disc of radius 2 L_i sin(b/4) (the arc's chord bound, a superset).
/// Leg 1 (O1, A1) and leg 2 (O2, A2, and the tactor joint P: the tactor rides on L3) then start
/// their distal link anywhere within r_1, r_2 of the nominal elbow, so with the motors at their
/// nominal angles the tactor lies exactly in
///   S = { X : L3 - r1 <= |X - A1| <= L3 + r1,  L4 - r2 <= |X - A2| <= L4 + r2 }
/// on the nominal assembly side: the intersection of two thin annuli, a curvilinear quadrilateral
/// whose four corners are circle-circle intersections. The distance from P along each bounding arc
/// is unimodal with its maximum on the far side of the arc's centre, so the largest displacement
/// max |X - P| over S is at a corner (exact, not a linearisation). The first-order set is the
/// parallelogram P + M^{-1} [+-r1, +-r2] (M as above): it agrees for small play and grows like
/// 1/det M near a type II singularity, where S instead stays bounded until the inner circles stop
/// meeting (then the set is not a quadrilateral and the status says singular_type2).
///
/// Robust coverage (robust_coverage()). A printed device's own reachable region is the design's
/// with its perturbed lengths and base positions; it covers the target when its certified margin
/// (fivebar/coverage/coverage.hpp containment()) is >= 0. At each point b of the ellipse's boundary the
/// distance to each boundary arc k of the region is, to first order, d_k(b) + g_k(b) . dq (closed
/// form: robust_margin_at()), with standard deviation sigma_k(b) = sqrt(sum_j g_kj(b)^2 sigma_j^2);
/// the robust margin is min over b and k of d_k(b) - z_p sigma_k(b), z_p = Phi^{-1}(p), minimised
/// over the whole boundary by branch and bound with a certified lower bound (robust_margin_min(),
/// as containment() certifies the margin itself), capped by the certified margin. A device
/// covers only if every point does, so min Phi(d_k(b) / sigma_k(b)) over the points evaluated is
/// an upper bound of the fraction of devices that cover (the points' errors are correlated, and
/// where two boundary points are nearly as close the true fraction is lower). The Monte Carlo
/// reference evaluates containment() on each sampled device: the fraction that covers, and the
/// (1 - p) quantile of their margins with a one-sided 95 % lower confidence bound (an order
/// statistic; quantile_lower_bound_rank()) to set beside the robust margin. Joint angle offsets and
/// play do not move the reachable region (play only widens it), so they do not enter.

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/json.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/rendered_plot.hpp"
#include "fivebar/sections/tolerance.hpp"

namespace fivebar {

/// The perturbed parameters, in the column order of the sensitivity matrix.
enum class ToleranceParameter : std::uint8_t { L1, L2, L3, L4, O1x, O1y, O2x, O2y, theta1, theta2 };
inline constexpr std::size_t kToleranceParameters = 10;
/// Standard deviation of each parameter (mm for lengths and positions, rad for angles), >= 0.
using ParameterSigmas = std::array<double, kToleranceParameters>;
using SensitivityMatrix = Eigen::Matrix<double, 2, static_cast<int>(kToleranceParameters)>;

/// Names of the parameters ("L1", ..., "theta2"), in ToleranceParameter order.
const std::array<const char*, kToleranceParameters>& tolerance_parameter_names();

/// Covariance of the ten parameters (mm^2, mm rad, rad^2), ToleranceParameter order.
using ParameterCovariance = Eigen::Matrix<double, static_cast<int>(kToleranceParameters), static_cast<int>(kToleranceParameters)>;

/// A calibration's posterior covariance for one mechanism (docs/calibrate.md "Posterior covariance
/// in the design"), as the design's provenance entries record it, over the twelve calibration
/// parameters L1..L4, O1 x, y, O2 x, y (mm, absolute base positions), V0_1 (V), k_1 (rad/V), V0_2,
/// k_2; rows of the parameters it does not cover hold the `tolerance:` sigma (independent) instead.
/// The controller believes theta_j = k_j (V_j - V0_j); the device's true angle differs by
/// dtheta_j = (theta_j / k_j) dk_j - k_j dV0_j, so the joint-angle part depends on the pose.
struct CalibratedUncertainty {
  Eigen::Matrix<double, 12, 12> covariance = Eigen::Matrix<double, 12, 12>::Zero();
  std::array<bool, 12> measured{};           ///< covered by the calibration
  std::array<double, 2> rad_per_volt{1.0, 1.0};  ///< k_j of the design (the controller's)
  /// Independent joint-angle variance added to dtheta_j (rad^2): the potentiometer's linearity when
  /// its V0_j is calibrated, else the whole `tolerance:` angle sigma squared.
  std::array<double, 2> angle_variance{0.0, 0.0};
  std::vector<std::string> keys;             ///< the design keys covered
  std::vector<std::string> sources;          ///< their source files
  /// The ten-parameter covariance at joint angles theta1, theta2 (rad, as the controller computes them).
  ParameterCovariance at(double theta1, double theta2) const;
};

/// The parameters' errors as a zero-mean Gaussian: independent sigmas (the `tolerance:` section,
/// converted implicitly from ParameterSigmas) or a full covariance (a calibration's posterior, whose
/// joint-angle part depends on the pose: at()). Draws are F z with z ~ N(0, I) drawn in parameter
/// order and C = F F^T (F = diag(sigma) when independent, so the draws are those of the sigmas; else
/// F = V sqrt(Lambda) from C's eigen-decomposition); the +-k sigma box of the worst case and the
/// corners is that of the principal components (the columns of F) when correlated.
class ParameterSpread {
 public:
  ParameterSpread(const ParameterSigmas& sigma);  // NOLINT(google-explicit-constructor): a sigma array is a spread
  explicit ParameterSpread(const ParameterCovariance& covariance);
  explicit ParameterSpread(const CalibratedUncertainty& calibrated);

  bool correlated() const { return correlated_; }
  bool calibrated() const { return calibrated_.has_value(); }
  /// The square roots of the diagonal (at the pose of at(); joint angles at zero otherwise).
  const ParameterSigmas& sigma() const { return sigma_; }
  const ParameterCovariance& covariance() const { return covariance_; }
  /// The ten-parameter spread at joint angles theta1, theta2 (the same spread unless calibrated).
  ParameterSpread at(double theta1, double theta2) const;
  /// g^T C g.
  double variance(const std::array<double, kToleranceParameters>& g) const;
  /// F z.
  std::array<double, kToleranceParameters> draw(const std::array<double, kToleranceParameters>& z) const;
  /// Column k of F (the k-th independent generator; zero columns for absent components).
  std::array<double, kToleranceParameters> generator(std::size_t k) const;

 private:
  ParameterSigmas sigma_{};
  bool correlated_ = false;
  ParameterCovariance covariance_ = ParameterCovariance::Zero();
  ParameterCovariance factor_ = ParameterCovariance::Zero();
  std::optional<CalibratedUncertainty> calibrated_;
  void factorise();
};

/// dP/dq at a tactor point in the mechanism's working mode.
struct Sensitivity {
  Status status = Status::unreachable;  ///< ik()'s status; S and pose fields zero unless ok
  Pose pose;                            ///< the nominal configuration (from ik())
  SensitivityMatrix S = SensitivityMatrix::Zero();  ///< mm per mm, mm per rad
};

/// First-order tolerance figures at one tactor point.
struct ToleranceEstimate {
  Status status = Status::unreachable;  ///< not ok: every other field is zero
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();  ///< mm^2
  Vec2 ellipse_semi_axes{0.0, 0.0};  ///< 3-sigma semi-axes, major first, mm
  double ellipse_angle = 0.0;        ///< direction of the major axis, rad, in (-pi/2, pi/2]
  double worst_case_mm = 0.0;        ///< farthest point of the +-3 sigma zonotope (exact, first order), mm
  double sum_of_effects_mm = 0.0;    ///< sum_j |S_j| 3 sigma_j: the separate effects added, an upper bound, mm
  /// The sign of each parameter's 3 sigma at the worst corner (+1 or -1; ToleranceParameter order).
  std::array<std::int8_t, kToleranceParameters> worst_corner{};
  double resolution_um = 0.0;        ///< tactor step of one count on the worse joint, micrometres
  /// The linearisation is not to be trusted here: the sum of separate effects (a bound of every
  /// first-order displacement in the +-3 sigma box) reaches a quarter of
  /// the way to the type II singularity (min(L3, L4) |sin| of the tactor angle, the distance a
  /// distal link's end must move to align the links), where the error is no longer linear in the
  /// tolerances (the Monte Carlo then disagrees, and some printed devices cannot assemble).
  bool near_singular = false;
};

/// Farthest point from the origin of the 2-D zonotope { sum_j s_j g_j : -1 <= s_j <= 1 } (derivation
/// above): its norm, the point and the signs s_j in {-1, +1} of a vertex that attains it. Exact in
/// O(n log n); an empty or all-zero set of generators gives 0 with every sign +1.
struct ZonotopeExtreme {
  double norm = 0.0;
  Vec2 point{0.0, 0.0};
  std::vector<std::int8_t> signs;
};
ZonotopeExtreme zonotope_farthest(const std::vector<Vec2>& generators);

/// Closed-form sensitivity of the tactor to the ten parameters at P (derivation above).
/// Status is ik()'s: not ok (unreachable or within tol::kSingularSin of a singularity) gives zeros.
Sensitivity tolerance_sensitivity(const Mechanism& m, const Vec2& P);

/// Standard deviations of the ten parameters from a `tolerance:` section: a link's pin-centre
/// distance moves with its length error and with the along-link component of each of its two
/// holes' position errors, sqrt(link^2 + 2 pin^2); base positions by base_sigma_mm per axis; the
/// joint angle offsets by angle_sigma_deg (converted to rad).
ParameterSigmas parameter_sigmas(const ToleranceSettings& settings);

/// Joint angle of one ADC count (rad) when `bits` resolve one full turn: 2 pi / 2^bits.
/// Precondition: 1 <= bits <= 32.
double angle_per_count(int bits);

/// First-order covariance, 3-sigma ellipse, worst case and resolution at P for the given sigmas
/// and joint angle per ADC count (rad). Status as tolerance_sensitivity().
ToleranceEstimate tolerance_first_order(const Mechanism& m, const Vec2& P, const ParameterSpread& sigma,
                                        double rad_per_count);

/// Monte Carlo reference: `samples` printed devices, each parameter drawn independently from
/// N(0, sigma_j) by std::mt19937_64 seeded with `seed` (deterministic for a seed on one standard
/// library); each device's tactor is its FK at the nominal IK angles on the nominal assembly branch.
struct MonteCarloTolerance {
  Status status = Status::unreachable;  ///< nominal ik()'s status; zeros unless ok
  std::size_t used = 0;     ///< samples whose perturbed FK was reachable and regular
  std::size_t failed = 0;   ///< samples whose perturbed device cannot reach (or is singular)
  Vec2 mean_error{0.0, 0.0};                             ///< mean of P_printed - P, mm
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();  ///< sample covariance (n - 1), mm^2
};
MonteCarloTolerance tolerance_monte_carlo(const Mechanism& m, const Vec2& P, const ParameterSpread& sigma,
                                          std::size_t samples, std::uint64_t seed);
/// The 3-sigma major semi-axis of a 2 x 2 covariance (mm^2 -> mm): 3 sqrt(largest eigenvalue).
double major_3sigma_mm(const Eigen::Matrix2d& covariance);

/// The Monte Carlo reference at many tactor points at once: the same `samples` printed devices
/// (drawn in order from `seed`, as tolerance_monte_carlo() draws them) at every point, the points
/// shared out over OpenMP threads (the answer does not depend on the thread count). Element k is
/// tolerance_monte_carlo(m, points[k], sigma, samples, seed) up to the summation order.
std::vector<MonteCarloTolerance> tolerance_monte_carlo(const Mechanism& m, const std::vector<Vec2>& points,
                                                       const ParameterSpread& sigma, std::size_t samples,
                                                       std::uint64_t seed);

/// The nonlinear counterpart of the worst case: the printed device at every corner of the box
/// |dq_j| <= k_sigma sigma_j (2^10 devices; parameters with sigma_j = 0 stay nominal), each
/// tactor its FK at the nominal IK angles on the nominal assembly branch. The largest |P_printed -
/// P| over the corners is where the first-order worst case should land when the first order holds
/// (the nonlinear maximum over the box need not be at a corner; this is the reference where the
/// first order is flagged).
struct CornerEnumeration {
  Status status = Status::unreachable;  ///< nominal ik()'s status; zeros unless ok
  double worst_mm = 0.0;                ///< max over the corners that assemble, mm
  std::size_t corners = 0;              ///< corners enumerated (2^(parameters with sigma > 0))
  std::size_t failed = 0;               ///< corners whose device cannot reach (or is singular)
  std::array<std::int8_t, kToleranceParameters> worst_corner{};  ///< signs at the worst corner
};
CornerEnumeration tolerance_corners(const Mechanism& m, const Vec2& P, const ParameterSpread& sigma,
                                    double k_sigma = 3.0);

// --- Sources from a design ----------------------------------------------------------------------

/// What the analyses of one mechanism take from the design (`tolerance:`, `print:`, `controller:`).
struct ToleranceSources {
  /// parameter_sigmas(), the joint angle sigma combining the calibration offset and the
  /// potentiometer's linearity (uniform over +-linearity_percent of its travel: sigma = half band
  /// / sqrt(3)) in quadrature. The ADC's quantisation is the resolution, reported on its own.
  ParameterSigmas sigma{};
  /// What the analyses use (spread()): `sigma`, or, when the design's provenance entries hold a calibration's
  /// sigmas for this mechanism's links, bases or potentiometers, that posterior covariance in
  /// place of the `tolerance:` sigmas it covers (docs/calibrate.md "Posterior covariance in the design").
  std::optional<CalibratedUncertainty> calibrated;
  ParameterSpread spread() const { return calibrated ? ParameterSpread(*calibrated) : ParameterSpread(sigma); }
  /// "tolerance: (assumed)" or "calibration posterior (FILE) for L1, ...; tolerance: for the rest".
  std::string spread_source;
  std::array<double, 2> rad_per_count{0.0, 0.0};  ///< joint angle of one count, joints 1 and 2
  std::string resolution_source;                   ///< where rad_per_count comes from
  std::array<double, 2> leg_play_mm{0.0, 0.0};     ///< r1, r2 of the play set (header above)
  double robust_fraction = 0.997;
  std::uint64_t samples = 10000;
  std::uint64_t seed = 1;
};
/// The sources of `mechanism` of `station`: the design's `tolerance:` (or its defaults, all
/// assumptions), the pin play from print.pin_clearance unless tolerance.pin_play_mm is set, the
/// resolution from tolerance.adc_bits when set, else from the controller's ADC (range / 2^bits
/// volts per count times the joint's potentiometer scale), else 2^16 counts per turn.
ToleranceSources tolerance_sources(const Design& design, const Station& station, const Mechanism& mechanism);

// --- Clearance (play) as a set -------------------------------------------------------------------

struct PlaySet {
  /// ok; unreachable or singular as ik() at P; singular_type2 also when the annuli do not give the
  /// four corners (the set reaches across the distal-link line): extent_mm is then a lower bound.
  Status status = Status::unreachable;
  double extent_mm = 0.0;         ///< max |X - P| over the set (exact: at its corners), mm
  double linear_extent_mm = 0.0;  ///< the same over the first-order parallelogram, mm
  std::vector<Vec2> corners;      ///< the corners found (mm), up to four
};
/// The tactor's play set at P for legs' radial play r = {r1, r2} (mm, >= 0; derivation above).
PlaySet tolerance_play(const Mechanism& m, const Vec2& P, const std::array<double, 2>& leg_play_mm);

/// True when X lies in the play set of P (the two annuli, on P's assembly side), within `slack` mm.
bool in_play_set(const Mechanism& m, const Vec2& P, const std::array<double, 2>& leg_play_mm, const Vec2& X,
                 double slack);

// --- Robust coverage -------------------------------------------------------------------------------

/// The first-order robust margin at one point b inside the region (derivation in
/// lib/src/tolerance/tolerance_robust.cpp): each leg's set is bounded by circular arcs (centre c(q), radius
/// R(q)); the distance from b to an arc whose radial projection of b lies on it is |R - |b - c||,
/// with gradient g = sign (dR/dq - u . dc/dq), u = (b - c)/|b - c|; the margin at b is the smallest
/// of these over both legs, and the robust value is the smallest of d_k - z sigma_k, sigma_k^2 =
/// sum_j g_j^2 sigma_j^2 (a device fails at b when any arc passes it).
struct RobustPoint {
  bool inside = false;  ///< b lies in both legs' sets (otherwise the other fields are zero)
  double distance_mm = 0.0;   ///< signed distance to the region's boundary (min over the arcs)
  double robust_mm = 0.0;     ///< min over the arcs of d_k - z sigma_k
  double sigma_mm = 0.0;      ///< sigma_k of the arc that sets robust_mm
  std::array<double, kToleranceParameters> gradient{};  ///< g of that arc
};
RobustPoint robust_margin_at(const Mechanism& m, const ParameterSpread& sigma, double z, const Vec2& b);

/// The minimum of robust_margin_at() over the boundary of `target`, certified by branch and bound
/// on the ellipse parameter with a Lipschitz bound per arc (speed of the boundary times 1 + z
/// |dsigma_k/du| / |b - c|), to `tol_mm`: the true minimum lies in [lower_mm, value_mm].
/// Precondition: the target is inside the region (its margin > 0); otherwise certified is false.
struct RobustMarginBound {
  bool certified = false;
  double value_mm = 0.0;   ///< attained at `point` (an upper bound of the minimum)
  double lower_mm = 0.0;   ///< certified lower bound of the minimum
  Vec2 point{0.0, 0.0};
  RobustPoint at;          ///< robust_margin_at(point)
  std::size_t evaluations = 0;
  bool capped = false;     ///< the evaluation budget ran out before tol_mm was met
  double fraction_first_order = 1.0;  ///< min Phi(d_k / sigma_k) over the points evaluated
};
RobustMarginBound robust_margin_min(const Mechanism& m, const Ellipse& target, const ParameterSpread& sigma, double z,
                                    double tol_mm);

/// One-sided lower confidence bound of the p-quantile from n independent samples of a continuous
/// distribution: the (1-based) rank r of the largest order statistic X_(r) with
/// P(X_(r) <= q_p) = P(Binomial(n, p) >= r) >= confidence, and that probability (its exact
/// coverage). r = 0 when even X_(1) does not reach the confidence (too few samples).
struct QuantileBound {
  std::size_t rank = 0;
  double coverage = 0.0;
};
QuantileBound quantile_lower_bound_rank(std::size_t n, double p, double confidence);

struct RobustCoverage {
  double fraction = 0.997;         ///< of printed devices that must cover
  double margin_mm = 0.0;          ///< the design's certified margin (containment())
  bool decided = true;             ///< containment() decided the nominal verdict
  double sigma_mm = 0.0;           ///< sigma(b) at the boundary point that sets the robust margin
  double z = 0.0;                  ///< Phi^{-1}(fraction)
  double robust_margin_mm = 0.0;   ///< margin - z sigma: what `fraction` of printed devices keep (first order)
  double robust_margin_lower_mm = 0.0;  ///< certified lower bound of robust_margin_mm (robust_margin_min())
  bool robust_certified = false;   ///< the bound holds (the nominal margin is > 0 and the search converged)
  double fraction_first_order = 0.0;  ///< min_b Phi(d(b) / sigma(b)): an upper bound of the covering fraction
  bool covered = false;            ///< robust_margin_mm >= 0
  std::array<double, kToleranceParameters> gradient{};  ///< g(b) there (mm per mm, mm per rad)
  Vec2 robust_point{0.0, 0.0};     ///< that boundary point
  Vec2 worst_point{0.0, 0.0};      ///< where the nominal margin is smallest
  // Monte Carlo reference (samples = 0: not run).
  std::size_t samples = 0;
  std::size_t samples_covering = 0;
  double fraction_monte_carlo = 0.0;
  double quantile_margin_mm = 0.0;  ///< the (1 - fraction) quantile of the sampled margins
  /// One-sided lower bound of that quantile at quantile_confidence (order statistic, binomial;
  /// quantile_lower_bound_rank()); -inf stands for "too few samples" (then quantile_lower_rank = 0).
  double quantile_lower_mm = 0.0;
  double quantile_confidence = 0.95;
  std::size_t quantile_lower_rank = 0;
  double monte_carlo_stderr = 0.0;  ///< binomial standard error of fraction_monte_carlo
  bool calibrated = false;          ///< the spread was a calibration's posterior covariance
};
/// Robust coverage of `target` by `m` under `sigma` for a `fraction` of printed devices, with a
/// Monte Carlo check of `samples` devices (0: none; OpenMP over devices, the draws made in order
/// from `seed` first, so the answer does not depend on the thread count).
RobustCoverage robust_coverage(const Mechanism& m, const Ellipse& target, const ParameterSpread& sigma,
                               double fraction, std::size_t samples, std::uint64_t seed);

/// One sampled printed device: its parameter errors (ToleranceParameter order: mm, rad), where its
/// tactor lands when commanded to the target centre, and its own coverage margin.
struct DeviceSample {
  std::array<double, kToleranceParameters> dq{};
  Status status = Status::unreachable;  ///< of its FK at the nominal IK angles of the centre
  Vec2 error_mm{0.0, 0.0};              ///< P_printed - P at the centre (zero unless ok)
  double margin_mm = 0.0;               ///< containment() of the target by the device's region
};
/// The devices of robust_coverage()'s Monte Carlo (the same draws from `seed`), each with its
/// tactor error at the target centre and its margin: the rows of `fivebar tolerance --devices`.
std::vector<DeviceSample> tolerance_devices(const Mechanism& m, const Ellipse& target, const ParameterSpread& sigma,
                                            std::size_t samples, std::uint64_t seed);
/// CSV (a row per device, for pandas): device, dL1_mm ... dO2y_mm, dtheta1_deg, dtheta2_deg,
/// status, error_x_mm, error_y_mm, margin_mm, covers.
void write_devices_csv(std::ostream& out, const std::vector<DeviceSample>& devices);

/// Phi^{-1}(p) of the standard normal, p in (0, 1) (Newton on std::erfc, to rounding).
double normal_quantile(double p);

// --- Maps ----------------------------------------------------------------------------------------

/// The tolerance figures of one mechanism on a grid over its reachable region's bounding box
/// (x fastest), and their worst values over the filled target ellipse.
struct ToleranceMap {
  std::string station, mechanism;
  Ellipse target;
  double x0 = 0.0, y0 = 0.0, spacing_mm = 0.0;
  int nx = 0, ny = 0;
  std::vector<std::uint8_t> field_status;      ///< Status per grid point
  std::vector<double> field_3sigma_mm;         ///< major 3-sigma semi-axis (0 where not ok)
  std::vector<double> field_worst_case_mm;
  std::vector<double> field_resolution_um;     ///< tactor step of one count on the worse joint
  std::vector<double> field_play_mm;           ///< play set extent
  std::vector<std::uint8_t> field_near_singular;  ///< 1 where the first order is flagged (near_singular)
  // Over the filled target (a 21 x 21 grid of its bounding box, points inside):
  ToleranceEstimate centre;
  MonteCarloTolerance centre_monte_carlo;
  double centre_monte_carlo_3sigma_mm = 0.0;
  PlaySet centre_play;
  std::size_t target_points = 0, target_not_ok = 0;
  /// The headline worst case at the centre: the +-3 sigma corners on the real (nonlinear)
  /// kinematics (tolerance_corners()); centre.worst_case_mm beside it is its first-order estimate.
  CornerEnumeration centre_corners;
  /// worst_3sigma: the first-order 3-sigma ellipse's major semi-axis. worst_case: the nonlinear
  /// +-3 sigma corners (tolerance_corners()) at every regular target point, the largest;
  /// worst_case_first_order: the first-order corner (ToleranceEstimate::worst_case_mm), the largest.
  double worst_3sigma_mm = 0.0, worst_case_mm = 0.0, worst_case_first_order_mm = 0.0, worst_resolution_um = 0.0,
         worst_play_mm = 0.0;
  Vec2 worst_3sigma_at{0.0, 0.0}, worst_case_at{0.0, 0.0}, worst_case_first_order_at{0.0, 0.0},
      worst_resolution_at{0.0, 0.0}, worst_play_at{0.0, 0.0};
  /// Target points where the nonlinear corner exceeds the first-order one by more than 10 %.
  std::size_t first_order_low_by_10_percent = 0;
  std::vector<Vec2> target_points_mm;                  ///< the target grid's points
  std::vector<ToleranceEstimate> target_estimates;     ///< first order at each of them
  /// The target points where the first order is flagged (near_singular), with the Monte Carlo
  /// (the design's samples and seed) and the nonlinear corners there: the figures to believe.
  struct Flagged {
    Vec2 at{0.0, 0.0};
    ToleranceEstimate first_order;
    MonteCarloTolerance monte_carlo;
    double monte_carlo_3sigma_mm = 0.0;
    CornerEnumeration corners;
  };
  std::vector<Flagged> near_singular;
  bool worst_3sigma_flagged = false, worst_case_flagged = false,  ///< the reported worst point is flagged
      worst_case_first_order_flagged = false;
  RobustCoverage robust;
  std::string spread_source;  ///< ToleranceSources::spread_source
  bool calibrated = false;    ///< the sigmas are (partly) a calibration's posterior covariance
};
/// The map of one mechanism with `spacing_mm` (> 0; the grid is capped at 1000 x 1000 points).
ToleranceMap tolerance_map(const Mechanism& m, const std::string& station, const Ellipse& target,
                           const ToleranceSources& sources, double spacing_mm);

/// JSON of a robust coverage: fraction, margin_mm, decided, margin_sigma_mm, z, robust_margin_mm,
/// covered, fraction_first_order_at_most, robust_point_mm, worst_point_mm and the Monte Carlo
/// reference (monte_carlo_samples, _covering, fraction_monte_carlo, its stderr, the quantile margin).
Json to_json(const RobustCoverage& robust);

/// JSON with units at the edges: the figures at the centre and over the target, the play set and
/// the robust coverage (no grid: that is the .vti file's).
Json to_json(const ToleranceMap& map);

/// Picture of a station's maps (one row per mechanism): 3-sigma error over the target with error
/// ellipses at a grid of poses, and the play set's extent.
RenderedPlot plot_tolerance(const Station& station, const std::vector<ToleranceMap>& maps);

/// The files of a station's maps, name and bytes: `<station>-<mechanism>-tolerance.vti` per map
/// (ParaView: three_sigma_first_order_mm, worst_case_first_order_mm, resolution_um, play_mm, near_singular, status) and
/// `<station>-tolerance.svg`, `.png`.
std::vector<std::pair<std::string, std::string>> tolerance_files(const Station& station,
                                                                 const std::vector<ToleranceMap>& maps);
/// Writes `<station>-<mechanism>-tolerance.vti` per map and `<station>-tolerance.svg|.png` into
/// `dir` (atomically); returns the paths written.
std::vector<std::filesystem::path> write_tolerance_files(const std::filesystem::path& dir, const Station& station,
                                                         const std::vector<ToleranceMap>& maps);

}  // namespace fivebar
