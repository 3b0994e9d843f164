// `fivebar report stability`: a catalogue of extreme cases run through FK, IK, the Jacobian and
// LCI, the workspace area and coverage, each compared with the __float128 reference
// (report/quad.hpp) against the error its conditioning allows.
//
// Error bounds (S = the largest coordinate or length the computation handles, L = the largest
// link, eps = 2^-52):
//
//  * Circle centres, radii and distances. A_i = O_i + L_i (cos, sin) costs <= 3 roundings of
//    quantities <= S per coordinate, d^2 = |c2 - c1|^2 and the chord ratios t = a/d =
//    1/2 + (r1 - r2)(r1 + r2)/(2 d^2) and h/d (detail::chord) <= 5 more relative roundings of
//    quantities <= 3S (|a| <= r when the circles meet). Every circle of an intersection is
//    therefore displaced by at most e = 16 eps S along its normal.
//  * Intersection point (FK's tactor, IK's elbows). Two curves crossing at angle gamma, displaced
//    by e1, e2 along their normals, cross within (e1 + e2)/|sin gamma| of the old point (first
//    order). Near tangency that overestimates: h^2 = (d^2 - (r1 - r2)^2)((r1 + r2)^2 - d^2) / (4 d^2)
//    moves by <= 2 r (2e) (r the smaller radius) when d moves by 2e, so
//    h moves by <= 2 sqrt(2 r e), and the centre line (d apart) turns by <= 2e/d, moving the point
//    by <= 2 e L / d. So |dP| <= 2e + min(2e/s, 2 sqrt(2 L e) + 2 e L / d), and never more than
//    the circle's diameter 2L (+2e); s is the reference |sin| of the crossing angle: the tactor
//    angle (type II) for FK, the elbow angle of leg i (type I) for IK, whose error is reported as
//    L_i |d theta_i| (atan2 adds < 1 ulp, in 2e).
//  * Jacobian J = B^-1 C (B rows (P - A_i)^T, C = diag(cross(A_i - O_i, P - A_i))). From
//    (B + dB)^-1 (C + dC) - J = (B + dB)^-1 (dC - dB J), |(B + dB)^-1| <= |B^-1| / (1 - |B^-1| |dB|)
//    (Neumann series) and |C| <= |B| |J|:
//      |dJ| / |J| <= cond(B) (|dB|/|B| + |dC|/|C|) / (1 - cond(B) |dB|/|B|),
//    |dB| <= sqrt(2) (eA + eP), |B| >= max(L3, L4), |dc_i| <= (L_i + L_{i+2})(eA + eP) + 2 eps L_i L_{i+2},
//    eA, eP the position bounds of the elbows and tactor of the pose the Jacobian is taken at,
//    cond(B) from the reference; plus 4 eps cond(B) for the rounding of M and det B; sqrt(2) for
//    comparing Frobenius norms. Valid while cond(B) |dB| / |B| < 1/2; beyond that B + dB may be
//    singular and J is not determined at all (no bound; the case is flagged ill-conditioned).
//  * LCI = sigma_min / sigma_max: singular values move by at most |dJ|_2 (Weyl), so
//    |dLCI| <= 2 r / (1 - r) with r the Jacobian's relative bound (1 when r >= 1/2).
//  * Exact-region area (Green's theorem over the boundary pieces): every piece's term is computed
//    from vertices rounded to double (<= eps S each) and an arc angle from atan2 (<= 2 eps S / r):
//    <= 8 eps S^2 per piece.
//  * Closed-form annuli area: inclusion-exclusion of four lens areas, each a sum of terms no larger
//    than pi a^2 and pi b^2; a backward-stable evaluation errs by a few eps per term:
//    |dA| <= 8 eps pi sum(a_j^2 + b_j^2). (The problem's own sensitivity to the rounding of the
//    radii, eps sum |dA/dr| r <= eps 2 pi sum r^2, is of the same size.)
//  * Coverage margin: extremes of |q(t) - O| over the ellipse, a value of a Lipschitz-1 function of
//    the inputs at a flat extremum: each evaluation carries <= 8 roundings of size <= S and the
//    extremum's location error enters at second order: |d margin| <= 32 eps S.
//
// A case is ill-conditioned when its bound exceeds 1e-6 of the natural size (S for positions, 1
// for relative and LCI errors, the area for areas): double precision cannot give more digits.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "fivebar/format.hpp"
#include "fivebar/coverage/coverage.hpp"
#include "fivebar/error.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/report.hpp"
#include "fivebar/numerics.hpp"
#include "fivebar/workspace/region.hpp"
#include "report/format.hpp"
#include "report/quad.hpp"

