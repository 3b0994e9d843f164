// Link-dimension sweeps: enumeration, evaluation with early exit, CSV streaming, Pareto archive,
// resume. Parallel with OpenMP over chunks of designs; rows are written in index order, so the
// output does not depend on the number of threads.
#include "fivebar/format.hpp"
#include "fivebar/sweep.hpp"

#include "fivebar/design/edit.hpp"
#include "csv.hpp"

#include <boost/random/sobol.hpp>
#include <omp.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>

#include "fivebar/collision.hpp"
#include "fivebar/csv_reader.hpp"
#include "fivebar/io.hpp"
#include "fivebar/json.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/tolerance.hpp"

namespace fivebar {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// Uniform [0, 1) from 53 random bits.
double unit(std::uint64_t bits) { return double(bits >> 11) * 0x1.0p-53; }

using csv::field;
/// CSV cell of a number: shortest round-trip form, empty for "no value" (NaN).
std::string num(double v) { return csv::number(v); }

const Vec2 kX(1.0, 0.0);

}  // namespace

// --- enumeration ---------------------------------------------------------------------------------

std::uint64_t sweep_size(const SweepSettings& s) {
  if (s.sample != "grid") return s.count;
  std::uint64_t n = 1;
  for (const SweepVariable& v : s.vary) n *= std::uint64_t(v.n);
  return n;
}

namespace {

/// Unit-cube coordinates of design `index`, for `count` consecutive designs (sequential Sobol).
void unit_points(const SweepSettings& s, std::uint64_t first, std::uint64_t count, std::vector<double>& u) {
  const std::size_t dims = s.vary.size();
  u.resize(count * dims);
  if (s.sample == "grid") {
    for (std::uint64_t k = 0; k < count; ++k) {
      std::uint64_t rest = first + k;
      for (std::size_t d = dims; d-- > 0;) {  // the last variable runs fastest
        const std::uint64_t n = std::uint64_t(s.vary[d].n);
        const std::uint64_t i = rest % n;
        rest /= n;
        u[k * dims + d] = n > 1 ? double(i) / double(n - 1) : 0.0;
      }
    }
  } else if (s.sample == "random") {
    for (std::uint64_t k = 0; k < count; ++k) {
      for (std::size_t d = 0; d < dims; ++d) {
        u[k * dims + d] = unit(splitmix64(splitmix64(s.seed) ^ ((first + k) * dims + d)));
      }
    }
  } else {  // sobol, with a Cranley-Patterson shift by the seed (seed 0: the plain sequence)
    boost::random::sobol engine(dims);
    engine.discard(first * dims);
    for (std::uint64_t k = 0; k < count; ++k) {
      for (std::size_t d = 0; d < dims; ++d) {
        double v = double(engine() - engine.min()) / (double(engine.max() - engine.min()) + 1.0);
        if (s.seed != 0) {
          v += unit(splitmix64(s.seed * 0x100000001B3ull + d));
          v -= std::floor(v);
        }
        u[k * dims + d] = v;
      }
    }
  }
}

void to_values(const SweepSettings& s, const double* u, std::vector<double>& values, bool grid) {
  values.resize(s.vary.size());
  for (std::size_t d = 0; d < s.vary.size(); ++d) {
    const SweepVariable& v = s.vary[d];
    values[d] = v.lo + (v.hi - v.lo) * u[d];
    if (grid && u[d] == 1.0) values[d] = v.hi;  // exact end points
  }
}

}  // namespace

std::vector<double> sweep_point(const SweepSettings& settings, std::uint64_t index) {
  std::vector<double> u, values;
  unit_points(settings, index, 1, u);
  to_values(settings, u.data(), values, settings.sample == "grid");
  return values;
}

