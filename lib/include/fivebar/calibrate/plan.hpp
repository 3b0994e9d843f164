#pragma once
/// Calibration poses chosen for the fit (docs/calibrate.md "Planning"): N joint targets per
/// mechanism within the usable joint ranges (fivebar/device/joint_limits.hpp usable_ranges(): declared
/// limits, hard stops against the base, potentiometer travel), away from singularities (LCI at
/// least `min_lci`), at least `extension_margin_mm` from each leg's full extension and folding
/// and `base_margin_mm` from the mechanism's base line on the target's side, and reachable by every
/// one of `reach_samples` devices drawn within 4 prior sigmas of every parameter (a margin over the
/// 3-sigma box; prior_sigma(), fivebar/calibrate/fit.hpp). From a grid of such candidates the poses are chosen
/// greedily, then improved by exchanges, to minimise the predicted tactor error over the target
/// (I-optimal, the default: the mean over target points t of trace(G_t M^{-1} G_t^T), G_t the
/// tactor's sensitivity to the parameters where the controller drives it to t, M the information
/// matrix of the poses; a linearisation) or, as an option, to maximise det M (D-optimal on the
/// parameters). The instrument frame is taken as fixed (the plan is per mechanism). Collision with
/// the other mechanism is not checked: it depends on where that mechanism is parked while this one
/// is measured.

#include <cstdint>
#include <string>
#include <vector>

#include "fivebar/calibrate/model.hpp"
#include "fivebar/design.hpp"

namespace fivebar::calibrate {

enum class PlanCriterion { i_optimal, d_optimal };

struct PlanOptions {
  int poses = 30;              ///< N per mechanism
  PlanCriterion criterion = PlanCriterion::i_optimal;
  double extension_margin_mm = 0.5;  ///< from a leg's full extension or folding (|P - O_i| vs L_i +- L_{i+2})
  double base_margin_mm = 2.0;       ///< from the mechanism's base line O1 O2, on the target's side
  int reach_samples = 64;            ///< perturbed devices each candidate must be reachable by
  double sigma_mm = 0.02;      ///< the measurement sigma the expected posterior sigmas assume
  int grid = 41;               ///< candidates per joint
  double min_lci = 0.1;        ///< candidates keep at least this LCI
  int random_trials = 50;      ///< random N-pose sets the plan is compared with
  std::uint64_t seed = 1;
};

struct PlannedPose {
  double theta1 = 0.0, theta2 = 0.0;  ///< rad
  double volts1 = 0.0, volts2 = 0.0;  ///< the potentiometer readings at the design calibration
  Vec2 point{0.0, 0.0};               ///< the tactor by FK, mm
};

struct MechanismPlan {
  std::string station, mechanism;
  std::vector<PlannedPose> poses;
  int candidates = 0;
  double observability_index = 0.0;         ///< O1 of the plan (a-priori scales)
  double random_observability_index = 0.0;  ///< median over the random sets
  std::vector<std::string> names;           ///< the twelve parameters (model.hpp)
  std::vector<double> expected_sigma;       ///< posterior sigma of each at options.sigma_mm, file units
  std::vector<double> random_sigma;         ///< median over the random sets (inf when singular)
  /// Predicted RMS tactor error over the target after calibrating with these poses at
  /// options.sigma_mm, mm: sqrt(mean_t trace(G_t C G_t^T)), C the posterior covariance (a
  /// linearisation); inf when the poses do not determine every parameter.
  double predicted_target_error_mm = 0.0;
  double random_target_error_mm = 0.0;      ///< median over the random sets
  int target_points = 0;                    ///< points of the target the error is averaged over
  std::string problem;                      ///< why no plan (too few candidates), else empty
};

/// One plan per mechanism of `station` (both when `mechanism` is empty).
std::vector<MechanismPlan> plan_poses(const Design& design, const std::string& station, const std::string& mechanism,
                                      const PlanOptions& options);

/// The predicted RMS tactor error over the target points (see MechanismPlan): tactor sensitivity
/// rows at `targets` (joint readings the controller drives to), poses' information at sigma_mm.
double predicted_target_error(const Mechanism& m, const MechanismVector& q, const std::vector<PlannedPose>& poses,
                              const std::vector<PlannedPose>& targets, double sigma_mm);
/// Points of the station's target ellipse (a grid of about n x n inside it) as the joint readings
/// the controller drives to with the design's calibration.
std::vector<PlannedPose> target_points(const Design& design, const Station& station, const Mechanism& m, int n = 15);

/// Posterior covariance sigma (file units) of the twelve parameters from poses at joint angles,
/// measurement sigma `sigma_mm`; inf for a parameter the poses do not determine.
std::vector<double> posterior_sigma(const Mechanism& m, const MechanismVector& q, const std::vector<PlannedPose>& poses,
                                    double sigma_mm);

}  // namespace fivebar::calibrate