namespace fivebar {

namespace {

using quadref::QMechanism;
using quadref::QPose;
using quadref::quad;
using quadref::QVec;
using report_fmt::sci;

constexpr double kEps = tol::kEps;
constexpr double kPi = std::numbers::pi;
constexpr double kInputRoundings = 16.0;
constexpr double kIllConditioned = 1e-6;
/// coverage() re-decides |margin| <= 1e-9 L exactly with a circumscribed 1024-gon (coverage.hpp):
/// an ellipse that close to tangency may be reported outside although it touches from inside.

const std::vector<double> kDistances{1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9,
                                     1e-10, 1e-11, 1e-12, 1e-13, 1e-14, 1e-15, 1e-16, 0.0};

// --- helpers -------------------------------------------------------------------------------------

bool finite_pose(const Pose& p) {
  bool ok = std::isfinite(p.theta1) && std::isfinite(p.theta2) && p.A1.allFinite() && p.A2.allFinite() &&
            p.P.allFinite() && p.J.allFinite() && std::isfinite(p.lci) && std::isfinite(p.force_capability) &&
            std::isfinite(p.type2_sin) && std::isfinite(p.type1_distance_mm) && std::isfinite(p.closure_error_mm);
  for (double v : p.transmission) ok = ok && std::isfinite(v);
  for (double v : p.type1_sin) ok = ok && std::isfinite(v);
  return ok;
}

double coord_scale(const Mechanism& m, std::initializer_list<Vec2> extra = {}) {
  double s = m.length_scale();
  s = std::max(s, m.O1.norm() + m.L[0] + m.L[2]);
  s = std::max(s, m.O2.norm() + m.L[1] + m.L[3]);
  for (const Vec2& v : extra) s = std::max(s, v.norm());
  return s;
}
double max_link(const Mechanism& m) { return *std::max_element(m.L.begin(), m.L.end()); }

/// Position bound of an intersection point crossing at |sin| = s, circle centres d apart (see the
/// top of the file); never more than the circle's diameter.
double position_bound(double e, double s, double L, double d) {
  const double first = s > 0.0 ? 2.0 * e / s : std::numeric_limits<double>::infinity();
  const double turn = d > 0.0 ? 2.0 * e * L / d : std::numeric_limits<double>::infinity();
  return std::min(2.0 * e + std::min(first, 2.0 * std::sqrt(2.0 * L * e) + turn), 2.0 * L + 2.0 * e);
}

std::string num(double v) { return v == 0.0 ? "0" : format::sci(v, 0); }

/// Which of (reachable, type I, type II) the reference allows: 0 false, 1 true, 2 either.
struct Expect {
  int reach = 1, t1 = 0, t2 = 0;
};
int decide(double value, double threshold, double band) {  // value < threshold means "true"
  if (value < threshold - band) return 1;
  if (value > threshold + band) return 0;
  return 2;
}
std::vector<Status> allowed(const Expect& e) {
  std::vector<Status> out;
  auto vals = [](int v) { return v == 2 ? std::vector<bool>{false, true} : std::vector<bool>{v == 1}; };
  for (bool r : vals(e.reach))
    for (bool a : vals(e.t1))
      for (bool b : vals(e.t2)) {
        const Status s = !r ? Status::unreachable : a ? Status::singular_type1 : b ? Status::singular_type2 : Status::ok;
        if (std::find(out.begin(), out.end(), s) == out.end()) out.push_back(s);
      }
  return out;
}
std::string join(const std::vector<Status>& v) {
  std::string s;
  for (Status x : v) s += (s.empty() ? "" : "|") + std::string(to_string(x));
  return s;
}
bool contains(const std::vector<Status>& v, Status s) { return std::find(v.begin(), v.end(), s) != v.end(); }

/// Relative Jacobian bound (top of the file); std::nullopt when the perturbation of B may make
/// it singular (cond(B) |dB| / |B| >= 1/2): the Jacobian is then not determined at all.
std::optional<double> jacobian_bound(const Mechanism& m, const QPose& ref, double eA, double eP) {
  if (ref.cond_B <= 0) return std::nullopt;
  const double e = eA + eP;
  const double dB = std::sqrt(2.0) * e / std::max(m.L[2], m.L[3]);
  const QVec e1 = ref.A1 - quadref::q(m.O1), e2 = ref.A2 - quadref::q(m.O2);
  const double c1 = std::fabs(double(quadref::cross(e1, ref.P - ref.A1)));
  const double c2 = std::fabs(double(quadref::cross(e2, ref.P - ref.A2)));
  const double cmax = std::max(c1, c2);
  if (!(cmax > 0.0)) return std::nullopt;
  const double dC = std::max((m.L[0] + m.L[2]) * e + 2 * kEps * m.L[0] * m.L[2],
                             (m.L[1] + m.L[3]) * e + 2 * kEps * m.L[1] * m.L[3]);
  const double kB = double(ref.cond_B);
  if (kB * dB >= 0.5) return std::nullopt;
  // (B + dB)^-1 (C + dC) - B^-1 C = (B + dB)^-1 (dC - dB J), |(B + dB)^-1| <= |B^-1| / (1 - |B^-1| |dB|).
  return std::sqrt(2.0) * (kB * (dB + dC / cmax) / (1.0 - kB * dB) + 4 * kEps * kB);
}
double lci_bound(const std::optional<double>& rel_j) {
  return rel_j && *rel_j < 0.5 ? std::min(1.0, 2.0 * *rel_j / (1.0 - *rel_j)) : 1.0;
}

double frobenius_rel(const Eigen::Matrix2d& J, const QPose& ref) {
  quad num = 0, den = 0;
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 2; ++c) {
      const quad d = quad(J(r, c)) - ref.J[r][c];
      num += d * d;
      den += ref.J[r][c] * ref.J[r][c];
    }
  return den > 0 ? double(sqrtq(num / den)) : 0.0;
}

class Catalogue {
 public:
  Catalogue(std::string label, std::vector<StabilityCase>& out) : label_(std::move(label)), out_(out) {}

  StabilityCase& add(const std::string& group, const std::string& name, const std::string& op, double parameter) {
    StabilityCase c;
    c.mechanism = label_;
    c.group = group;
    c.name = name;
    c.operation = op;
    c.parameter = parameter;
    out_.push_back(std::move(c));
    return out_.back();
  }

  /// Finishes a case: passed from finiteness, status and error <= bound; ill-conditioning from
  /// the bound against `natural` (the quantity's natural size).
  static void judge(StabilityCase& c, bool status_ok, double natural, const std::string& why_ill) {
    const bool within = !c.error || !c.bound || *c.error <= *c.bound;
    if (c.error && !std::isfinite(*c.error)) c.finite = false;
    c.passed = c.finite && status_ok && within;
    c.ill_conditioned = c.bound && *c.bound > kIllConditioned * natural;
    std::string text;
    if (!c.finite) text += "non-finite result; ";
    if (!status_ok && c.expected.find(c.status) == std::string::npos)
      text += "status " + c.status + " not in " + c.expected + "; ";
    if (!within) text += "error " + sci(*c.error) + " exceeds the bound " + sci(*c.bound) + "; ";
    if (c.ill_conditioned) text += why_ill;
    if (!c.explanation.empty() && !text.empty()) text += "; ";
    c.explanation = text + c.explanation;
  }

