// Kinematic calibration by nonlinear least squares (fivebar/calibrate/fit.hpp). Ceres Solver stays
// in this file.
#include "fivebar/calibrate/fit.hpp"

#include <ceres/ceres.h>

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <limits>
#include <numeric>

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/sections/controller.hpp"

namespace fivebar::calibrate {

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

/// One pose's residual (model - measured) / sigma with its analytic Jacobian (model.hpp).
class PoseCost final : public ceres::SizedCostFunction<2, kMechanismParameters, kFrameParameters> {
 public:
  PoseCost(const Mechanism& m, const Measurement& row, double weight) : m_(m), row_(row), w_(weight) {}
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Map<const MechanismVector> q(parameters[0]);
    const Eigen::Map<const FrameVector> frame(parameters[1]);
    const Prediction p = predict(m_, q, frame, row_.volts1, row_.volts2);
    if (p.status != Status::ok) return false;  // Ceres rejects the step
    residuals[0] = w_ * (p.y.x() - row_.point.x());
    residuals[1] = w_ * (p.y.y() - row_.point.y());
    if (jacobians != nullptr) {
      if (jacobians[0] != nullptr) {
        Eigen::Map<Eigen::Matrix<double, 2, kMechanismParameters, Eigen::RowMajor>> J(jacobians[0]);
        J = w_ * p.dq;
      }
      if (jacobians[1] != nullptr) {
        Eigen::Map<Eigen::Matrix<double, 2, kFrameParameters, Eigen::RowMajor>> J(jacobians[1]);
        J = w_ * p.dframe;
      }
    }
    return true;
  }

 private:
  Mechanism m_;
  Measurement row_;
  double w_;
};

struct Block {
  std::string name;
  const Mechanism* design = nullptr;
  MechanismVector q;
  std::vector<std::size_t> rows;  ///< indices into the station's measurements
};

/// Poses the design's nominal model cannot assemble: the device reached them, so they are skipped
/// and named rather than fatal (docs/calibrate.md); blocks left without poses are dropped.
void skip_unassemblable(std::vector<Block>& blocks, const std::vector<Measurement>& all, std::vector<ExcludedPose>& skipped) {
  for (Block& b : blocks) {
    std::erase_if(b.rows, [&](std::size_t i) {
      const Prediction p = predict(*b.design, b.q, FrameVector::Zero(), all[i].volts1, all[i].volts2);
      if (p.status == Status::ok) return false;
      skipped.push_back({all[i].line, b.name,
                         "readings " + format::shortest(all[i].volts1) + ", " + format::shortest(all[i].volts2) +
                             " V: the design's nominal model cannot assemble the pose (" + std::string(to_string(p.status)) + ")",
                         0.0, 0.0});
      return true;
    });
  }
  std::erase_if(blocks, [](const Block& b) { return b.rows.empty(); });
}

std::string skipped_text(const std::vector<ExcludedPose>& skipped) {
  std::vector<std::string> lines;
  for (const ExcludedPose& e : skipped) lines.push_back("line " + std::to_string(e.line));
  return format::join(lines);
}

/// Marks the poses whose residual at the robust estimate exceeds kOutlierScales robust scales
/// (the given sigma when every row has one, else 1.4826 times the median absolute residual per
/// axis); returns how many were marked.
template <class Weight>
int flag_outliers(const std::vector<Block>& blocks, const std::vector<Measurement>& all, const std::vector<bool>& held_out,
                  const FrameVector& frame, const Weight& weight, bool all_sigma, std::vector<bool>& outlier,
                  std::vector<ExcludedPose>& named) {
  struct Row {
    std::size_t index;
    const Block* block;
    Vec2 r;  // weighted residual
    double mm;
  };
  std::vector<Row> rows;
  std::vector<double> axis;
  for (const Block& b : blocks) {
    for (std::size_t i : b.rows) {
      if (held_out[i]) continue;
      const Prediction p = predict(*b.design, b.q, frame, all[i].volts1, all[i].volts2);
      if (p.status != Status::ok) continue;
      const Vec2 e = p.y - all[i].point;
      rows.push_back({i, &b, weight(all[i]) * e, e.norm()});
      axis.push_back(std::abs(rows.back().r.x()));
      axis.push_back(std::abs(rows.back().r.y()));
    }
  }
  if (axis.empty()) return 0;
  std::nth_element(axis.begin(), axis.begin() + static_cast<std::ptrdiff_t>(axis.size() / 2), axis.end());
  const double scale = all_sigma ? 1.0 : std::max(1.4826 * axis[axis.size() / 2], 1e-12);
  int n = 0;
  for (const Row& row : rows) {
    const double z = row.r.norm() / scale;
    if (!(z > kOutlierScales)) continue;
    outlier[row.index] = true;
    named.push_back({all[row.index].line, row.block->name,
                     "outlier: residual " + format::fixed(row.mm, 4) + " mm, " + format::fixed(z, 1) + " robust scales (limit " +
                         format::fixed(kOutlierScales, 2) + ")",
                     row.mm, z});
    ++n;
  }
  return n;
}

