#pragma once
/// Calibration poses chosen for the fit (docs/calibrate.md "Planning"): N joint targets per
/// mechanism within the usable joint ranges (fivebar/export/joint_limits.hpp usable_ranges(): declared
/// limits, hard stops against the base, potentiometer travel), away from singularities (LCI at
/// least `min_lci`), chosen greedily from a grid of candidates to maximise the determinant of the
/// scaled information matrix (D-optimal; every step adds the candidate of largest
/// det(I + J_c M^{-1} J_c^T)), then improved by exchanges. The instrument frame is taken as fixed
/// (the plan is per mechanism). Collision with the other mechanism is not checked: it depends on
/// where that mechanism is parked while this one is measured.

#include <cstdint>
#include <string>
#include <vector>

#include "fivebar/calibrate/model.hpp"
#include "fivebar/design.hpp"

namespace fivebar::calibrate {

struct PlanOptions {
  int poses = 30;              ///< N per mechanism
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
  std::string problem;                      ///< why no plan (too few candidates), else empty
};

/// One plan per mechanism of `station` (both when `mechanism` is empty).
std::vector<MechanismPlan> plan_poses(const Design& design, const std::string& station, const std::string& mechanism,
                                      const PlanOptions& options);

/// Posterior covariance sigma (file units) of the twelve parameters from poses at joint angles,
/// measurement sigma `sigma_mm`; inf for a parameter the poses do not determine.
std::vector<double> posterior_sigma(const Mechanism& m, const MechanismVector& q, const std::vector<PlannedPose>& poses,
                                    double sigma_mm);

}  // namespace fivebar::calibrate