  // --- FK ----------------------------------------------------------------------------------------
  void fk_case(const Mechanism& m, double t1, double t2, int side, const std::string& group, const std::string& name,
               double parameter, bool with_jacobian) {
    const Pose pose = fk(m, t1, t2, side > 0 ? AssemblyMode::Plus : AssemblyMode::Minus);
    const QMechanism qm(m);
    const QPose ref = quadref::fk(qm, t1, t2, side);
    const double S = coord_scale(m), e = kInputRoundings * kEps * S, L = max_link(m);
    const double s2 = double(ref.type2_sin);
    const double eP = position_bound(e, s2, L, double(quadref::norm(ref.A2 - ref.A1))), eA = 2 * e;
    Expect ex;
    const double g = double(quadref::fk_gap(qm, t1, t2));
    ex.reach = g < -2 * e ? 1 : g > 2 * e ? 0 : 2;
    if (ref.reachable) {
      const double band1 = (eP + 2 * e) / std::min({m.L[0], m.L[1], m.L[2], m.L[3]});
      const double s1 = double(std::min(ref.type1_sin[0], ref.type1_sin[1]));
      ex.t1 = decide(s1, tol::kSingularSin, band1);
      ex.t2 = ref.continuum ? 1 : decide(s2, tol::kSingularSin, (eP + 2 * e) / std::min(m.L[2], m.L[3]));
      if (ref.continuum) ex.t1 = 2;
    }
    const auto ok_statuses = allowed(ex);
    StabilityCase& c = add(group, name, "fk", parameter);
    c.status = std::string(to_string(pose.status));
    c.expected = join(ok_statuses);
    c.unit = "mm";
    c.conditioning = s2;
    c.finite = finite_pose(pose);
    if (ref.reachable && pose.status != Status::unreachable) {
      if (ref.continuum) {
        // Every point of the circle is a solution: check that the returned one closes the loop.
        const quad r1 = quadref::norm(quadref::q(pose.P) - ref.A1) - quad(m.L[2]);
        const quad r2 = quadref::norm(quadref::q(pose.P) - ref.A2) - quad(m.L[3]);
        c.error = double(std::max(quadref::qabs(r1), quadref::qabs(r2)));
        c.bound = 4 * e;
        c.explanation = "coincident elbows with L3 = L4: a continuum of solutions; checks the loop closure";
      } else {
        c.error = double(hypotq(quad(pose.P.x()) - ref.P.x, quad(pose.P.y()) - ref.P.y));
        c.bound = eP;
      }
    }
    judge(c, contains(ok_statuses, pose.status), S,
          "tactor angle |sin| = " + sci(s2) + ": P is determined only to " + sci(eP) +
              " mm in double (rounding amplified by 1/|sin|)");
    if (with_jacobian && ref.reachable && !ref.continuum && pose.status != Status::unreachable)
      jacobian_cases(m, pose, ref, eA, eP, group, name, parameter, S);
  }

  // --- IK ----------------------------------------------------------------------------------------
  void ik_case(const Mechanism& m, const Vec2& P, const std::string& group, const std::string& name, double parameter,
               bool with_jacobian) {
    const Pose pose = ik(m, P);
    const QMechanism qm(m);
    const QPose ref = quadref::ik(qm, quadref::q(P), m.working_mode.sign1, m.working_mode.sign2);
    const double S = coord_scale(m, {P}), e = kInputRoundings * kEps * S, L = max_link(m);
    const std::array<double, 2> s{double(ref.type1_sin[0]), double(ref.type1_sin[1])};
    const std::array<double, 2> bounds{
        position_bound(e, s[0], L, double(quadref::norm(quadref::q(P) - quadref::q(m.O1)))),
        position_bound(e, s[1], L, double(quadref::norm(quadref::q(P) - quadref::q(m.O2))))};
    Expect ex;
    const double g = double(quadref::ik_gap(qm, quadref::q(P)));
    ex.reach = g < -2 * e ? 1 : g > 2 * e ? 0 : 2;
    if (ref.reachable) {
      const int a = decide(s[0], tol::kSingularSin, (bounds[0] + 2 * e) / std::min(m.L[0], m.L[2]));
      const int b = decide(s[1], tol::kSingularSin, (bounds[1] + 2 * e) / std::min(m.L[1], m.L[3]));
      ex.t1 = (a == 1 || b == 1) ? 1 : (a == 2 || b == 2) ? 2 : 0;
      ex.t2 = decide(double(ref.type2_sin), tol::kSingularSin,
                     (std::max(bounds[0], bounds[1]) + 2 * e) / std::min(m.L[2], m.L[3]));
      if (ref.continuum) ex.t1 = 1;
    }
    const auto ok_statuses = allowed(ex);
    StabilityCase& c = add(group, name, "ik", parameter);
    c.status = std::string(to_string(pose.status));
    c.expected = join(ok_statuses);
    c.unit = "mm";
    c.conditioning = std::min(s[0], s[1]);
    c.finite = finite_pose(pose);
    bool within_all = true;
    if (ref.reachable && pose.status != Status::unreachable) {
      if (ref.continuum) {
        c.error = pose.closure_error_mm;
        c.bound = 4 * e;
        c.explanation = "P on a base joint with L_i = L_{i+2}: any angle of that leg closes the loop; checks the closure";
      } else {
        // Report the leg with the larger error-to-bound ratio; every leg must be within its bound.
        double worst = -1.0;
        for (int i = 0; i < 2; ++i) {
          const quad d = remainderq(quad(i == 0 ? pose.theta1 : pose.theta2) - (i == 0 ? ref.theta1 : ref.theta2),
                                    2 * quadref::kQuadPi);
          const double err = double(quadref::qabs(d) * quad(m.L[i]));
          within_all = within_all && err <= bounds[i];
          if (err / bounds[i] > worst) {
            worst = err / bounds[i];
            c.error = err;
            c.bound = bounds[i];
          }
        }
      }
    }
    if (!within_all && c.error && c.bound && *c.error <= *c.bound) c.explanation = "the other leg exceeds its bound";
    judge(c, contains(ok_statuses, pose.status) && within_all, S,
          "elbow |sin| = " + sci(c.conditioning) + ": the angles are determined only to " +
              sci(std::max(bounds[0], bounds[1])) + " mm at the elbow in double");
    if (with_jacobian && ref.reachable && !ref.continuum && pose.status != Status::unreachable)
      jacobian_cases(m, pose, ref, std::max(bounds[0], bounds[1]), 0.0, group, name, parameter, S);
  }