std::string unit_of(int i) {
  if (i < 8) return "mm";
  return i % 2 == 0 ? "V" : "rad/V";
}

}  // namespace

double prior_sigma(int index, const MechanismVector& q) { return parameter_scale(index, q); }

double parameter_scale(int index, const MechanismVector& q) {
  if (index >= kMechanismParameters) return index == kMechanismParameters ? kDeg : 0.1;
  if (index < 8) return 0.1;
  if (index == 8 || index == 10) return kDeg / std::max(std::abs(q[index + 1]), 1e-12);
  return 0.01 * std::abs(q[index]);
}

CalibrationResult calibrate(const Design& design, const std::vector<Measurement>& all, const CalibrateOptions& opt,
                            const std::string& origin) {
  CalibrationResult out;
  // The station.
  std::string station = opt.station;
  if (station.empty()) {
    for (const Measurement& r : all) {
      if (station.empty()) station = r.station;
      if (r.station != station) {
        throw InputError(origin + ": measurements of stations " + station + " and " + r.station +
                         ": choose one (--station)");
      }
    }
  }
  const Station& st = design.require_station(station);
  out.station = station;
  const ControllerSettings* controller = design.get<ControllerSettings>();
  std::vector<Block> blocks;
  for (const Mechanism* m : st.mechanisms()) {
    if (!opt.mechanisms.empty() && std::find(opt.mechanisms.begin(), opt.mechanisms.end(), m->name) == opt.mechanisms.end()) continue;
    Block b;
    b.name = m->name;
    b.design = m;
    const Potentiometer p1 = controller ? controller->joint(station, m->name, 1).potentiometer : Potentiometer{};
    const Potentiometer p2 = controller ? controller->joint(station, m->name, 2).potentiometer : Potentiometer{};
    b.q = mechanism_vector(*m, p1.volts_at_zero, p1.rad_per_volt, p2.volts_at_zero, p2.rad_per_volt);
    for (std::size_t i = 0; i < all.size(); ++i) {
      if (all[i].station == station && all[i].mechanism == m->name) b.rows.push_back(i);
    }
    if (!b.rows.empty()) blocks.push_back(std::move(b));
  }
  for (const std::string& name : opt.mechanisms) {
    if (st.mechanism(name) == nullptr) throw InputError("station " + station + " has no mechanism '" + name + "'");
  }
  if (blocks.empty()) throw InputError(origin + ": no measurements of station " + station + (opt.mechanisms.empty() ? "" : " for the chosen mechanisms"));
  skip_unassemblable(blocks, all, out.skipped);
  if (blocks.empty()) throw InputError(origin + ": no pose of station " + station + " can be assembled by the design's model: " + skipped_text(out.skipped));

  const int nb = static_cast<int>(blocks.size());
  const int np = nb * kMechanismParameters + kFrameParameters;
  const int frame0 = nb * kMechanismParameters;
  for (const Block& b : blocks) out.mechanisms.push_back(b.name);

  // Requested parameters.
  std::vector<bool> requested(static_cast<std::size_t>(np), false);
  const auto& mnames = mechanism_parameter_names();
  const auto& fnames = frame_parameter_names();
  if (!opt.fit_given) {
    for (int k = 0; k < frame0; ++k) requested[static_cast<std::size_t>(k)] = true;
    for (int k = 0; k < kFrameParameters; ++k) requested[static_cast<std::size_t>(frame0 + k)] = opt.fit_frame;
  } else {
    for (const std::string& name : opt.fit) {
      const auto mi = std::find(mnames.begin(), mnames.end(), name);
      const auto fi = std::find(fnames.begin(), fnames.end(), name);
      if (mi != mnames.end()) {
        for (int b = 0; b < nb; ++b) requested[static_cast<std::size_t>(b * kMechanismParameters + (mi - mnames.begin()))] = true;
      } else if (fi != fnames.end()) {
        if (!opt.fit_frame) throw InputError("fit: '" + name + "' needs the instrument's pose fitted (frame fit)");
        requested[static_cast<std::size_t>(frame0 + (fi - fnames.begin()))] = true;
      } else {
        throw InputError("fit: unknown parameter '" + name + "' (known: " + format::join({mnames.begin(), mnames.end()}) + ", " +
                         format::join({fnames.begin(), fnames.end()}) + ")");
      }
    }
  }
  const auto full_name = [&](int k) {
    if (k >= frame0) return fnames[static_cast<std::size_t>(k - frame0)];
    return blocks[static_cast<std::size_t>(k / kMechanismParameters)].name + "." + mnames[static_cast<std::size_t>(k % kMechanismParameters)];
  };

  // Hold-out poses: K evenly spaced over the station's measurements.
  std::vector<std::size_t> rows;
  for (const Block& b : blocks) rows.insert(rows.end(), b.rows.begin(), b.rows.end());
  std::sort(rows.begin(), rows.end());
  std::vector<bool> held_out(all.size(), false);
  if (opt.holdout < 0 || static_cast<std::size_t>(opt.holdout) >= rows.size()) {
    throw InputError("holdout = " + std::to_string(opt.holdout) + ": must be >= 0 and < the " + std::to_string(rows.size()) +
                     " poses of station " + station);
  }
  for (int j = 0; j < opt.holdout; ++j) {
    held_out[rows[static_cast<std::size_t>((j + 0.5) * static_cast<double>(rows.size()) / opt.holdout)]] = true;
  }
  const auto sigma_of = [&](const Measurement& r) { return opt.sigma_mm ? *opt.sigma_mm : r.sigma_mm; };
  bool all_sigma = true;
  for (std::size_t i : rows) all_sigma = all_sigma && sigma_of(all[i]) > 0.0;
  const auto weight = [&](const Measurement& r) { return all_sigma ? 1.0 / sigma_of(r) : 1.0; };

  std::vector<bool> outlier(all.size(), false);  // named by the robust fit, left out of the final fit
  FrameVector frame = FrameVector::Zero();
  const FrameVector frame_prior = frame;
  int fit_rows = 0;
  // The stacked weighted Jacobian (fitting rows) at the current values, every parameter.
  const auto stacked = [&](Eigen::MatrixXd& J, Eigen::VectorXd& r) {
    J.setZero(2 * fit_rows, np);
    r.setZero(2 * fit_rows);
    int row = 0;
    for (int b = 0; b < nb; ++b) {
      const Block& blk = blocks[static_cast<std::size_t>(b)];
      for (std::size_t i : blk.rows) {
        if (held_out[i] || outlier[i]) continue;
        const Measurement& m = all[i];
        const Prediction p = predict(*blk.design, blk.q, frame, m.volts1, m.volts2);
        if (p.status != Status::ok) {
          throw InputError(origin + ":" + std::to_string(m.line) + ": readings " + format::shortest(m.volts1) + ", " +
                           format::shortest(m.volts2) + " V put " + station + "/" + blk.name + " at a pose the model cannot assemble (" +
                           std::string(to_string(p.status)) + ")");
        }
        const double w = weight(m);
        J.block(row, b * kMechanismParameters, 2, kMechanismParameters) = w * p.dq;
        J.block(row, frame0, 2, kFrameParameters) = w * p.dframe;
        r.segment<2>(row) = w * (p.y - m.point);
        row += 2;
      }
    }
  };
  for (std::size_t i : rows) fit_rows += held_out[i] ? 0 : 1;

  const auto unknowns = static_cast<int>(std::count(requested.begin(), requested.end(), true));
  if (2 * fit_rows < unknowns) {
    throw InputError(origin + ": " + std::to_string(fit_rows) + " poses give " + std::to_string(2 * fit_rows) + " equations for " +
                     std::to_string(unknowns) + " unknowns: measure at least " + std::to_string((unknowns + 1) / 2) + " poses" +
                     (out.skipped.empty() ? std::string()
                                          : " (" + std::to_string(out.skipped.size()) + " skipped: the design's model cannot assemble " +
                                                skipped_text(out.skipped) + ")"));
  }

  // Identifiability at the design values: greedy in the order of preference (fit.hpp).
  std::vector<int> order;
  for (int b = 0; b < nb; ++b) {
    for (int i : {0, 1, 2, 3, 9, 11, 8, 10}) order.push_back(b * kMechanismParameters + i);
  }
  for (int i = 0; i < kFrameParameters; ++i) order.push_back(frame0 + i);
  for (int b = nb - 1; b >= 0; --b) {
    const bool lower = blocks[static_cast<std::size_t>(b)].name == "lower";
    for (int i : lower ? std::array{6, 4, 5, 7} : std::array{4, 5, 6, 7}) order.push_back(b * kMechanismParameters + i);
  }
  Eigen::MatrixXd J;
  Eigen::VectorXd r0;
  stacked(J, r0);
  std::vector<double> scale(static_cast<std::size_t>(np));
  for (int k = 0; k < np; ++k) {
    scale[static_cast<std::size_t>(k)] =
        parameter_scale(k >= frame0 ? k - frame0 + kMechanismParameters : k % kMechanismParameters,
                        blocks[static_cast<std::size_t>(std::min(k, frame0 - 1) / kMechanismParameters)].q);
  }
  std::vector<int> kept;
  Eigen::MatrixXd Q(J.rows(), 0);
  std::vector<bool> fitted(static_cast<std::size_t>(np), false);
  for (int k : order) {
    if (!requested[static_cast<std::size_t>(k)]) continue;
    const Eigen::VectorXd col = J.col(k) * scale[static_cast<std::size_t>(k)];
    Eigen::VectorXd res = col;
    for (int pass = 0; pass < 2; ++pass) res -= Q * (Q.transpose() * res);
    const double norm = col.norm();
    if (norm > 0.0 && res.norm() > kUnidentifiableRel * norm) {
      Q.conservativeResize(Eigen::NoChange, Q.cols() + 1);
      Q.col(Q.cols() - 1) = res / res.norm();
      kept.push_back(k);
      fitted[static_cast<std::size_t>(k)] = true;
      continue;
    }
    Unidentifiable u;
    u.parameter = full_name(k);
    if (norm == 0.0) {
      u.combination = "no pose moves the tactor with it";
    } else {
      Eigen::MatrixXd A(J.rows(), static_cast<Eigen::Index>(kept.size()));
      for (std::size_t c = 0; c < kept.size(); ++c) A.col(static_cast<Eigen::Index>(c)) = J.col(kept[c]) * scale[static_cast<std::size_t>(kept[c])];
      const Eigen::VectorXd coef = A.completeOrthogonalDecomposition().solve(col);
      std::string text;
      for (std::size_t c = 0; c < kept.size(); ++c) {
        const double v = coef[static_cast<Eigen::Index>(c)];
        if (std::abs(v) < 0.05) continue;
        text += (text.empty() ? (v < 0 ? "-" : "") : (v < 0 ? " - " : " + ")) + format::fixed(std::abs(v), 3) + " " + full_name(kept[c]);
      }
      u.combination = "moves the tactor as " + (text.empty() ? std::string("nothing") : text) + " (in a-priori scales)";
    }
    out.unidentifiable.push_back(u);
    if (opt.fit_given) out.requested_unidentifiable = true;
  }

  // Figures at the design values. residual_of[i]: row i's entry of out.residuals, so that the
  // figures after the fit are linear in rows (one lookup per row, not a scan of every residual).
  std::vector<std::size_t> residual_of(all.size(), 0);
  const auto figures = [&](bool holdout, bool after) {
    Figures f;
    int n = 0;
    for (int b = 0; b < nb; ++b) {
      const Block& blk = blocks[static_cast<std::size_t>(b)];
      for (std::size_t i : blk.rows) {
        if (held_out[i] != holdout) continue;
        const Prediction p = predict(*blk.design, blk.q, frame, all[i].volts1, all[i].volts2);
        const double e = p.status == Status::unreachable ? std::numeric_limits<double>::infinity() : (p.y - all[i].point).norm();
        f.rms_mm += e * e;
        f.max_mm = std::max(f.max_mm, e);
        ++n;
        if (!after) {
          residual_of[i] = out.residuals.size();
          out.residuals.push_back({all[i].line, blk.name, holdout, e, 0.0});
        } else {
          out.residuals[residual_of[i]].after_mm = e;
        }
      }
    }
    f.rms_mm = n > 0 ? std::sqrt(f.rms_mm / n) : 0.0;
    return f;
  };
  out.before = figures(false, false);
  out.holdout_before = figures(true, false);

  // The solve.
  const auto solve = [&](ceres::LossFunction* loss_for_rows) {
    ceres::Problem::Options po;
    po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    for (Block& blk : blocks) {
      for (std::size_t i : blk.rows) {
        if (held_out[i] || outlier[i]) continue;
        problem.AddResidualBlock(new PoseCost(*blk.design, all[i], weight(all[i])), loss_for_rows, blk.q.data(), frame.data());
      }
    }
    for (int b = 0; b < nb; ++b) {
      std::vector<int> constant;
      for (int i = 0; i < kMechanismParameters; ++i) {
        if (!fitted[static_cast<std::size_t>(b * kMechanismParameters + i)]) constant.push_back(i);
      }
      double* data = blocks[static_cast<std::size_t>(b)].q.data();
      if (static_cast<int>(constant.size()) == kMechanismParameters) problem.SetParameterBlockConstant(data);
      else if (!constant.empty()) problem.SetManifold(data, new ceres::SubsetManifold(kMechanismParameters, constant));
    }
    std::vector<int> fconst;
    for (int i = 0; i < kFrameParameters; ++i) {
      if (!fitted[static_cast<std::size_t>(frame0 + i)]) fconst.push_back(i);
    }
    if (static_cast<int>(fconst.size()) == kFrameParameters) problem.SetParameterBlockConstant(frame.data());
    else if (!fconst.empty()) problem.SetManifold(frame.data(), new ceres::SubsetManifold(kFrameParameters, fconst));
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::DENSE_QR;
    so.max_num_iterations = opt.max_iterations;
    so.function_tolerance = 1e-12;
    so.parameter_tolerance = 1e-12;
    so.gradient_tolerance = 1e-14;
    so.num_threads = 1;
    so.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    out.iterations += static_cast<int>(summary.iterations.size());
    out.converged = summary.termination_type == ceres::CONVERGENCE;
    out.termination = ceres::TerminationTypeToString(summary.termination_type);
    out.solver_report = summary.BriefReport();
  };
  solve(nullptr);
  if (opt.loss != Loss::none) {
    // The loss's scale in measurement sigmas: given, or robustly from the first fit (1.4826 MAD).
    double s = 0.0;
    if (all_sigma) {
      s = 1.0;  // rows are already in sigmas
    } else {
      Eigen::MatrixXd Jr;
      Eigen::VectorXd r;
      stacked(Jr, r);
      std::vector<double> a(r.data(), r.data() + r.size());
      for (double& v : a) v = std::abs(v);
      std::nth_element(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(a.size() / 2), a.end());
      s = std::max(1.4826 * a[a.size() / 2], 1e-9);
    }
    const double c = opt.loss_scale * s;
    std::unique_ptr<ceres::LossFunction> loss;
    if (opt.loss == Loss::huber) loss = std::make_unique<ceres::HuberLoss>(c);
    else loss = std::make_unique<ceres::CauchyLoss>(c);
    solve(loss.get());
    // Honest sigmas (docs/calibrate.md "Model"): the robust estimate names the outliers, and
    // the estimate and covariance are those of least squares over the other poses. A covariance
    // taken over every residual, blunders included, overstates the sigmas many times.
    fit_rows -= flag_outliers(blocks, all, held_out, frame, weight, all_sigma, outlier, out.outliers);
    if (2 * fit_rows < unknowns) {
      throw InputError(origin + ": " + std::to_string(out.outliers.size()) + " outliers leave " + std::to_string(fit_rows) +
                       " poses for " + std::to_string(unknowns) + " unknowns");
    }
    if (!out.outliers.empty()) solve(nullptr);
  }

  // Identification figures and covariance at the estimate.
  Eigen::VectorXd r;
  stacked(J, r);
  const int nk = static_cast<int>(kept.size());
  Eigen::MatrixXd Js(J.rows(), nk);
  for (int c = 0; c < nk; ++c) Js.col(c) = J.col(kept[static_cast<std::size_t>(c)]) * scale[static_cast<std::size_t>(kept[static_cast<std::size_t>(c)])];
  out.poses = fit_rows;
  out.holdout_poses = opt.holdout;
  Eigen::MatrixXd cov_scaled = Eigen::MatrixXd::Zero(nk, nk);
  if (nk > 0) {
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(Js, Eigen::ComputeThinV);
    const Eigen::VectorXd sv = svd.singularValues();
    out.singular_values.assign(sv.data(), sv.data() + sv.size());
    out.condition_number = sv[nk - 1] > 0.0 ? sv[0] / sv[nk - 1] : std::numeric_limits<double>::infinity();
    double log_sum = 0.0;
    for (int i = 0; i < nk; ++i) log_sum += std::log(std::max(sv[i], 1e-300));
    out.observability_index = std::exp(log_sum / nk) / std::sqrt(static_cast<double>(fit_rows));
    Eigen::VectorXd inv2(nk);
    for (int i = 0; i < nk; ++i) inv2[i] = sv[i] > 0.0 ? 1.0 / (sv[i] * sv[i]) : 0.0;
    cov_scaled = svd.matrixV() * inv2.asDiagonal() * svd.matrixV().transpose();
  }
  const int dof = 2 * fit_rows - nk;
  double s2 = 1.0;
  if (!all_sigma) {
    s2 = dof > 0 ? r.squaredNorm() / dof : 0.0;
    out.sigma_estimated = true;
    out.sigma_mm = std::sqrt(s2);
  } else {
    out.sigma_mm = opt.sigma_mm ? *opt.sigma_mm : 0.0;
  }
  Eigen::MatrixXd cov(nk, nk);
  for (int a = 0; a < nk; ++a) {
    for (int b = 0; b < nk; ++b) {
      cov(a, b) = s2 * cov_scaled(a, b) * scale[static_cast<std::size_t>(kept[static_cast<std::size_t>(a)])] *
                  scale[static_cast<std::size_t>(kept[static_cast<std::size_t>(b)])];
    }
  }
  std::vector<int> pos(static_cast<std::size_t>(np), -1);
  for (int c = 0; c < nk; ++c) pos[static_cast<std::size_t>(kept[static_cast<std::size_t>(c)])] = c;
  const auto var = [&](int a, int b) {
    const int i = pos[static_cast<std::size_t>(a)], j = pos[static_cast<std::size_t>(b)];
    return (i < 0 || j < 0) ? 0.0 : cov(i, j);
  };

  out.after = figures(false, true);
  out.holdout_after = figures(true, true);

  // Parameters, in file units and keys.
  for (int b = 0; b < nb; ++b) {
    const Block& blk = blocks[static_cast<std::size_t>(b)];
    const int o = b * kMechanismParameters;
    const MechanismVector q0 = mechanism_vector(*blk.design, 0, 0, 0, 0);
    const Potentiometer p1 = controller ? controller->joint(station, blk.name, 1).potentiometer : Potentiometer{};
    const Potentiometer p2 = controller ? controller->joint(station, blk.name, 2).potentiometer : Potentiometer{};
    const MechanismVector prior = mechanism_vector(*blk.design, p1.volts_at_zero, p1.rad_per_volt, p2.volts_at_zero, p2.rad_per_volt);
    (void)q0;
    const std::string mk = "stations." + station + ".mechanisms." + blk.name + ".";
    const std::string ck = "controller.stations." + station + "." + blk.name + ".";
    const auto add = [&](int i, std::string key, double design_value, double value, double variance, bool id, bool req) {
      Parameter p;
      p.mechanism = blk.name;
      p.name = mnames[static_cast<std::size_t>(i)];
      p.key = std::move(key);
      p.unit = unit_of(i);
      p.design = design_value;
      p.value = value;
      p.sigma = std::sqrt(std::max(variance, 0.0));
      p.requested = req;
      p.identified = id;
      if (!id) p.note = req ? "not identifiable from these poses: held at the design value" : "not requested: held at the design value";
      out.parameters.push_back(std::move(p));
    };
    const auto is = [&](int i) { return fitted[static_cast<std::size_t>(o + i)]; };
    const auto rq = [&](int i) { return static_cast<bool>(requested[static_cast<std::size_t>(o + i)]); };
    for (int i = 0; i < 4; ++i) add(i, mk + "links[" + std::to_string(i) + "]", prior[i], blk.q[i], var(o + i, o + i), is(i), rq(i));
    add(4, mk + "bases[0][0]", prior[4], blk.q[4], var(o + 4, o + 4), is(4), rq(4));
    add(5, mk + "bases[0][1]", prior[5], blk.q[5], var(o + 5, o + 5), is(5), rq(5));
    // O2 = O1 + d: its variance carries O1's.
    add(6, mk + "bases[1][0]", prior[4] + prior[6], blk.q[4] + blk.q[6], var(o + 4, o + 4) + var(o + 6, o + 6) + 2 * var(o + 4, o + 6), is(6), rq(6));
    add(7, mk + "bases[1][1]", prior[5] + prior[7], blk.q[5] + blk.q[7], var(o + 5, o + 5) + var(o + 7, o + 7) + 2 * var(o + 5, o + 7), is(7), rq(7));
    add(8, ck + "theta1.potentiometer.volts_at_zero", prior[8], blk.q[8], var(o + 8, o + 8), is(8), rq(8));
    add(9, ck + "theta1.potentiometer.rad_per_volt", prior[9], blk.q[9], var(o + 9, o + 9), is(9), rq(9));
    add(10, ck + "theta2.potentiometer.volts_at_zero", prior[10], blk.q[10], var(o + 10, o + 10), is(10), rq(10));
    add(11, ck + "theta2.potentiometer.rad_per_volt", prior[11], blk.q[11], var(o + 11, o + 11), is(11), rq(11));
  }
  // The covariance of the patched keys (file units): bases[1] = O1 + (O2 - O1) carries O1's part.
  {
    std::vector<std::vector<int>> combos;
    for (int b = 0; b < nb; ++b) {
      const int o = b * kMechanismParameters;
      for (const Parameter& p : out.parameters) {
        if (p.mechanism != blocks[static_cast<std::size_t>(b)].name || !p.identified) continue;
        const auto i = static_cast<int>(std::find(mnames.begin(), mnames.end(), p.name) - mnames.begin());
        combos.push_back(i == 6 ? std::vector<int>{o + 4, o + 6} : i == 7 ? std::vector<int>{o + 5, o + 7} : std::vector<int>{o + i});
        out.key_covariance_keys.push_back(p.key);
      }
    }
    const auto nkey = static_cast<Eigen::Index>(combos.size());
    out.key_covariance = Eigen::MatrixXd::Zero(nkey, nkey);
    for (Eigen::Index a = 0; a < nkey; ++a) {
      for (Eigen::Index c = 0; c < nkey; ++c) {
        for (int x : combos[static_cast<std::size_t>(a)]) {
          for (int y : combos[static_cast<std::size_t>(c)]) out.key_covariance(a, c) += var(x, y);
        }
      }
    }
  }
  static const std::array<const char*, 3> fkeys{"frame.rotation_deg", "frame.x_mm", "frame.y_mm"};
  if (opt.fit_frame) {
    for (int i = 0; i < kFrameParameters; ++i) {
      Parameter p;
      p.name = fnames[static_cast<std::size_t>(i)];
      p.key = fkeys[static_cast<std::size_t>(i)];
      const double f = i == 0 ? 1.0 / kDeg : 1.0;
      p.unit = i == 0 ? "deg" : "mm";
      p.design = frame_prior[i] * f;
      p.value = frame[i] * f;
      p.sigma = std::sqrt(std::max(var(frame0 + i, frame0 + i), 0.0)) * f;
      p.requested = requested[static_cast<std::size_t>(frame0 + i)];
      p.identified = fitted[static_cast<std::size_t>(frame0 + i)];
      if (!p.identified) p.note = p.requested ? "not identifiable from these poses: held at 0" : "not requested: held at 0";
      out.parameters.push_back(std::move(p));
    }
  }
  out.covariance = cov;
  for (int k : kept) out.covariance_names.push_back(full_name(k));

  // The quality gate (fivebar/provenance/gate.hpp): the residual test is chi-square when the rows
  // state their sigma, else the largest residual against the fit's own scale.
  gate::GateInput gi;
  gi.fit = "fivebar calibrate";
  gi.solver = {out.converged, out.termination, out.iterations};
  // The priors here are the a-priori scales of the identifiability analysis (0.1 mm, ...), not
  // measured tolerances: a value is refused when its sigma exceeds three of them (docs/calibrate.md
  // "The quality gate"; 60 random poses at 0.02 mm leave a link's sigma up to 1.5 scales, poses on
  // a line hundreds).
  gi.max_sigma_to_prior = 3.0;
  if (all_sigma) {
    gi.tests.push_back(gate::chi_square_test(r.squaredNorm(), dof));
  } else {
    std::vector<double> z(r.data(), r.data() + r.size());
    for (double& v : z) v = s2 > 0.0 ? v / std::sqrt(s2) : 0.0;
    gi.tests.push_back(gate::largest_residual_test(z));
  }
  for (const Parameter& p : out.parameters) {
    if (!p.identified || p.mechanism.empty()) continue;
    const auto b = std::find_if(blocks.begin(), blocks.end(), [&](const Block& x) { return x.name == p.mechanism; });
    const Potentiometer p1 = controller ? controller->joint(station, b->name, 1).potentiometer : Potentiometer{};
    const Potentiometer p2 = controller ? controller->joint(station, b->name, 2).potentiometer : Potentiometer{};
    const MechanismVector prior = mechanism_vector(*b->design, p1.volts_at_zero, p1.rad_per_volt, p2.volts_at_zero, p2.rad_per_volt);
    const auto i = static_cast<int>(std::find(mnames.begin(), mnames.end(), p.name) - mnames.begin());
    gi.parameters.push_back({p.key, p.mechanism + "." + p.name, p.unit, p.value, p.sigma, prior_sigma(i, prior), true, ""});
  }
  out.gate = gate::evaluate(gi);
  return out;
}

