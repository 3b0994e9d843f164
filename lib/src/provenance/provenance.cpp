// Measured or assumed (fivebar/provenance.hpp).
#include "fivebar/provenance.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <ctime>
#include <array>
#include <utility>
#include <cmath>
#include <stdexcept>

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/sha256.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/motor.hpp"
#include "fivebar/sections/print.hpp"
#include "fivebar/sections/provenance.hpp"

namespace fivebar {

namespace {

/// The key paths of joint j's volts_at_zero and rad_per_volt: the narrowest scope that sets each
/// (ControlOverride levels; file order within one).
std::pair<std::string, std::string> potentiometer_keys(const ControllerSettings& c, std::string_view station,
                                                       std::string_view mechanism, int j) {
  std::string v0 = "controller.potentiometer.volts_at_zero", k = "controller.potentiometer.rad_per_volt";
  int l0 = -1, lk = -1;
  for (const ControlOverride& o : c.overrides) {
    const bool applies = (o.station.empty() || o.station == station) && (o.mechanism.empty() || o.mechanism == mechanism) &&
                         (o.joint == 0 || o.joint == j);
    if (!applies) continue;
    if (o.volts_at_zero && o.level() >= l0) l0 = o.level(), v0 = "controller." + o.key() + ".potentiometer.volts_at_zero";
    if (o.rad_per_volt && o.level() >= lk) lk = o.level(), k = "controller." + o.key() + ".potentiometer.rad_per_volt";
  }
  return {v0, k};
}

}  // namespace

std::array<std::string, 12> calibration_keys(const Design& design, std::string_view station, std::string_view mechanism) {
  std::array<std::string, 12> keys;
  const std::string k = "stations." + std::string(station) + ".mechanisms." + std::string(mechanism) + ".";
  for (int i = 0; i < 4; ++i) keys[static_cast<std::size_t>(i)] = k + "links[" + std::to_string(i) + "]";
  keys[4] = k + "bases[0][0]";
  keys[5] = k + "bases[0][1]";
  keys[6] = k + "bases[1][0]";
  keys[7] = k + "bases[1][1]";
  const ControllerSettings* c = design.get<ControllerSettings>();
  const ControllerSettings none;
  for (int j = 1; j <= 2; ++j) {
    const auto [v0, kk] = potentiometer_keys(c ? *c : none, station, mechanism, j);
    keys[static_cast<std::size_t>(6 + 2 * j)] = v0;
    keys[static_cast<std::size_t>(7 + 2 * j)] = kk;
  }
  return keys;
}

const std::vector<std::string>& provenance_groups() {
  static const std::vector<std::string> groups{"kinematics", "potentiometer", "motor", "contact", "density", "tolerance"};
  return groups;
}

namespace {

bool covers(std::string_view k, std::string_view key) {
  return key == k || (key.size() > k.size() && key.substr(0, k.size()) == k && (key[k.size()] == '.' || key[k.size()] == '['));
}

/// The narrowest entry that covers `key` (its own, else the nearest key path above it), or nullptr.
const std::pair<const std::string, ProvenanceEntry>* covering_entry(const Design& design, std::string_view key) {
  const ProvenanceSettings* p = design.get<ProvenanceSettings>();
  if (p == nullptr) return nullptr;
  const std::pair<const std::string, ProvenanceEntry>* best = nullptr;
  for (const auto& item : p->entries) {
    if (covers(item.first, key) && (best == nullptr || item.first.size() > best->first.size())) best = &item;
  }
  return best;
}

/// Why the export's require_measured does not trust `key`, or "" when it does (fivebar/provenance.hpp).
std::string distrust(const Design& design, const std::string& key) {
  const auto* item = covering_entry(design, key);
  if (item == nullptr) return "no provenance: entry (an assumption)";
  const ProvenanceEntry& e = item->second;
  const std::string at = item->first == key ? std::string() : " (entry " + item->first + ")";
  if (e.placeholder_hash()) return "its provenance: entry's sha256 is all zeros, a placeholder rather than a file's hash" + at;
  if (!e.gate) return "its provenance: entry records no quality gate (written by hand or by an older fivebar)" + at;
  if (!e.gate->passed) return "its provenance: entry records a quality gate that did not pass" + at;
  std::filesystem::path file(e.source);
  if (file.is_relative() && !design.source.empty()) file = design.source.parent_path() / file;
  std::error_code ec;
  if (std::filesystem::is_regular_file(file, ec)) {
    std::string now;
    try {
      now = sha256_file(file);
    } catch (const std::exception&) {
      return "its source " + file.generic_string() + " cannot be read to check its sha256" + at;
    }
    if (now != e.sha256) return "its source " + file.generic_string() + " has changed since the fit (sha256 " + now.substr(0, 12) + "... , entry " + e.sha256.substr(0, 12) + "...)" + at;
  }
  return {};
}

}  // namespace

bool is_measured(const Design& design, std::string_view key) {
  const auto* item = covering_entry(design, key);
  if (item == nullptr) return false;
  const ProvenanceEntry& e = item->second;
  return !e.placeholder_hash() && (!e.gate || e.gate->passed);
}

namespace {

/// Every key path of `group` the design has (measured or not).
std::vector<std::string> group_keys(const Design& design, std::string_view group) {
  std::vector<std::string> keys;
  if (group == "kinematics") {
    for (const Station& s : design.stations) {
      for (const Mechanism* m : s.mechanisms()) {
        const std::string k = "stations." + s.name + ".mechanisms." + m->name + ".";
        for (int i = 0; i < 4; ++i) keys.push_back(k + "links[" + std::to_string(i) + "]");
        for (const char* b : {"bases[0][0]", "bases[0][1]", "bases[1][0]", "bases[1][1]"}) keys.push_back(k + b);
      }
    }
  } else if (group == "potentiometer") {
    const ControllerSettings* c = design.get<ControllerSettings>();
    if (c != nullptr) {
      for (const Station& s : design.stations) {
        for (const Mechanism* m : s.mechanisms()) {
          for (int j = 1; j <= 2; ++j) {
            const auto [v0, k] = potentiometer_keys(*c, s.name, m->name, j);
            for (const std::string& key : {v0, k}) {
              if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
            }
          }
        }
      }
    }
  } else if (group == "motor" || group == "contact" || group == "tolerance") {
    keys = design_number_keys(design, group);
  } else if (group == "density") {
    if (design.has<PrintSettings>()) keys.push_back("print.density_g_cm3");
  } else {
    throw InputError("unknown provenance group '" + std::string(group) + "' (known: " + format::join(provenance_groups()) + ")");
  }
  return keys;
}

/// The key paths of `group` that one mechanism's figures rest on (measured or not).
std::vector<std::string> group_keys(const Design& design, std::string_view group, std::string_view station, std::string_view mechanism);

}  // namespace

std::vector<std::string> assumed_values(const Design& design, std::string_view group) {
  std::vector<std::string> keys = group_keys(design, group);
  std::erase_if(keys, [&](const std::string& k) { return is_measured(design, k); });
  return keys;
}

std::vector<std::string> assumed_groups(const Design& design) {
  std::vector<std::string> out;
  for (const std::string& g : provenance_groups()) {
    if (!assumed_values(design, g).empty()) out.push_back(g);
  }
  return out;
}

const std::vector<FigureBasis>& figure_bases() {
  static const std::vector<FigureBasis> table = [] {
    const std::vector<std::string> plant{"kinematics", "motor", "density"};
    std::vector<FigureBasis> t{
        {"max_rho", "max spectral radius", 1.0, "", 4, plant},
        {"kp_margin", "kp margin", 1.0, "x", 2, plant},
        {"kd_margin", "kd margin", 1.0, "x", 2, plant},
        {"oscillatory_damping", "least damping", 1.0, "", 3, plant},
        {"oscillatory_frequency_hz", "least-damped frequency", 1.0, "Hz", 2, plant},
        {"min_bandwidth_hz", "min bandwidth", 1.0, "Hz", 2, plant},
        {"max_tracking_error_m", "max tracking error", 1e3, "mm", 3, {"kinematics", "potentiometer", "motor", "contact", "density"}},
        {"max_saturation_fraction", "time saturated", 100.0, "%", 1, {"kinematics", "motor", "contact", "density"}},
        {"robust_margin_mm", "robust margin", 1.0, "mm", 3, {"kinematics", "tolerance"}},
    };
    // Groups in provenance_groups() order.
    for (FigureBasis& f : t) {
      std::vector<std::string> ordered;
      for (const std::string& g : provenance_groups()) {
        if (std::find(f.groups.begin(), f.groups.end(), g) != f.groups.end()) ordered.push_back(g);
      }
      f.groups = ordered;
    }
    return t;
  }();
  return table;
}

const FigureBasis& figure_basis(std::string_view key) {
  for (const FigureBasis& f : figure_bases()) {
    if (f.key == key) return f;
  }
  std::vector<std::string> keys;
  for (const FigureBasis& f : figure_bases()) keys.push_back(f.key);
  throw InputError("unknown validated figure '" + std::string(key) + "' (known: " + format::join(keys) + ")");
}

namespace {
std::vector<std::string> group_keys(const Design& design, std::string_view group, std::string_view station, std::string_view mechanism) {
  std::vector<std::string> keys;
  if (group == "kinematics" || group == "potentiometer") {
    const std::array<std::string, 12> all = calibration_keys(design, station, mechanism);
    const bool kin = group == "kinematics";
    if (!kin && design.get<ControllerSettings>() == nullptr) return keys;
    keys.assign(all.begin() + (kin ? 0 : 8), all.begin() + (kin ? 8 : 12));
  } else if (group == "motor") {
    const MotorSettings* ms = design.get<MotorSettings>();
    if (ms == nullptr) return keys;
    for (int j = 1; j <= 2; ++j) {
      for (std::size_t f = 0; f < motor_fields().size(); ++f) {
        std::string key = "motor." + std::string(motor_fields()[f].key);
        int level = -1;
        for (const MotorOverride& o : ms->overrides) {
          const bool applies = (o.station.empty() || o.station == station) && (o.mechanism.empty() || o.mechanism == mechanism) &&
                               (o.joint == 0 || o.joint == j);
          if (applies && o.values[f] && o.level() >= level) {
            level = o.level();
            key = "motor." + o.key() + "." + std::string(motor_fields()[f].key);
          }
        }
        if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
      }
    }
  } else {
    return group_keys(design, group);
  }
  return keys;
}
}  // namespace

std::vector<std::string> assumed_values(const Design& design, std::string_view group, std::string_view station,
                                        std::string_view mechanism) {
  std::vector<std::string> keys = group_keys(design, group, station, mechanism);
  std::erase_if(keys, [&](const std::string& k) { return is_measured(design, k); });
  return keys;
}

namespace {
/// The distinct key paths of `group` that the figures of `stations` (all when empty; only
/// `mechanism` when given) rest on.
std::vector<std::string> scoped_keys(const Design& design, std::string_view group, const std::vector<std::string>& stations,
                                     std::string_view mechanism) {
  std::vector<std::string> keys;
  for (const Station& s : design.stations) {
    if (!stations.empty() && std::find(stations.begin(), stations.end(), s.name) == stations.end()) continue;
    for (const Mechanism* m : s.mechanisms()) {
      if (!mechanism.empty() && m->name != mechanism) continue;
      for (std::string& k : group_keys(design, group, s.name, m->name)) {
        if (std::find(keys.begin(), keys.end(), k) == keys.end()) keys.push_back(std::move(k));
      }
    }
  }
  if (keys.empty() && group != "kinematics" && group != "potentiometer" && group != "motor") keys = group_keys(design, group);
  return keys;
}
}  // namespace

std::vector<UntrustedValue> untrusted_values(const Design& design, std::string_view group, const std::vector<std::string>& stations,
                                             std::string_view mechanism) {
  std::vector<UntrustedValue> out;
  for (const std::string& k : scoped_keys(design, group, stations, mechanism)) {
    if (std::string why = distrust(design, k); !why.empty()) out.push_back({k, std::move(why)});
  }
  return out;
}

std::vector<std::string> assumed_groups(const Design& design, const std::vector<std::string>& stations, std::string_view mechanism) {
  std::vector<std::string> out;
  for (const std::string& g : provenance_groups()) {
    const std::vector<std::string> keys = scoped_keys(design, g, stations, mechanism);
    if (std::any_of(keys.begin(), keys.end(), [&](const std::string& k) { return !is_measured(design, k); })) out.push_back(g);
  }
  return out;
}

std::vector<std::string> figure_assumed(const Design& design, std::string_view key, std::string_view station,
                                        std::string_view mechanism) {
  const FigureBasis& f = figure_basis(key);
  std::vector<std::string> out;
  for (const std::string& g : f.groups) {
    const bool assumed = station.empty() ? !assumed_values(design, g).empty() : !assumed_values(design, g, station, mechanism).empty();
    if (assumed) out.push_back(g);
  }
  return out;
}

std::string rests_on_text(const Design& design, std::string_view key, std::string_view station, std::string_view mechanism) {
  const std::vector<std::string> assumed = figure_assumed(design, key, station, mechanism);
  if (assumed.empty()) return "measured (" + format::join(figure_basis(key).groups) + ")";
  return format::join(assumed) + " assumed";
}

std::string figure_text(std::string_view key, double value) {
  const FigureBasis& f = figure_basis(key);
  std::string v = format::fixed(value * f.scale, f.digits);
  if (f.unit == "x") v = "x" + v;
  else if (!f.unit.empty()) v += (f.unit == "%" ? "" : " ") + f.unit;
  return f.label + " " + v;
}

std::string rests_on_line(const Design& design, std::string_view key, double value, std::string_view station,
                          std::string_view mechanism) {
  return figure_text(key, value) + ": " + rests_on_text(design, key, station, mechanism);
}

std::string today_utc() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buffer[16];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%d", &tm);
  return buffer;
}