  void jacobian_cases(const Mechanism& m, const Pose& pose, const QPose& ref, double eA, double eP,
                      const std::string& group, const std::string& name, double parameter, double S) {
    (void)S;
    const std::optional<double> rel = jacobian_bound(m, ref, eA, eP);
    if (ref.jacobian_valid && pose.jacobian_valid) {
      StabilityCase& c = add(group, name, "jacobian", parameter);
      c.status = "valid";
      c.expected = "valid";
      c.unit = "rel";
      c.conditioning = double(ref.lci);
      c.finite = pose.J.allFinite();
      c.error = frobenius_rel(pose.J, ref);
      c.bound = rel;
      const std::string cond = "cond(J) = " + sci(ref.lci > 0 ? double(1 / ref.lci) : 0.0) +
                               ", cond(B) = " + sci(double(ref.cond_B));
      if (rel) {
        judge(c, true, 1.0, cond + ": J is determined only to a relative " + sci(*rel));
      } else {
        judge(c, true, 1.0, "");
        c.ill_conditioned = true;
        c.explanation = cond + " with positions known only to " + sci(eA + eP) +
                        " mm: the perturbed B may be singular, J is not determined in double precision";
      }
    }
    StabilityCase& c = add(group, name, "lci", parameter);
    c.status = std::string(to_string(pose.status));
    c.expected = c.status;
    c.unit = "1";
    c.conditioning = double(ref.lci);
    c.finite = std::isfinite(pose.lci) && pose.lci >= 0.0 && pose.lci <= 1.0;
    c.error = std::fabs(pose.lci - double(ref.lci));
    c.bound = lci_bound(rel);
    judge(c, true, 1.0, "LCI determined only to " + sci(*c.bound) + " (absolute)");
  }

  // --- workspace ---------------------------------------------------------------------------------
  void area_cases(const Mechanism& m, const std::string& group, const std::string& name, double parameter) {
    const QMechanism qm(m);
    const quad qa = quadref::annuli_area(qm);
    const double S = coord_scale(m);
    {
      const Region region = reachable_region(m);
      std::size_t pieces = 0;
      for (const BoundaryLoop& l : region.loops()) pieces += l.pieces.size();
      StabilityCase& c = add(group, name, "area", parameter);
      c.status = region.empty() ? "empty" : std::to_string(region.components()) + " component(s)";
      c.expected = qa > 0 ? "non-empty" : "empty";
      c.unit = "mm2";
      c.conditioning = 1.0;
      c.finite = std::isfinite(region.area_mm2()) && std::isfinite(region.perimeter_mm());
      c.error = double(quadref::qabs(quad(region.area_mm2()) - qa));
      c.bound = 8.0 * kEps * S * S * double(std::max<std::size_t>(pieces, 1));
      const bool status_ok = (qa > quad(*c.bound)) ? !region.empty() : true;
      judge(c, status_ok, std::max(double(qa), 1e-300),
            "area " + sci(double(qa)) + " mm² is small against the " + sci(S * S) +
                " mm² its boundary terms are made of: relative accuracy " + sci(*c.bound / std::max(double(qa), 1e-300)));
    }
    {
      const double cf = annuli_intersection_area(m);
      StabilityCase& c = add(group, name, "closed-form area", parameter);
      c.status = "computed";
      c.expected = "computed";
      c.unit = "mm2";
      c.conditioning = 1.0;
      c.finite = std::isfinite(cf);
      c.error = double(quadref::qabs(quad(cf) - qa));
      c.bound = closed_form_bound(qm);
      judge(c, true, std::max(double(qa), 1e-300),
            "the area is small against the lens areas it is the difference of: relative accuracy " +
                sci(*c.bound / std::max(double(qa), 1e-300)));
    }
  }

  /// What a backward-stable inclusion-exclusion of the four lens areas allows: each lens is a sum
  /// of terms no larger than pi a^2 and pi b^2, evaluated with a few roundings each.
  static double closed_form_bound(const QMechanism& qm) {
    const quad R1 = qm.L[0] + qm.L[2], r1 = quadref::qabs(qm.L[0] - qm.L[2]);
    const quad R2 = qm.L[1] + qm.L[3], r2 = quadref::qabs(qm.L[1] - qm.L[3]);
    double total = 0.0;
    for (auto [a, b] : {std::pair{R1, R2}, std::pair{R1, r2}, std::pair{r1, R2}, std::pair{r1, r2}}) {
      total += 8 * kEps * kPi * double(a * a + b * b);
    }
    return total;
  }

  // --- coverage ----------------------------------------------------------------------------------
  void coverage_cases(const Mechanism& m, const Ellipse& e, const std::string& group, const std::string& name,
                      double parameter) {
    const CoverageResult r = coverage(m, e);
    const double qmargin = double(quadref::annuli_margin(QMechanism(m), e));
    const double S = coord_scale(m, {e.center + Vec2(e.axes.x(), e.axes.y())});
    const double bound = 32 * kEps * S;
    {
      StabilityCase& c = add(group, name, "margin", parameter);
      c.status = r.inside ? "inside" : "not inside";
      c.expected = "any";
      c.unit = "mm";
      c.conditioning = 1.0;
      c.finite = std::isfinite(r.margin_mm) && std::isfinite(r.min_lci) && std::isfinite(r.covered_fraction) &&
                 std::isfinite(r.min_force_capability) && r.worst_point.allFinite() && r.min_lci_point.allFinite();
      // Outside, coverage() measures the depth against the whole region, which the legs' annuli
      // margin (the reference) only bounds from above.
      c.error = qmargin >= 0 ? std::fabs(r.margin_mm - qmargin) : std::max(0.0, r.margin_mm - qmargin);
      c.bound = bound;
      judge(c, true, S, "");
    }
    {
      // The verdict: decided ones follow the sign of the reference margin; undecided only within
      // the certified error bound of tangency.
      const double band = r.margin_error_mm + bound;
      StabilityCase& c = add(group, name, "coverage verdict", parameter);
      c.status = !r.decided ? "undecided" : r.inside ? "inside" : "not inside";
      c.expected = qmargin < -band ? "not inside" : qmargin > band ? "inside" : "inside|not inside|undecided";
      c.unit = "mm";
      c.conditioning = 1.0;
      c.finite = std::isfinite(r.margin_mm) && std::isfinite(r.margin_error_mm);
      const bool ok = r.decided ? (r.inside == (qmargin > 0) || std::fabs(qmargin) <= bound) : std::fabs(qmargin) <= band;
      if (!r.decided) {
        c.explanation = "reference margin " + sci(qmargin) + " mm: within the certified bound " + sci(band) +
                        " mm of tangency the verdict is undecided";
      }
      judge(c, ok, S, "");
      if (!r.decided) c.ill_conditioned = true;
    }
  }