Design patched_design(const Design& design, const CalibrationResult& result) {
  Design d = design;
  Station* st = nullptr;
  for (Station& s : d.stations) {
    if (s.name == result.station) st = &s;
  }
  if (st == nullptr) throw InputError("the design has no station '" + result.station + "'");
  ControllerSettings* c = d.get<ControllerSettings>();
  for (const Parameter& p : result.parameters) {
    if (!p.identified || p.mechanism.empty()) continue;
    Mechanism& m = p.mechanism == "lower" ? *st->lower : *st->upper;
    const auto& names = mechanism_parameter_names();
    const auto i = static_cast<int>(std::find(names.begin(), names.end(), p.name) - names.begin());
    if (i < 4) m.L[static_cast<std::size_t>(i)] = p.value;
    else if (i == 4) m.O1.x() = p.value;
    else if (i == 5) m.O1.y() = p.value;
    else if (i == 6) m.O2.x() = p.value;
    else if (i == 7) m.O2.y() = p.value;
    else {
      if (c == nullptr) c = &d.set(ControllerSettings{});
      const int joint = i < 10 ? 1 : 2;
      ControlOverride* o = nullptr;
      for (ControlOverride& e : c->overrides) {
        if (e.station == result.station && e.mechanism == p.mechanism && e.joint == joint) o = &e;
      }
      if (o == nullptr) {
        ControlOverride e;
        e.station = result.station;
        e.mechanism = p.mechanism;
        e.joint = joint;
        c->overrides.push_back(e);
        o = &c->overrides.back();
      }
      if (i % 2 == 0) o->volts_at_zero = p.value;
      else o->rad_per_volt = p.value;
    }
  }
  // O1 held while O2 - O1 was fitted: bases[1] already carries the fitted difference (fit.cpp adds it).
  for (const Parameter& p : result.parameters) {
    if (p.mechanism.empty() || p.identified) continue;
    Mechanism& m = p.mechanism == "lower" ? *st->lower : *st->upper;
    if (p.name == "O2x" || p.name == "O2y") {
      // O2 = O1 + d with d at its prior: keep the design's difference from the (possibly moved) O1.
      const Mechanism* orig = design.station(result.station)->mechanism(p.mechanism);
      const Vec2 dprior = orig->O2 - orig->O1;
      if (p.name == "O2x") m.O2.x() = m.O1.x() + dprior.x();
      else m.O2.y() = m.O1.y() + dprior.y();
    }
  }
  d.validate();
  return d;
}

}  // namespace fivebar::calibrate