Station apply_sweep(const Design& design, const SweepSettings& s, const std::vector<double>& values) {
  const Station* base = design.station(s.station);
  if (base == nullptr) throw ValidationError("station", "no such station: " + s.station);
  Station st = *base;
  std::vector<Mechanism*> targets;
  for (Mechanism* m : {st.lower ? &*st.lower : nullptr, st.upper ? &*st.upper : nullptr}) {
    if (m && (s.mechanism.empty() || s.mechanism == m->name)) targets.push_back(m);
  }
  for (std::size_t d = 0; d < s.vary.size(); ++d) {
    const std::string& name = s.vary[d].name;
    const double v = values[d];
    if (name == "ellipse_a") {
      st.target.axes.x() = v;
    } else if (name == "ellipse_b") {
      st.target.axes.y() = v;
    } else if (name == "upper_height") {
      if (!st.upper) throw ValidationError("mechanisms.upper", "upper_height is swept but there is no upper mechanism");
      st.upper->O1.y() = v;
      st.upper->O2.y() = v;
    } else {
      for (Mechanism* m : targets) {
        // The links through the one design-edit API (fivebar/design/edit.hpp): L1..L4 are
        // stations.<s>.mechanisms.<m>.links[0..3].
        DesignKey key;
        key.field = DesignKey::Field::link;
        key.upper = m == (st.upper ? &*st.upper : nullptr);
        const int first = name == "L1" || name == "L12" ? 0 : name == "L2" ? 1 : name == "L3" || name == "L34" ? 2 : name == "L4" ? 3 : -1;
        if (first >= 0) {
          key.i = first;
          set_station_number(st, key, v);
        }
        if (name == "L12" || name == "L34") {
          key.i = first + 1;
          set_station_number(st, key, v);
        }
        if (name == "spacing") {
          const Vec2 dir = m->O2 != m->O1 ? Vec2((m->O2 - m->O1).normalized()) : kX;
          m->O2 = m->O1 + v * dir;
        }
      }
    }
  }
  check_station_edit(st, design.get<Geometry>());  // the rules of an edited station, stated once
  return st;
}

// --- evaluation ----------------------------------------------------------------------------------

double sweep_collision_spacing(const SweepSettings& settings, const Ellipse& target) {
  const double widest = std::max(target.axes.x(), target.axes.y());
  return std::max(settings.collision_spacing_mm, widest / kSweepCollisionStepsAcross);
}

SweepRow::SweepRow()
    : margin_lower_mm(kNaN), margin_upper_mm(kNaN), margin_shared_mm(kNaN), min_lci(kNaN),
      min_force_capability(kNaN), footprint_w_mm(kNaN), footprint_h_mm(kNaN), footprint_mm2(kNaN),
      collision_fraction(kNaN), robust_margin_mm(kNaN) {}

double SweepRow::score(const std::string& objective) const {
  if (objective == "margin") {
    return !std::isnan(margin_shared_mm) ? margin_shared_mm
                                         : std::fmin(margin_lower_mm, margin_upper_mm);  // fmin skips NaN
  }
  if (objective == "min_lci") return min_lci;
  if (objective == "force") return min_force_capability;
  if (objective == "footprint") return -footprint_mm2;
  if (objective == "collision") return -collision_fraction;
  if (objective == "robust") return robust_margin_mm;
  return kNaN;
}

CoverageOptions sweep_coverage_options() {
  // Min LCI from 1 + 2 x 24 samples refined by compass search to 1e-3 of the ellipse size: the
  // minimum is then known to ~1e-6 (the LCI field is smooth; its minimum over the ellipse lies on
  // the boundary for the usual designs). `fivebar coverage` refines further.
  CoverageOptions o;
  o.rings = 2;
  o.angles = 24;
  o.lci_refine = 1e-3;
  return o;
}