 private:
  std::string label_;
  std::vector<StabilityCase>& out_;
};

// --- constructions -------------------------------------------------------------------------------

/// A pose of m far from every singularity, found on a grid of joint angles (library FK).
struct Regular {
  bool found = false;
  double t1 = 0, t2 = 0;
  Vec2 P{0, 0};
  int side = 1;
  double quality = 0;
};
Regular regular_pose(const Mechanism& m) {
  Regular best;
  auto consider = [&](const Pose& p) {
    if (p.status != Status::ok || p.assembly == 0) return;
    const double q = std::min({p.type1_sin[0], p.type1_sin[1], p.type2_sin});
    if (q > best.quality) best = {true, p.theta1, p.theta2, p.P, p.assembly, q};
  };
  // Tactor points where both legs certainly reach: intersections of circles around O1 and O2
  // with radii inside each annulus (finds the tiny workspaces of extreme link ratios too).
  constexpr int N = 12;
  const double R1 = m.L[0] + m.L[2], r1 = std::fabs(m.L[0] - m.L[2]);
  const double R2 = m.L[1] + m.L[3], r2 = std::fabs(m.L[1] - m.L[3]);
  for (int i = 0; i < N; ++i) {
    for (int j = 0; j < N; ++j) {
      const double rho1 = r1 + (R1 - r1) * (i + 0.5) / N, rho2 = r2 + (R2 - r2) * (j + 0.5) / N;
      for (int side : {1, -1}) {
        const CircleIntersection x = intersect_circles(m.O1, rho1, m.O2, rho2, side);
        if (x.status == Status::unreachable) continue;
        consider(ik(m, x.point));
      }
    }
  }
  // Concentric legs (coincident bases) have no such intersections: scan the joint angles.
  if (!best.found) {
    constexpr int M = 48;
    for (int i = 0; i < M; ++i)
      for (int j = 0; j < M; ++j)
        for (AssemblyMode b : {AssemblyMode::Plus, AssemblyMode::Minus})
          consider(fk(m, -kPi + 2 * kPi * (i + 0.5) / M, -kPi + 2 * kPi * (j + 0.5) / M, b));
  }
  return best;
}

/// An ellipse around the regular pose's tactor, well inside the annuli (a quarter of the distance
/// to the nearest boundary circle).
Ellipse ellipse_near(const Mechanism& m, const Vec2& P) {
  double d = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 2; ++i) {
    const double D = (P - (i == 0 ? m.O1 : m.O2)).norm();
    d = std::min({d, m.L[i] + m.L[i + 2] - D, D - std::fabs(m.L[i] - m.L[i + 2])});
  }
  Ellipse e;
  e.center = P;
  e.axes = {0.5 * d, 0.4 * d};
  e.angle = 0.3;
  return e;
}

Mechanism without_limits(Mechanism m) {
  m.joint_limits.reset();
  return m;
}

/// Grid of the exact constructions: 2^-30 of the length scale's binade, so that sums and
/// products of a few of its multiples are exact doubles.
double dyadic_step(const Mechanism& m) { return std::ldexp(1.0, std::ilogb(m.length_scale()) - 30); }

/// m without joint limits, its lengths and base coordinates rounded to the dyadic grid (no change
/// for a design given in such numbers, e.g. the paper's): the singular points built from them
/// below are then exact.
Mechanism dyadic(const Mechanism& m0) {
  Mechanism m = without_limits(m0);
  const double q = dyadic_step(m);
  for (double& l : m.L) l = std::max(q, std::round(l / q) * q);
  m.O1 = (m.O1 / q).array().round().matrix() * q;
  m.O2 = (m.O2 / q).array().round().matrix() * q;
  return m;
}

Vec2 axis_dir(int k) { return k == 0 ? Vec2(1, 0) : k == 1 ? Vec2(0, 1) : k == 2 ? Vec2(-1, 0) : Vec2(0, -1); }

/// Smallest t in (0, hi] with pred(t), for a predicate that holds from some t* on (near 0):
/// steps down by 1e-3 until it fails, then bisects on a log scale. std::nullopt when pred(hi) fails.
template <class Pred>
std::optional<double> smallest_t(Pred&& pred, double hi) {
  double lo = 0.0;
  if (!pred(hi)) return std::nullopt;
  for (int it = 0; it < 400; ++it) {
    const double mid = lo > 0 ? std::sqrt(lo * hi) : hi * 1e-3;
    if (pred(mid)) {
      hi = mid;
    } else {
      lo = mid;
    }
    if (hi - lo <= 1e-17 * hi) break;
  }
  return hi;
}

