// simulate() (fivebar/dynamics.hpp): the controller's sample loop around SUNDIALS CVODE (BDF,
// Newton, dense direct solver). The only file that includes SUNDIALS (docs/architecture.md).

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>
#include <sstream>

#include "dynamics/system.hpp"
#include "fivebar/format.hpp"
#include "fivebar/tolerances.hpp"

namespace fivebar {

using dynamics_detail::Evaluation;
using dynamics_detail::kStateSize;
using dynamics_detail::System;

namespace {

int rhs_callback(realtype, N_Vector y, N_Vector dy, void* data) {
  System& s = *static_cast<System*>(data);
  ++s.evaluations;
  const double* yv = N_VGetArrayPointer(y);
  for (sunindextype i = 0; i < N_VGetLength(y); ++i) {
    if (!std::isfinite(yv[i])) return -1;  // unrecoverable
  }
  return dynamics_detail::rhs(s, yv, N_VGetArrayPointer(dy)) ? 0 : 1;  // 1: recoverable, CVODE cuts the step
}

int root_callback(realtype, N_Vector y, realtype* g, void* data) {
  dynamics_detail::roots(*static_cast<System*>(data), N_VGetArrayPointer(y), g);
  return 0;
}

void quiet(int, const char*, const char*, char* msg, void* data) { *static_cast<std::string*>(data) = msg; }

/// Owns the SUNDIALS objects of one run.
struct Cvode {
  SUNContext ctx = nullptr;
  N_Vector y = nullptr;
  N_Vector atol = nullptr;
  SUNMatrix A = nullptr;
  SUNLinearSolver LS = nullptr;
  void* mem = nullptr;
  ~Cvode() {
    if (mem) CVodeFree(&mem);
    if (LS) SUNLinSolFree(LS);
    if (A) SUNMatDestroy(A);
    if (atol) N_VDestroy(atol);
    if (y) N_VDestroy(y);
    if (ctx) SUNContext_Free(&ctx);
  }
};

std::string state_text(const SimulationInput& input, const double* y) {
  std::ostringstream s;
  for (std::size_t k = 0; k < input.mechanisms.size(); ++k) {
    const double* m = y + kStateSize * k;
    s << (k ? "; " : "") << input.mechanisms[k].name << " theta = (" << format::fixed(m[0] * format::kDegPerRad, 4)
      << ", " << format::fixed(m[1] * format::kDegPerRad, 4) << ") deg, w = (" << format::fixed(m[2], 4) << ", "
      << format::fixed(m[3], 4) << ") rad/s, i = (" << format::fixed(m[4], 4) << ", " << format::fixed(m[5], 4) << ") A";
  }
  return s.str();
}

}  // namespace

std::string_view to_string(SimStatus status) {
  switch (status) {
    case SimStatus::ok: return "ok";
    case SimStatus::singular: return "singular";
    case SimStatus::step_limit: return "step_limit";
    case SimStatus::wall_time_limit: return "wall_time_limit";
    case SimStatus::solver_failure: return "solver_failure";
  }
  return "?";
}

SimulationResult simulate(const SimulationInput& given, const SimulationOptions& options) {
  // A copy whose mechanisms stay on the FK branch they start on.
  SimulationInput input = given;
  for (SimulatedMechanism& m : input.mechanisms) {
    if (m.model.branch != AssemblyMode::Any) continue;
    const Pose p0 = fk(m.model.mechanism, m.theta0[0], m.theta0[1]);
    if (p0.assembly != 0) m.model.branch = p0.assembly > 0 ? AssemblyMode::Plus : AssemblyMode::Minus;
  }
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  SimulationResult result;
  if (input.mechanisms.empty()) throw InputError("simulate: no mechanism to simulate");
  std::size_t n_ref = 0;
  for (const SimulatedMechanism& m : input.mechanisms) {
    if (m.reference.empty() || m.reference.size() != m.reference_point_mm.size()) {
      throw InputError("simulate: mechanism " + m.name + " has no reference (or angles and points differ in length)");
    }
    n_ref = std::max(n_ref, m.reference.size());
  }
  if (!(options.rtol > 0.0) || !(options.rtol < 1.0)) throw InputError("simulate: rtol must be in (0, 1)");
  const ControllerSettings& ctl = input.controller;
  const double T = 1.0 / ctl.loop_rate_hz;
  const double duration = options.duration_s > 0.0 ? options.duration_s : double(n_ref - 1) * T + options.settle_s;
  const auto n_samples = static_cast<std::size_t>(std::floor(duration / T + tol::kSamplePeriodsRel));
  const std::size_t nm = input.mechanisms.size();
  const auto n = static_cast<sunindextype>(kStateSize * nm);

  System sys = dynamics_detail::make_system(input, options);
  Cvode cv;
  if (SUNContext_Create(nullptr, &cv.ctx) != 0) throw std::runtime_error("SUNDIALS: cannot create a context");
  cv.y = N_VNew_Serial(n, cv.ctx);
  cv.atol = N_VNew_Serial(n, cv.ctx);
  double* y = N_VGetArrayPointer(cv.y);
  double* atol = N_VGetArrayPointer(cv.atol);
  for (std::size_t k = 0; k < nm; ++k) {
    const SimulatedMechanism& m = input.mechanisms[k];
    double* yk = y + kStateSize * k;
    yk[0] = m.theta0[0];
    yk[1] = m.theta0[1];
    yk[2] = options.lock_joints ? 0.0 : m.w0[0];
    yk[3] = options.lock_joints ? 0.0 : m.w0[1];
    yk[4] = yk[5] = 0.0;
    const DynamicsTerms t0 = dynamics_terms(m.model, Eigen::Vector2d(yk[0], yk[1]), Eigen::Vector2d::Zero());
    yk[6] = t0.P.x();
    yk[7] = t0.P.y();
    double* ak = atol + kStateSize * k;
    const double r = options.rtol;
    ak[0] = ak[1] = r * options.angle_scale;
    ak[2] = ak[3] = r * options.rate_scale;
    ak[4] = ak[5] = r * options.current_scale;
    ak[6] = ak[7] = r * options.anchor_scale;
    if (t0.status == Status::unreachable || t0.status == Status::singular_type2) {
      result.status = SimStatus::singular;
      result.reason = "t = 0 s: the initial pose of " + m.name + " is " + std::string(to_string(t0.status));
      result.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
      return result;
    }
  }
  std::string solver_message;
  cv.mem = CVodeCreate(CV_BDF, cv.ctx);
  if (cv.mem == nullptr) throw std::runtime_error("SUNDIALS: CVodeCreate failed");
  CVodeSetErrHandlerFn(cv.mem, &quiet, &solver_message);
  CVodeInit(cv.mem, &rhs_callback, 0.0, cv.y);
  CVodeSVtolerances(cv.mem, options.rtol, cv.atol);
  CVodeSetUserData(cv.mem, &sys);
  cv.A = SUNDenseMatrix(n, n, cv.ctx);
  cv.LS = SUNLinSol_Dense(cv.y, cv.A, cv.ctx);
  CVodeSetLinearSolver(cv.mem, cv.LS, cv.A);
  const bool roots = options.contact;
  if (roots) {
    CVodeRootInit(cv.mem, static_cast<int>(nm), &root_callback);
    CVodeSetNoInactiveRootWarn(cv.mem);
  }

  // Controllers, per mechanism and joint.
  std::vector<std::array<DiscretePid, 2>> pids;
  for (const SimulatedMechanism& m : input.mechanisms) {
    pids.push_back({DiscretePid(m.control[0].pid, T), DiscretePid(m.control[1].pid, T)});
  }
  std::vector<std::array<double, 2>> pending(nm, {0.0, 0.0});
  std::vector<MechanismSummary> summary(nm);
  std::vector<double> sum_err2(nm, 0.0), sum_i2(nm, 0.0);
  std::vector<double> peak_i(nm, 0.0);
  for (std::size_t k = 0; k < nm; ++k) summary[k].name = input.mechanisms[k].name;

  double t = 0.0;
  std::size_t recorded = 0;
  for (std::size_t s = 0;; ++s) {
    const double tk = double(s) * T;
    // The controller at t_k: read, compute, and choose what is applied over [t_k, t_k+1).
    for (std::size_t k = 0; k < nm; ++k) {
      const SimulatedMechanism& m = input.mechanisms[k];
      const auto& ref = m.reference[std::min(s, m.reference.size() - 1)];
      std::array<double, 2> fresh{0.0, 0.0};
      for (std::size_t j = 0; j < 2; ++j) {
        const double theta = y[kStateSize * k + j];
        const double measured =
            options.quantise ? adc_reading(theta, m.control[j].potentiometer, ctl.adc_bits, ctl.adc_range_v) : theta;
        fresh[j] = pids[k][j].update(ref[j] - measured);
      }
      if (options.drive == Drive::constant_duty) {
        sys.duty[k] = {options.duty, options.duty};
      } else if (options.drive == Drive::open_circuit) {
        sys.duty[k] = {0.0, 0.0};
      } else {
        sys.duty[k] = options.delay ? pending[k] : fresh;
      }
      pending[k] = fresh;
    }
    // Record the sample.
    TimeSample sample;
    sample.t = tk;
    for (std::size_t k = 0; k < nm; ++k) {
      const SimulatedMechanism& m = input.mechanisms[k];
      const Evaluation ev = dynamics_detail::evaluate(sys, k, y);
      const double* yk = y + kStateSize * k;
      MechanismSample ms;
      const std::size_t r = std::min(s, m.reference.size() - 1);
      ms.theta_ref = m.reference[r];
      ms.theta = {yk[0], yk[1]};
      ms.w = {yk[2], yk[3]};
      ms.current = {yk[4], yk[5]};
      ms.duty = sys.duty[k];
      ms.voltage = ev.voltage;
      ms.P_ref_mm = m.reference_point_mm[r];
      ms.P_mm = ev.terms.P * 1e3;
      ms.force_N = ev.force;
      ms.slipping = sys.slipping[k] != 0;
      ms.energy_J = 0.5 * Eigen::Vector2d(yk[2], yk[3]).dot(ev.terms.M * Eigen::Vector2d(yk[2], yk[3]));
      MechanismSummary& sum = summary[k];
      const double err = (ms.P_mm - ms.P_ref_mm).norm();
      sum.max_error_mm = std::max(sum.max_error_mm, err);
      sum_err2[k] += err * err;
      for (std::size_t j = 0; j < 2; ++j) {
        sum.max_joint_error_deg = std::max(sum.max_joint_error_deg, std::abs(ms.theta[j] - ms.theta_ref[j]) * format::kDegPerRad);
        sum.peak_duty = std::max(sum.peak_duty, std::abs(ms.duty[j]));
        sum_i2[k] += ms.current[j] * ms.current[j];
      }
      if (s < n_samples && (ev.saturated[0] || ev.saturated[1])) sum.saturation_s += T;
      sum.peak_shear_N = std::max(sum.peak_shear_N, ms.force_N.norm());
      if (options.record) sample.mechanisms.push_back(ms);
    }
    ++recorded;
    if (options.record) result.samples.push_back(std::move(sample));
    if (s == n_samples) break;

    // Integrate to the next sample: a restart, the sample time a stop time.
    const double t_next = double(s + 1) * T;
    CVodeReInit(cv.mem, tk, cv.y);
    CVodeSetStopTime(cv.mem, t_next);
    if (roots) {
      std::vector<int> dir = dynamics_detail::root_directions(sys);
      CVodeSetRootDirection(cv.mem, dir.data());
    }
    ++result.restarts;
    t = tk;
    while (t < t_next) {
      sys.last_failure_singular = false;
      const int flag = CVode(cv.mem, t_next, cv.y, &t, CV_ONE_STEP);
      ++result.steps;
      if (flag == CV_ROOT_RETURN) {
        std::vector<int> found(nm, 0);
        CVodeGetRootInfo(cv.mem, found.data());
        for (std::size_t k = 0; k < nm; ++k) {
          if (found[k] == 0) continue;
          sys.slipping[k] = !sys.slipping[k];
          if (sys.slipping[k]) {
            summary[k].slipped = true;
            ++summary[k].slips;
          }
        }
        if (t < t_next) {
          CVodeReInit(cv.mem, t, cv.y);
          CVodeSetStopTime(cv.mem, t_next);
          std::vector<int> dir = dynamics_detail::root_directions(sys);
          CVodeSetRootDirection(cv.mem, dir.data());
          ++result.restarts;
        }
      } else if (flag < 0) {
        result.status = sys.last_failure_singular || flag == CV_REPTD_RHSFUNC_ERR || flag == CV_RHSFUNC_FAIL
                            ? SimStatus::singular
                            : SimStatus::solver_failure;
        result.reason = "t = " + format::fixed(t, 6) + " s: " + state_text(input, y) + ": " +
                        (result.status == SimStatus::singular ? "a pose reached a type II singularity or left the "
                                                                "workspace; CVODE: "
                                                              : "CVODE: ") +
                        solver_message;
        break;
      }
      for (std::size_t k = 0; k < nm; ++k) {
        for (std::size_t j = 0; j < 2; ++j) peak_i[k] = std::max(peak_i[k], std::abs(y[kStateSize * k + 4 + j]));
      }
      if (result.steps > options.max_steps) {
        result.status = SimStatus::step_limit;
        result.reason = "t = " + format::fixed(t, 6) + " s: more than " + std::to_string(options.max_steps) +
                        " integrator steps (" + state_text(input, y) + ")";
        break;
      }
      if (std::chrono::duration<double>(Clock::now() - start).count() > options.max_wall_s) {
        result.status = SimStatus::wall_time_limit;
        result.reason = "t = " + format::fixed(t, 6) + " s: more than " + format::fixed(options.max_wall_s, 1) +
                        " s of wall time (" + state_text(input, y) + ")";
        break;
      }
    }
    if (result.status != SimStatus::ok) break;
  }
  result.rhs_evaluations = sys.evaluations;
  result.t_end = result.status == SimStatus::ok ? double(n_samples) * T : t;
  for (std::size_t k = 0; k < nm; ++k) {
    summary[k].rms_error_mm = std::sqrt(sum_err2[k] / double(recorded));
    summary[k].rms_current_A = std::sqrt(sum_i2[k] / double(2 * recorded));
    summary[k].peak_current_A = peak_i[k];
  }
  result.summary = std::move(summary);
  result.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

}  // namespace fivebar