namespace {

void footprint(const Station& st, const std::vector<const Mechanism*>& targets, const Design& design, SweepRow& row) {
  double x0 = st.target.center.x(), x1 = x0, y0 = st.target.center.y(), y1 = y0;
  auto add = [&](const Vec2& p) {
    x0 = std::min(x0, p.x());
    x1 = std::max(x1, p.x());
    y0 = std::min(y0, p.y());
    y1 = std::max(y1, p.y());
  };
  // The elbow angles take their extremes on the ellipse's boundary (no interior critical points:
  // d theta_i / dP is a row of J^-1, never zero away from singularities), so boundary samples
  // bound the linkage; the tactor sweeps the ellipse itself.
  constexpr int kSamples = 32;
  thread_local std::vector<double> uc, us;
  if (uc.empty()) {
    for (int k = 0; k < kSamples; ++k) {
      uc.push_back(std::cos(2 * std::numbers::pi * k / kSamples));
      us.push_back(std::sin(2 * std::numbers::pi * k / kSamples));
    }
  }
  const double c = std::cos(st.target.angle), s = std::sin(st.target.angle);
  const double a = 0.5 * st.target.axes.x(), b = 0.5 * st.target.axes.y();
  add(st.target.center + Vec2(std::hypot(a * c, b * s), std::hypot(a * s, b * c)));
  add(st.target.center - Vec2(std::hypot(a * c, b * s), std::hypot(a * s, b * c)));
  for (const Mechanism* m : targets) {
    add(m->O1);
    add(m->O2);
    for (int k = 0; k < kSamples; ++k) {
      const Vec2 q = st.target.center + Vec2(c * a * uc[k] - s * b * us[k], s * a * uc[k] + c * b * us[k]);
      const auto x1i = intersect_circles(m->O1, m->L[0], q, m->L[2], -m->working_mode.sign1);
      const auto x2i = intersect_circles(m->O2, m->L[1], q, m->L[3], -m->working_mode.sign2);
      if (x1i.status != Status::unreachable) add(x1i.point);
      if (x2i.status != Status::unreachable) add(x2i.point);
    }
  }
  const double pad = design.get<Geometry>() ? 0.5 * std::max(design.get<Geometry>()->boss_diameter,
                                                      *std::max_element(design.get<Geometry>()->link_width.begin(),
                                                                        design.get<Geometry>()->link_width.end()))
                                     : 0.0;
  row.footprint_w_mm = x1 - x0 + 2 * pad;
  row.footprint_h_mm = y1 - y0 + 2 * pad;
  row.footprint_mm2 = row.footprint_w_mm * row.footprint_h_mm;
}

std::string fmt_margin(const std::string& which, double margin) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, margin, std::chars_format::general, 6);
  return "not covered: " + which + " margin " + std::string(buf, r.ptr) + " mm";
}

SweepRow evaluate_values(const Design& design, const SweepSettings& s, std::uint64_t index, std::vector<double> values,
                         const CoverageOptions& cov) {
  SweepRow row;
  Station st;
  try {
    st = apply_sweep(design, s, values);
  } catch (const ValidationError& e) {
    row.index = index;
    row.values = std::move(values);
    row.status = std::string("invalid: ") + e.what();
    return row;
  }
  StationFigureRequest request;
  request.mechanism = s.mechanism;
  request.collision_spacing_mm = s.collision_spacing_mm;
  request.robust = std::find(s.objectives.begin(), s.objectives.end(), "robust") != s.objectives.end();
  request.coverage = cov;
  row = evaluate_station_figures(design, st, request);
  row.index = index;
  row.values = std::move(values);
  return row;
}

}  // namespace

SweepRow evaluate_station_figures(const Design& design, const Station& st, const StationFigureRequest& request) {
  SweepRow row;
  const CoverageOptions& cov = request.coverage;
  std::vector<const Mechanism*> targets;
  for (const Mechanism* m : st.mechanisms()) {
    if (request.mechanism.empty() || request.mechanism == m->name) targets.push_back(m);
  }
  // Hard constraints in order of cost; the first failure ends the evaluation.
  for (const Mechanism* m : targets) {
    const Containment c = containment(*m, st.target);
    (m->name == "lower" ? row.margin_lower_mm : row.margin_upper_mm) = c.margin_mm;
    if (!c.inside) {
      row.status = c.decided ? fmt_margin(m->name, c.margin_mm)
                             : "undecided: " + m->name + " within rounding of the region boundary";
      return row;
    }
  }
  if (targets.size() == 2) row.margin_shared_mm = std::min(row.margin_lower_mm, row.margin_upper_mm);
  row.min_lci = std::numeric_limits<double>::infinity();
  row.min_force_capability = std::numeric_limits<double>::infinity();
  for (const Mechanism* m : targets) {
    CoverageResult r;
    conditioning(*m, st.target, cov, r);
    row.min_lci = std::min(row.min_lci, r.min_lci);
    row.min_force_capability = std::min(row.min_force_capability, r.min_force_capability);
    if (!r.assembly_ok) {
      row.status = r.decided ? "not covered: " + m->name + " tactor crosses to the wrong assembly side"
                             : "undecided: " + m->name + " within rounding of the type II curve";
      return row;
    }
    if (!r.lci_ok) {
      std::ostringstream why;
      why << "not covered: " << m->name << " min LCI " << r.min_lci << " < " << m->min_lci;
      row.status = why.str();
      return row;
    }
  }
  footprint(st, targets, design, row);
  // Soft: the collision fraction (the costliest metric, so last and only for covered designs).
  if (design.get<Geometry>() && st.lower && st.upper && request.collision_spacing_mm > 0.0) {
    row.collision_fraction =
        collision_fraction(st, *design.get<Geometry>(), std::max(request.collision_spacing_mm, std::max(st.target.axes.x(), st.target.axes.y()) / kSweepCollisionStepsAcross)).fraction;
  }
  // Soft: the robust margin (72 boundary points, 17 margins each per mechanism: about 1 ms), only
  // when asked for.
  if (request.robust) {
    row.robust_margin_mm = std::numeric_limits<double>::infinity();
    for (const Mechanism* m : targets) {
      const ToleranceSources src = tolerance_sources(design, st, *m);
      row.robust_margin_mm = std::min(
          row.robust_margin_mm, robust_coverage(*m, st.target, src.spread(), src.robust_fraction, 0, src.seed).robust_margin_mm);
    }
  }
  row.covered = true;
  row.status = "covered";
  return row;
}