/// Type I: leg 1 stretched (R = L1 + L3) or folded (r = |L1 - L3|) with the singular point on an
/// axis through O1, moved to the origin of the frame so that any distance to it is representable.
void type1_family(Catalogue& cat, const Mechanism& m0, bool stretched) {
  const Mechanism m = dyadic(m0);
  const double R = stretched ? m.L[0] + m.L[2] : std::fabs(m.L[0] - m.L[2]);
  const std::string kind = stretched ? "leg 1 stretched" : "leg 1 folded";
  if (!(R > 0.0)) return;  // L1 = L3: the "equal links" group covers the folded leg
  // Pick the axis direction where the rest of the mechanism is most regular at the singular point.
  int best = -1;
  double quality = 0.0;
  for (int k = 0; k < 4; ++k) {
    const Vec2 Pstar = m.O1 + R * axis_dir(k);
    const QPose ref = quadref::ik(QMechanism(m), quadref::q(Pstar), m.working_mode.sign1, m.working_mode.sign2);
    if (!ref.reachable || ref.continuum) continue;
    const double q = double(std::min(ref.type1_sin[1], ref.type2_sin));
    if (q > quality) {
      quality = q;
      best = k;
    }
  }
  if (best < 0 || quality < 1e-3) {
    StabilityCase& c = cat.add("type I distance", kind, "ik", 0.0);
    c.status = "not constructible";
    c.expected = "-";
    c.explanation = "no axis direction puts the singular point of leg 1 where leg 2 is regular";
    return;
  }
  const Vec2 u = axis_dir(best);
  Mechanism mf = m;
  mf.O1 = -R * u;
  mf.O2 = quadref::d(quadref::q(m.O2) - quadref::q(m.O1) - quad(R) * quadref::q(u));
  const double S = mf.length_scale();
  for (double delta : kDistances) {
    // Inside the annulus: towards O1 from the stretched circle, away from it for the folded one.
    const Vec2 P = (stretched ? -1.0 : 1.0) * delta * S * u;
    cat.ik_case(mf, P, "type I distance", kind + ", distance " + num(delta), delta, true);
  }
  // Ill-conditioned Jacobians: distances giving cond(J) = 1e2 ... 1e14 (bisection in quad).
  if (!stretched) return;
  for (int k = 2; k <= 14; k += 2) {
    const double target = std::pow(10.0, -k);
    auto lci_at = [&](double t) {
      const QPose ref = quadref::ik(QMechanism(mf), quadref::q(Vec2(-t * S * u)), mf.working_mode.sign1,
                                    mf.working_mode.sign2);
      return ref.reachable ? double(ref.lci) : 0.0;
    };
    // Distance / S up to 0.1 (the first row of the distance sweep): LCI grows with it.
    const auto t = smallest_t([&](double x) { return lci_at(x) >= target; }, 0.1);
    if (!t) continue;
    const Vec2 P = -*t * S * u;
    const QPose ref = quadref::ik(QMechanism(mf), quadref::q(P), mf.working_mode.sign1, mf.working_mode.sign2);
    const double cond = ref.lci > 0 ? double(1 / ref.lci) : 0.0;
    cat.ik_case(mf, P, "ill-conditioned Jacobian", "via type I, cond(J) = " + num(std::pow(10.0, k)), cond, true);
  }
}

/// Type II: distal links collinear at theta = (0, 0), exactly: bases placed so that
/// A2 - A1 = (3k, 4k) with 5k = L3 + L4 (stretched) or |L3 - L4| (folded), L4 adjusted by less
/// than a grid step so that 5k is on the dyadic grid. Distances by theta1 = eps.
void type2_family(Catalogue& cat, const Mechanism& m0, bool stretched) {
  const std::string kind = stretched ? "distal links stretched"
                                     : m0.L[2] == m0.L[3] ? "coincident elbows (L3 = L4)" : "distal links folded";
  Mechanism m = dyadic(m0);
  const double q = dyadic_step(m);
  const double D = stretched ? m.L[2] + m.L[3] : std::fabs(m.L[2] - m.L[3]);
  const double k = D / 5.0;  // exact when D is a multiple of 5 * 2^-20: make it one
  const double k_exact = std::round(k / q) * q;
  if (stretched) {
    m.L[3] = 5.0 * k_exact - m.L[2];
  } else if (m.L[2] != m.L[3]) {
    m.L[3] = m.L[2] - 5.0 * k_exact * (m.L[2] > m.L[3] ? 1.0 : -1.0);
  }
  if (!(m.L[3] > 0.0)) return;
  const Vec2 v(3.0 * k_exact * (stretched || m.L[2] > m.L[3] ? 1.0 : -1.0),
               4.0 * k_exact * (stretched || m.L[2] > m.L[3] ? 1.0 : -1.0));
  m.O1 = {-m.L[0], 0.0};            // A1 = (0, 0) at theta1 = 0
  m.O2 = {v.x() - m.L[1], v.y()};   // A2 = v at theta2 = 0
  const int side = 1;
  const QMechanism qm(m);
  const double S = m.length_scale();
  // Both motors turn by +-t, each in the direction that moves the configuration into the
  // reachable side (reaches the larger distances); t = 0 is the exact singularity.
  auto gap2 = [&](double t1, double t2) { return double(quadref::fk_gap(qm, t1, t2)); };
  double d1 = 1.0, d2 = 1.0;
  for (double a : {1.0, -1.0})
    for (double b : {1.0, -1.0})
      if (gap2(a * 1e-6, b * 1e-6) < gap2(d1 * 1e-6, d2 * 1e-6)) d1 = a, d2 = b;
  auto gap_at = [&](double t) { return gap2(d1 * t, d2 * t); };
  auto solve = [&](auto&& pred) { return smallest_t(pred, 1.0); };
  for (double delta : kDistances) {
    double t = 0.0;
    if (delta > 0.0) {
      const auto found = solve([&](double x) { return gap_at(x) < -delta * S; });
      if (!found) continue;
      t = *found;
    }
    cat.fk_case(m, d1 * t, d2 * t, side, "type II distance", kind + ", distance " + num(delta), delta, true);
  }
  if (!stretched) return;
  for (int e = 2; e <= 14; e += 2) {
    const double target = std::pow(10.0, -e);
    auto lci_at = [&](double t) {
      const QPose ref = quadref::fk(qm, d1 * t, d2 * t, side);
      return ref.reachable ? double(ref.lci) : 0.0;
    };
    const auto found = solve([&](double x) { return lci_at(x) >= target; });
    if (!found) continue;
    const QPose ref = quadref::fk(qm, d1 * *found, d2 * *found, side);
    cat.fk_case(m, d1 * *found, d2 * *found, side, "ill-conditioned Jacobian",
                "via type II, cond(J) = " + num(std::pow(10.0, e)), ref.lci > 0 ? double(1 / ref.lci) : 0.0, true);
  }
}