std::string recorded_source(const std::filesystem::path& data, const std::filesystem::path& design_folder) {
  namespace fs = std::filesystem;
  std::error_code e1;
  std::error_code e2;
  // Both made absolute and free of links and dots, so the relative path leads where the OS would.
  const fs::path to = fs::weakly_canonical(fs::absolute(data, e1), e1);
  const fs::path from = fs::weakly_canonical(fs::absolute(design_folder.empty() ? fs::path(".") : design_folder, e2), e2);
  if (e1 || e2) return data.generic_string();
  const fs::path relative = to.lexically_relative(from);
  return relative.empty() ? to.generic_string() : relative.generic_string();
}

Design with_measured_values(const Design& design, const std::vector<MeasuredValue>& values, const MeasurementSource& source,
                            const Eigen::MatrixXd& covariance, const std::vector<GateRecord>& gates) {
  if (!gates.empty() && gates.size() != values.size()) throw std::invalid_argument("with_measured_values: one gate record per value");
  const auto n = static_cast<Eigen::Index>(values.size());
  if (covariance.size() != 0 && (covariance.rows() != n || covariance.cols() != n)) {
    throw std::invalid_argument("with_measured_values: the covariance must be values.size() square");
  }
  Design d = design;
  ProvenanceSettings p = d.get<ProvenanceSettings>() ? *d.get<ProvenanceSettings>() : ProvenanceSettings{};
  for (const MeasuredValue& v : values) {
    p.entries.erase(v.key);
    for (auto& item : p.entries) item.second.correlation.erase(v.key);
  }
  for (std::size_t i = 0; i < values.size(); ++i) {
    const MeasuredValue& v = values[i];
    ProvenanceEntry e;
    e.source = source.file;
    e.sha256 = source.sha256;
    e.date = source.date;
    e.method = source.method;
    e.sigma = v.sigma;
    if (!gates.empty()) e.gate = gates[i];
    p.entries[v.key] = std::move(e);
  }
  if (covariance.size() != 0) {
    for (Eigen::Index a = 0; a < n; ++a) {
      for (Eigen::Index b = 0; b < n; ++b) {
        const MeasuredValue& va = values[static_cast<std::size_t>(a)];
        const MeasuredValue& vb = values[static_cast<std::size_t>(b)];
        if (!(va.key < vb.key) || !(va.sigma > 0.0) || !(vb.sigma > 0.0)) continue;
        const double rho = std::clamp(covariance(a, b) / (va.sigma * vb.sigma), -1.0, 1.0);
        if (rho != 0.0 && std::isfinite(rho)) p.entries[va.key].correlation[vb.key] = rho;
      }
    }
  }
  d.set(std::move(p));
  d.validate();
  return d;
}