SweepRow evaluate_sweep_design(const Design& design, const SweepSettings& settings, std::uint64_t index,
                               const CoverageOptions& coverage) {
  return evaluate_values(design, settings, index, sweep_point(settings, index), coverage);
}

// --- Pareto --------------------------------------------------------------------------------------

bool ParetoArchive::dominates(const SweepRow& a, const SweepRow& b) const {
  bool better = false;
  for (const std::string& o : objectives_) {
    const double x = a.score(o), y = b.score(o);
    if (x < y) return false;
    if (x > y) better = true;
  }
  return better;
}

void ParetoArchive::insert(const SweepRow& row) {
  if (!row.covered) return;
  for (const SweepRow& r : rows_) {
    if (dominates(r, row)) return;
  }
  rows_.erase(std::remove_if(rows_.begin(), rows_.end(), [&](const SweepRow& r) { return dominates(row, r); }),
              rows_.end());
  rows_.push_back(row);
}

// --- CSV -----------------------------------------------------------------------------------------

std::string sweep_csv_header(const SweepSettings& s) {
  std::string h = "index";
  for (const SweepVariable& v : s.vary) h += "," + v.name + (v.name.rfind("ellipse", 0) == 0 ? "_mm" : "_mm");
  h += ",status,covered,margin_lower_mm,margin_upper_mm,margin_shared_mm,min_lci,min_force_capability,"
       "footprint_w_mm,footprint_h_mm,footprint_mm2,collision_fraction,robust_margin_mm";
  return h;
}

std::string sweep_csv_row(const SweepRow& r) {
  std::string line = std::to_string(r.index);
  for (double v : r.values) line += "," + num(v);
  line += "," + field(r.status) + "," + (r.covered ? "1" : "0");
  for (double v : {r.margin_lower_mm, r.margin_upper_mm, r.margin_shared_mm, r.min_lci, r.min_force_capability,
                   r.footprint_w_mm, r.footprint_h_mm, r.footprint_mm2, r.collision_fraction, r.robust_margin_mm}) {
    line += "," + num(v);
  }
  return line;
}

namespace {

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cur += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cur += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

/// Longest line of a sweep CSV read back: a row is a few hundred bytes (its status message included).
constexpr std::size_t kMaxSweepCsvLine = std::size_t{64} << 10;

bool parse_double(const std::string& text, double& v) {
  if (text.empty()) {
    v = kNaN;
    return true;
  }
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  return r.ec == std::errc{} && r.ptr == text.data() + text.size();
}

}  // namespace