/// FK, IK, area and coverage of a derived mechanism at its most regular pose.
void derived_cases(Catalogue& cat, const Mechanism& m, const std::optional<Ellipse>& target, const std::string& group,
                   const std::string& name, double parameter) {
  const Regular r = regular_pose(m);
  if (r.found) {
    cat.fk_case(m, r.t1, r.t2, r.side, group, name, parameter, true);
    const QPose ref = quadref::fk(QMechanism(m), r.t1, r.t2, r.side);
    cat.ik_case(m, quadref::d(ref.P), group, name, parameter, false);
  }
  cat.area_cases(m, group, name, parameter);
  if (target) {
    cat.coverage_cases(m, *target, group, name, parameter);
  } else if (r.found) {
    cat.coverage_cases(m, ellipse_near(m, r.P), group, name, parameter);
  }
}

/// Ellipses tangent to a boundary circle of the annuli at an axis end (exact: angle 0, centre on
/// an axis through the base joint, the tangency point moved to the origin of the frame), then
/// moved in and out by delta * S.
bool tangent_placement(Catalogue& cat, const Mechanism& m, const Ellipse& target, bool outer) {
  double a = 0.5 * target.axes.x(), b = 0.5 * target.axes.y();
  for (int shrink = 0; shrink < 8; ++shrink, a *= 0.5, b *= 0.5) {
    for (int leg = 0; leg < 2; ++leg) {
      const Vec2 O = leg == 0 ? m.O1 : m.O2;
      const double rad = outer ? m.L[leg] + m.L[leg + 2] : std::fabs(m.L[leg] - m.L[leg + 2]);
      if (!(rad > 0.0)) continue;
      for (int k = 0; k < 4; ++k) {
        const Vec2 u = axis_dir(k);
        const double semi = k % 2 == 0 ? a : b, other = k % 2 == 0 ? b : a;
        if (outer && other * other > semi * rad) continue;  // the ellipse must bend more than the circle
        // Frame with the tangency point T at the origin.
        const Vec2 T = O + rad * u;
        Mechanism mf = m;
        mf.O1 = quadref::d(quadref::q(m.O1) - quadref::q(T));
        mf.O2 = quadref::d(quadref::q(m.O2) - quadref::q(T));
        Ellipse e;
        e.axes = {2 * a, 2 * b};
        e.angle = 0.0;
        e.center = (outer ? -semi : semi) * u;
        // Tangent (zero margin) while every other constraint is comfortably clear.
        const double q0 = double(quadref::annuli_margin(QMechanism(mf), e));
        if (std::fabs(q0) > 1e-12 * mf.length_scale()) continue;
        bool clear = true;
        for (int j = 0; j < 2 && clear; ++j) {
          const quadref::QExtremes ex = quadref::ellipse_extremes(e, quadref::q(j == 0 ? mf.O1 : mf.O2));
          const double Rj = mf.L[j] + mf.L[j + 2], rj = std::fabs(mf.L[j] - mf.L[j + 2]);
          const double m_out = Rj - double(ex.max_distance);
          const double m_in = rj > 0 ? (ex.inside ? -rj : double(ex.min_distance) - rj) : 1e300;
          if (!(j == leg && outer) && m_out < 1e-3 * mf.length_scale()) clear = false;
          if (!(j == leg && !outer) && m_in < 1e-3 * mf.length_scale()) clear = false;
        }
        if (!clear) continue;
        const std::string where = std::string(outer ? "outer" : "inner") + " circle of leg " + std::to_string(leg + 1);
        const double S = mf.length_scale();
        for (double delta : {1e-2, 1e-3, 1e-6, 1e-9, 1e-12, 1e-15, 0.0, -1e-15, -1e-12, -1e-9, -1e-6, -1e-3}) {
          if (std::fabs(delta) * S > 0.5 * std::min(a, b)) continue;
          Ellipse ed = e;
          ed.center = e.center + (outer ? -1.0 : 1.0) * delta * S * u;
          cat.coverage_cases(mf, ed, "tangent ellipse", where + ", margin " + num(delta) + " x scale", delta);
        }
        return true;
      }
    }
  }
  return false;
}

/// Ellipses tangent to a boundary circle of the annuli at an axis end (exact: angle 0, centre on
/// an axis through the base joint, the tangency point moved to the origin of the frame), then
/// moved in and out by delta * S; one family for an outer circle, one for a hole when there is one.
void tangent_family(Catalogue& cat, const Mechanism& m0, const Ellipse& target) {
  const Mechanism m = dyadic(m0);
  const bool outer = tangent_placement(cat, m, target, true);
  const bool has_hole = m.L[0] != m.L[2] || m.L[1] != m.L[3];
  const bool inner = has_hole && tangent_placement(cat, m, target, false);
  if (!outer || (has_hole && !inner)) {
    StabilityCase& c = cat.add("tangent ellipse", "construction", "margin", 0.0);
    c.status = "not constructible";
    c.expected = "-";
    c.explanation = std::string("no axis-aligned tangent placement of the (shrunk) target ellipse at an ") +
                    (!outer ? "outer" : "inner") + " circle";
  }
}