ProvenanceCovariance provenance_covariance(const Design& design, const std::vector<std::string>& keys) {
  const auto n = static_cast<Eigen::Index>(keys.size());
  ProvenanceCovariance out;
  out.covariance = Eigen::MatrixXd::Zero(n, n);
  out.measured.assign(keys.size(), false);
  const ProvenanceSettings* p = design.get<ProvenanceSettings>();
  if (p == nullptr) return out;
  // The entry that covers each key: its own, else the nearest key path above it.
  std::vector<const std::string*> entry_key(keys.size(), nullptr);
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const std::string& key = keys[i];
    for (const auto& [k, e] : p->entries) {
      const bool covers = key == k || (key.size() > k.size() && key.compare(0, k.size(), k) == 0 && (key[k.size()] == '.' || key[k.size()] == '['));
      if (covers && e.sigma && (entry_key[i] == nullptr || k.size() > entry_key[i]->size())) entry_key[i] = &k;
    }
    if (entry_key[i] == nullptr) continue;
    const ProvenanceEntry& e = p->entries.find(*entry_key[i])->second;
    out.measured[i] = true;
    out.covariance(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i)) = *e.sigma * *e.sigma;
    if (std::find(out.sources.begin(), out.sources.end(), e.source) == out.sources.end()) out.sources.push_back(e.source);
  }
  for (Eigen::Index a = 0; a < n; ++a) {
    for (Eigen::Index b = 0; b < n; ++b) {
      const std::string* ka = entry_key[static_cast<std::size_t>(a)];
      const std::string* kb = entry_key[static_cast<std::size_t>(b)];
      if (a == b || ka == nullptr || kb == nullptr || *ka == *kb) continue;
      const ProvenanceEntry& ea = p->entries.find(*ka)->second;
      const auto it = ea.correlation.find(*kb);
      if (it == ea.correlation.end()) continue;
      const ProvenanceEntry& eb = p->entries.find(*kb)->second;
      const double c = it->second * *ea.sigma * *eb.sigma;
      out.covariance(a, b) = c;
      out.covariance(b, a) = c;
    }
  }
  return out;
}

}  // namespace fivebar