void read_sweep_csv(const std::filesystem::path& csv, const SweepSettings& settings,
                    const std::function<void(const SweepRow&, const std::string& line)>& row) {
  std::ifstream in(csv, std::ios::binary);
  if (!in) throw InputError(csv.string() + ": cannot read the sweep CSV");
  // The one bounded reader (fivebar/csv_reader.hpp): a row of this sweep is far below 64 KiB and
  // the file holds at most the sweep's designs, so a file that is not this sweep's CSV (a link to
  // /dev/zero, a line with no end) is refused after one bounded line (docs/reliability.md "Resume").
  csv::Limits limits;
  limits.max_line = kMaxSweepCsvLine;
  limits.max_bytes = std::numeric_limits<std::uintmax_t>::max();
  limits.max_rows = static_cast<std::size_t>(std::min<std::uint64_t>(sweep_size(settings), std::numeric_limits<std::size_t>::max()));
  csv::Reader reader(in, csv.string(), limits);
  if (reader.header() != split_csv(sweep_csv_header(settings))) {
    throw InputError(reader.where() + "header differs from this sweep's (" + sweep_csv_header(settings) + "): not the same sweep");
  }
  const std::size_t nv = settings.vary.size();
  while (reader.next()) {
    const auto& f = reader.cells();
    auto bad = [&](const std::string& why) { throw InputError(reader.where() + why); };
    SweepRow r;
    const auto res = std::from_chars(f[0].data(), f[0].data() + f[0].size(), r.index);
    if (res.ec != std::errc{} || f[0].empty() || res.ptr != f[0].data() + f[0].size()) bad("index '" + csv::shown(f[0]) + "' is not a whole number");
    r.values.resize(nv);
    for (std::size_t d = 0; d < nv; ++d) {
      if (!parse_double(f[1 + d], r.values[d]) || !std::isfinite(r.values[d])) bad("bad value '" + csv::shown(f[1 + d]) + "'");
    }
    r.status = f[1 + nv];
    if (f[2 + nv] != "0" && f[2 + nv] != "1") bad("covered must be 0 or 1");
    r.covered = f[2 + nv] == "1";
    double* metrics[] = {&r.margin_lower_mm, &r.margin_upper_mm, &r.margin_shared_mm, &r.min_lci,
                         &r.min_force_capability, &r.footprint_w_mm, &r.footprint_h_mm, &r.footprint_mm2,
                         &r.collision_fraction, &r.robust_margin_mm};
    for (std::size_t k = 0; k < 10; ++k) {
      if (!parse_double(f[3 + nv + k], *metrics[k])) bad("bad number '" + csv::shown(f[3 + nv + k]) + "'");
    }
    row(r, reader.text());
  }
}


// --- run -----------------------------------------------------------------------------------------

namespace {

/// sweep.identity.json, parsed (null when it is not JSON): a few hundred bytes when fivebar wrote
/// it, so one past 1 MiB is refused unread (InputError).
Json read_identity(const std::filesystem::path& path) {
  try {
    return Json::parse(csv::read_bounded(path, std::uintmax_t{1} << 20, "sweep identity"));
  } catch (const Json::exception&) {
    return Json();
  }
}

bool better_lexicographic(const SweepRow& a, const SweepRow& b, const std::vector<std::string>& objectives) {
  for (const std::string& o : objectives) {
    const double x = a.score(o), y = b.score(o);
    if (x > y) return true;
    if (x < y) return false;
  }
  return a.index < b.index;
}

std::string csv_name(const SweepOptions& o) {
  if (o.shards <= 1) return "sweep.csv";
  return "sweep.shard-" + std::to_string(o.shard) + "-of-" + std::to_string(o.shards) + ".csv";
}

}  // namespace

// Whichever launcher started us (Open MPI, or any PMI/PMIx one) says how many ranks there are.
bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"}) {
    if (const char* s = std::getenv(v)) return std::atoi(s) > 1;
  }
  return false;
}

int sweep_threads(int requested) {
  const std::string bound = std::to_string(kMaxSweepThreads);
  if (requested < 0 || requested > kMaxSweepThreads) {
    throw InputError("threads = " + std::to_string(requested) + ": must be 1 ... " + bound + " (0: every core)");
  }
  if (requested > 0) return requested;
  const int fallback = omp_get_max_threads();
  if (fallback > kMaxSweepThreads) {
    throw InputError("OMP_NUM_THREADS asks for " + std::to_string(fallback) + " threads: a sweep runs at most " + bound);
  }
  return fallback;
}

std::string SweepEstimate::text() const {
  char buffer[200];
  const double hours = seconds / 3600.0;
  std::snprintf(buffer, sizeof buffer, "%.3g designs: about %s on %d thread%s and %.3g MB of CSV", double(designs),
                (hours >= 1.0 ? format::fixed(hours, 1) + " h" : format::fixed(seconds, 1) + " s").c_str(), threads,
                threads == 1 ? "" : "s", csv_bytes / 1e6);
  return buffer;
}