void catalogue(Catalogue& cat, const Mechanism& m, const Ellipse& target) {
  // Distance to type I / type II singularities, and the stiff (ill-conditioned) Jacobians.
  type1_family(cat, m, true);
  type1_family(cat, m, false);
  type2_family(cat, m, true);
  type2_family(cat, m, false);
  // Link ratios: proximal links ratio x the distal ones.
  for (double ratio : {1e-4, 1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3, 1e4}) {
    Mechanism r = without_limits(m);
    r.L[0] = ratio * m.L[2];
    r.L[1] = ratio * m.L[3];
    derived_cases(cat, r, std::nullopt, "link ratio", "L1/L3 = L2/L4 = " + num(ratio), ratio);
  }
  // Scales: the whole mechanism and its target.
  for (double scale : {1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6}) {
    Mechanism s = without_limits(m);
    s.O1 *= scale;
    s.O2 *= scale;
    for (double& l : s.L) l *= scale;
    Ellipse e = target;
    e.center *= scale;
    e.axes *= scale;
    derived_cases(cat, s, e, "scale", "x " + num(scale), scale);
  }
  // Coincident base joints.
  {
    Mechanism c = without_limits(m);
    c.O2 = c.O1;
    derived_cases(cat, c, std::nullopt, "coincident base joints", "O2 = O1", 0.0);
  }
  // Equal proximal and distal links: the folded circle shrinks to the base joint.
  {
    Mechanism q = without_limits(m);
    q.L[2] = q.L[0];
    q.L[3] = q.L[1];
    derived_cases(cat, q, std::nullopt, "equal links", "L3 = L1, L4 = L2", 0.0);
    const double S = q.length_scale();
    // P on O1 (a continuum for leg 1), then near it: the elbow |sin| ~ distance / L1.
    for (double delta : {0.0, 1e-16, 1e-12, 1e-8, 1e-4, 1e-2}) {
      const Vec2 dir = (q.O2 - q.O1).norm() > 0 ? Vec2(0.6, 0.8) : Vec2(0.0, 1.0);
      cat.ik_case(q, q.O1 + delta * S * dir, "equal links", "P at distance " + num(delta) + " x scale from O1", delta,
                  true);
    }
  }
  // Coincident elbows are the folded type II family when L3 = L4.
  tangent_family(cat, m, target);
}

std::string label_of(const Station& s, const Mechanism& m) { return s.name + "/" + m.name; }

}  // namespace

std::size_t StabilityReport::failed() const {
  return std::size_t(std::count_if(cases.begin(), cases.end(), [](const StabilityCase& c) { return !c.passed; }));
}
std::size_t StabilityReport::ill_conditioned() const {
  return std::size_t(std::count_if(cases.begin(), cases.end(), [](const StabilityCase& c) { return c.ill_conditioned; }));
}

StabilityReport stability_catalogue(const Mechanism& m, const Ellipse& target, const std::string& label) {
  StabilityReport report;
  Catalogue cat(label, report.cases);
  catalogue(cat, m, target);
  // Keep each group together (the type I family also yields ill-conditioned Jacobians, ...), in
  // the order the groups first appear.
  std::vector<std::string> order;
  for (const StabilityCase& c : report.cases)
    if (std::find(order.begin(), order.end(), c.group) == order.end()) order.push_back(c.group);
  auto rank = [&](const StabilityCase& c) { return std::find(order.begin(), order.end(), c.group) - order.begin(); };
  std::stable_sort(report.cases.begin(), report.cases.end(),
                   [&](const StabilityCase& a, const StabilityCase& b) { return rank(a) < rank(b); });
  return report;
}

StabilityReport stability_report(const Design& design, const StabilityOptions& o) {
  StabilityReport report;
  report.design = design.name;
  const std::vector<const Station*> stations = design.select_stations(o.station);
  for (const Station* s : stations) {
    for (const Mechanism* m : s->mechanisms()) {
      if (o.progress) o.progress("stability: " + label_of(*s, *m));
      StabilityReport one = stability_catalogue(*m, s->target, label_of(*s, *m));
      for (StabilityCase& c : one.cases) report.cases.push_back(std::move(c));
    }
    if (o.progress) o.progress("stability: " + s->name + " dynamics");
    for (StabilityCase& c : dynamics_stability_cases(design, *s)) report.cases.push_back(std::move(c));
  }
  return report;
}

Json to_json(const StabilityReport& r) {
  Json j;
  j["command"] = "report stability";
  j["design"] = r.design;
  j["cases_total"] = r.cases.size();
  j["failed"] = r.failed();
  j["ill_conditioned"] = r.ill_conditioned();
  j["passed"] = r.passed();
  Json cases = Json::array();
  for (const StabilityCase& c : r.cases) {
    Json k;
    k["subject"] = c.mechanism;  // "index/lower" or the catalogue's label: not a mechanism record
    k["group"] = c.group;
    k["case"] = c.name;
    k["operation"] = c.operation;
    k["parameter"] = c.parameter;
    k["status"] = c.status;
    k["expected"] = c.expected;
    k["unit"] = c.unit;
    k["error"] = c.error ? Json(*c.error) : Json(nullptr);
    k["bound"] = c.bound ? Json(*c.bound) : Json(nullptr);
    k["conditioning"] = c.conditioning;
    k["finite"] = c.finite;
    k["passed"] = c.passed;
    k["ill_conditioned"] = c.ill_conditioned;
    k["explanation"] = c.explanation;
    cases.push_back(k);
  }
  j["cases"] = cases;
  return j;
}

std::string to_text(const StabilityReport& r) {
  using report_fmt::pad;
  std::ostringstream out;
  out << "fivebar report stability: design " << r.design << ", " << r.cases.size() << " cases, " << r.failed()
      << " failed, " << r.ill_conditioned() << " ill-conditioned (flagged, may still pass)\n";
  out << "error: against the __float128 reference; bound: what the problem's conditioning allows in double\n";
  std::string last;
  for (const StabilityCase& c : r.cases) {
    const std::string head = c.mechanism + "  " + c.group;
    if (head != last) {
      out << "\n" << head << "\n";
      out << "  " << pad("case", 48) << pad("op", 17) << pad("status", 16) << pad("error", 10, true)
          << pad("bound", 10, true) << pad("unit", 5, true) << pad("|sin|/LCI", 11, true) << "  verdict\n";
      last = head;
    }
    std::string verdict = c.passed ? "PASS" : "FAIL";
    if (c.ill_conditioned) verdict += " ill-conditioned";
    out << "  " << pad(c.name, 48) << pad(c.operation, 17) << pad(c.status, 16) << pad(sci(c.error), 10, true)
        << pad(sci(c.bound), 10, true) << pad(c.unit, 5, true) << pad(sci(c.conditioning), 11, true) << "  " << verdict
        << "\n";
    if (!c.passed || c.group == "dynamics") out << "      " << c.explanation << "\n";
  }
  out << "\n" << (r.passed() ? "all cases passed" : std::to_string(r.failed()) + " case(s) FAILED") << "\n";
  return out.str();
}

}  // namespace fivebar