SweepEstimate estimate_sweep(const Design& design, const SweepOptions& options, std::uint64_t probe) {
  if (!design.get<SweepSettings>()) throw InputError(design.name + ": the design has no sweep: section");
  const SweepSettings& s = *design.get<SweepSettings>();
  SweepEstimate e;
  e.threads = sweep_threads(options.threads);
  const std::uint64_t all = sweep_size(s);
  const std::uint64_t shards = std::max<std::uint64_t>(options.shards, 1);
  e.designs = all / shards + (options.shard < all % shards ? 1 : 0);
  const std::uint64_t n = std::min(probe, e.designs);
  if (n == 0) return e;
  std::vector<double> u, values;
  double bytes = 0.0;
  const auto t0 = std::chrono::steady_clock::now();
  for (std::uint64_t k = 0; k < n; ++k) {
    const std::uint64_t index = (e.designs / n) * k;  // spread over the sweep: sizes change along it
    unit_points(s, index, 1, u);
    to_values(s, u.data(), values, s.sample == "grid");
    const SweepRow row = evaluate_values(design, s, index, values, options.coverage);
    bytes += double(sweep_csv_row(row).size() + 1);
  }
  const double per_design = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / double(n);
  e.seconds = per_design * double(e.designs) / double(e.threads);
  e.csv_bytes = bytes / double(n) * double(e.designs);
  return e;
}

SweepResult run_sweep(const Design& design, const SweepOptions& options) {
  const int threads = sweep_threads(options.threads);
  if (!design.get<SweepSettings>()) throw InputError(design.name + ": the design has no sweep: section");
  if (!options.confirmed) {
    const SweepEstimate e = estimate_sweep(design, options);
    if (e.seconds > kSweepConfirmSeconds || e.csv_bytes > kSweepConfirmBytes) {
      throw InputError("this sweep is large: " + e.text() + "; confirm it, or sample it (sweep.sample: sobol, sweep.count)",
                       Remedy::confirm);
    }
  }
  const SweepSettings& s = *design.get<SweepSettings>();
  if (options.shards == 0 || options.shard >= options.shards) throw InputError("shard out of range");
  SweepResult result;
  const std::uint64_t all = sweep_size(s);
  result.first = all / options.shards * options.shard + std::min(options.shard, all % options.shards);
  result.total = all / options.shards + (options.shard < all % options.shards ? 1 : 0);
  const std::uint64_t end = result.first + result.total;
  make_directories(options.out_dir);
  result.csv = options.out_dir / csv_name(options);

  ParetoArchive archive(s.objectives);
  std::optional<SweepRow> best;
  auto account = [&](const SweepRow& r) {
    archive.insert(r);
    if (r.covered && (!best || better_lexicographic(r, *best, s.objectives))) best = r;
  };

  // The identity of this sweep (docs/reliability.md "Resume"): the whole design with its sweep
  // section, the CSV layout and the shard. resuming continues only a CSV written under the same one.
  std::filesystem::path identity_path = result.csv;
  identity_path.replace_extension(".identity.json");
  char hash[32];
  std::snprintf(hash, sizeof hash, "fnv1a64:%016llx", static_cast<unsigned long long>(format::fnv1a64(to_yaml(design))));
  Json identity = {{"design_hash", hash},
                   {"csv_header", sweep_csv_header(s)},
                   {"first", result.first},
                   {"total", result.total}};
  const bool resuming = options.resume && std::filesystem::exists(result.csv);
  if (resuming) {
    std::error_code ec;
    const bool in = std::filesystem::exists(identity_path, ec);
    const Json found = in ? read_identity(identity_path) : Json();
    if (!in || found != identity) {
      throw InputError(result.csv.string() + ": cannot resume: " +
                       (in ? "not the same sweep: " + identity_path.filename().string() + " names another (design hash " +
                                 (found.contains("design_hash") ? found["design_hash"].dump() : std::string("unknown")) +
                                 ", this one " + hash + ")"
                           : "no " + identity_path.filename().string() +
                                 " beside it, so it cannot be shown to belong to this sweep") +
                       "; start afresh instead of resuming",
                       Remedy::start_afresh);
    }
  }
  write_file_atomic(identity_path, identity.dump(2) + "\n");

  AtomicFile csv(result.csv);
  csv.stream() << sweep_csv_header(s) << '\n';
  std::uint64_t next = result.first;
  if (resuming) {
    std::vector<double> u_row, expected;
    read_sweep_csv(result.csv, s, [&](const SweepRow& r, const std::string& line) {
      if (r.index != next || next >= end) {
        throw InputError(result.csv.string() + ": row with index " + std::to_string(r.index) + " where " +
                         std::to_string(next) + " was expected: not a prefix of this sweep");
      }
      // Every resumed row must hold the values this sweep gives its index, to the last bit.
      unit_points(s, r.index, 1, u_row);
      to_values(s, u_row.data(), expected, s.sample == "grid");
      if (expected != r.values) {
        throw InputError(result.csv.string() + ": row " + std::to_string(r.index) +
                         " holds other swept values than this sweep gives that index: not the same sweep");
      }
      csv.stream() << line << '\n';
      account(r);
      ++next;
    });
  }
  result.done = next - result.first;

  const auto t0 = std::chrono::steady_clock::now();
  std::vector<double> u;
  std::vector<SweepRow> rows;
  const std::size_t dims = s.vary.size();
  const bool is_grid = s.sample == "grid";
  while (next < end) {
    const std::uint64_t n = std::min<std::uint64_t>(options.chunk, end - next);
    unit_points(s, next, n, u);
    rows.assign(n, SweepRow{});
    const std::int64_t count = std::int64_t(n);
#pragma omp parallel for schedule(dynamic, 64) num_threads(threads)
    for (std::int64_t k = 0; k < count; ++k) {
      std::vector<double> values;
      to_values(s, u.data() + std::size_t(k) * dims, values, is_grid);
      // An exception must not leave an OpenMP region (std::terminate, no CSV): a design that
      // throws becomes a row saying so, and the sweep goes on.
      try {
        rows[std::size_t(k)] = evaluate_values(design, s, next + std::uint64_t(k), std::move(values), options.coverage);
      } catch (const std::exception& e) {
        SweepRow& r = rows[std::size_t(k)];
        r = SweepRow{};
        r.index = next + std::uint64_t(k);
        to_values(s, u.data() + std::size_t(k) * dims, r.values, is_grid);
        r.status = std::string("error: ") + e.what();
      }
    }
    for (const SweepRow& r : rows) {
      csv.stream() << sweep_csv_row(r) << '\n';
      account(r);
      result.covered += r.covered;
      result.invalid += r.status.rfind("invalid", 0) == 0;
    }
    next += n;
    result.evaluated += n;
    result.done = next - result.first;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (options.progress) options.progress(result.done, result.total, seconds);
    if (options.stop && options.stop->load() && next < end) {
      result.interrupted = true;
      break;
    }
  }
  csv.commit();  // a valid CSV of every completed row, interrupted or not
  result.files.push_back(result.csv);
  result.files.push_back(identity_path);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  result.designs_per_s = result.seconds > 0 ? double(result.evaluated) / result.seconds : 0.0;

  result.pareto = archive.rows();
  std::sort(result.pareto.begin(), result.pareto.end(),
            [](const SweepRow& a, const SweepRow& b) { return a.index < b.index; });
  const std::string suffix = options.shards > 1 ? ".shard-" + std::to_string(options.shard) + "-of-" +
                                                      std::to_string(options.shards)
                                                : "";
  {
    std::string text = sweep_csv_header(s) + "\n";
    for (const SweepRow& r : result.pareto) text += sweep_csv_row(r) + "\n";
    const auto path = options.out_dir / ("pareto" + suffix + ".csv");
    write_file_atomic(path, text);
    result.files.push_back(path);
  }
  result.best = best;
  if (best) {
    Design d = design;
    Station st = apply_sweep(design, s, best->values);
    for (Station& x : d.stations) {
      if (x.name == st.name) x = st;
    }
    d.reset<SweepSettings>();
    d.products.reset();
    // Its own name, so that `fivebar run best.yaml` does not overwrite the swept design's outputs.
    d.name = design.name.substr(0, 59) + "-best";
    result.best_design = d;
    const auto path = options.out_dir / ("best" + suffix + ".yaml");
    std::ostringstream head;
    head << "# Best design of the sweep of " << design.name << " (station " << s.station << "), design #"
         << best->index << " by the objectives " ;
    for (std::size_t i = 0; i < s.objectives.size(); ++i) head << (i ? ", " : "") << s.objectives[i];
    head << ".\n# Written by fivebar sweep: a complete design file (fivebar run " << path.filename().string()
         << ").\n";
    write_file_atomic(path, head.str() + to_yaml(d));
    result.files.push_back(path);
  }
  if (options.plots && options.shards <= 1 && !result.interrupted) {
    for (const auto& f : write_sweep_plots(result.csv, s, result.pareto, options.out_dir)) result.files.push_back(f);
  }
  return result;
}

}  // namespace fivebar
