// Tests of the controller export (fivebar/export/export.hpp): number formatting, the hash, the parameter
// tree against the design (values typed here from the paper's Table 1 and the showcase's
// controller section), every format read back with an independent reader (yaml-cpp, nlohmann) and
// with parse_export(), the gate's checks and reasons, atomic writing, and --check's comparison.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <limits>
#include <numbers>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/patterns.hpp"
#include "fivebar/sections/print.hpp"
#include "fivebar/sections/optimize.hpp"
#include "fivebar/sections/sweep.hpp"
#include "fivebar/sections/bench.hpp"
#include "fivebar/sections/contact.hpp"
#include "fivebar/sections/motor.hpp"
#include "fivebar/sections/tolerance.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/export/mjcf.hpp"
#include "fivebar/export/urdf.hpp"
#include "fivebar/sha256.hpp"
#include "fivebar/error.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/format.hpp"
#include "fivebar/io.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/version.hpp"

namespace fivebar {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::Contains;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::Not;
using ::testing::StartsWith;
using ::testing::ThrowsMessage;

const fs::path kSource = FIVEBAR_SOURCE_DIR;
constexpr double kPi = std::numbers::pi;
double deg(double d) { return d * kPi / 180.0; }

Design paper() { return load_design(kSource / "designs" / "iros2022.yaml"); }

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::uint64_t seed() {
  const char* env = std::getenv("FIVEBAR_TEST_SEED");
  return env ? std::strtoull(env, nullptr, 10) : 20220714u;
}

const Json& params_of(const Json& tree) { return tree.begin().value().at("ros__parameters"); }

// --- Numbers and hash --------------------------------------------------------------------------------

TEST(FormatDouble, AlwaysADoubleInShortestForm) {
  EXPECT_EQ(format_double(5.0), "5.0");
  EXPECT_EQ(format_double(-3.0), "-3.0");
  EXPECT_EQ(format_double(0.0), "0.0");
  EXPECT_EQ(format_double(-0.0), "-0.0");
  EXPECT_EQ(format_double(0.1), "0.1");
  EXPECT_EQ(format_double(0.009), "0.009");
  EXPECT_EQ(format_double(1e-5), "1.0e-05");
  EXPECT_EQ(format_double(-2.5e20), "-2.5e+20");
  EXPECT_EQ(format_double(1e300), "1.0e+300");
  EXPECT_EQ(format_double(0.1 + 0.2), "0.30000000000000004");
  EXPECT_EQ(format_double(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(format_double(std::nan("")), "nan");
}

TEST(FormatDouble, ReadsBackBitForBit) {
  std::mt19937_64 rng(seed());
  std::uniform_int_distribution<std::uint64_t> bits;
  SCOPED_TRACE("seed " + std::to_string(seed()) + " (FIVEBAR_TEST_SEED overrides)");
  for (int i = 0; i < 20000; ++i) {
    double x = 0.0;
    const std::uint64_t b = bits(rng);
    std::memcpy(&x, &b, sizeof x);
    if (!std::isfinite(x)) continue;
    const std::string text = format_double(x);
    ASSERT_NE(text.find('.'), std::string::npos) << text;
    EXPECT_EQ(std::strtod(text.c_str(), nullptr), x) << text;
  }
}

TEST(Hash, Fnv1a64KnownVectors) {
  // Reference values of the FNV-1a 64-bit function (Fowler, Noll, Vo).
  EXPECT_EQ(format::fnv1a64(""), 0xcbf29ce484222325ULL);
  EXPECT_EQ(format::fnv1a64("a"), 0xaf63dc4c8601ec8cULL);
  EXPECT_EQ(format::fnv1a64("foobar"), 0x85944171f73967e8ULL);
}

TEST(Hash, Sha256OfTheCanonicalTextOfTheExportedStations) {
  const Design d = paper();
  const std::string h = design_hash(d, {});
  EXPECT_THAT(h, StartsWith("sha256:"));
  EXPECT_EQ(h.size(), 7u + 64u);
  EXPECT_EQ(h, "sha256:" + sha256_hex(to_yaml(export_view(d, {}))));
  EXPECT_EQ(design_hash(paper(), {}), h);  // deterministic
  // The view keeps every section but the four no exported byte reads.
  const Design v = export_view(d, {});
  EXPECT_TRUE(v.has<PrintSettings>() && v.has<MotorSettings>() && v.has<ContactSettings>() && v.has<ToleranceSettings>());
  EXPECT_FALSE(v.has<SweepSettings>() || v.has<OptimizeSettings>() || v.has<BenchSettings>() || v.products.has_value());

  const auto changed = [&](auto edit) {
    Design e = paper();
    edit(e);
    return design_hash(e, {});
  };
  EXPECT_NE(changed([](Design& e) { e.get<ControllerSettings>()->pid.kp = 5.5; }), h);
  EXPECT_NE(changed([](Design& e) { e.stations[0].lower->L[2] = 15.25; }), h);
  EXPECT_NE(changed([](Design& e) { e.get<PatternSettings>()->global[0].amplitude_mm = 2.5; }), h);
  EXPECT_NE(changed([](Design& e) { e.get<Geometry>()->min_clearance = 0.25; }), h);
  // Issue 39: the motor and the resin change the URDF and the MJCF, hence the hash.
  EXPECT_NE(changed([](Design& e) { e.get<MotorSettings>()->defaults.gear_ratio = 150.0; }), h);
  EXPECT_NE(changed([](Design& e) { e.get<PrintSettings>()->density_g_cm3 = 2.0; }), h);
  // Sweeping, optimising and the product list do not make a controller file stale.
  EXPECT_EQ(changed([](Design& e) { e.reset<SweepSettings>(); }), h);
  EXPECT_EQ(changed([](Design& e) { e.reset<OptimizeSettings>(); }), h);
  EXPECT_EQ(changed([](Design& e) { e.products = std::vector<std::string>{"export"}; }), h);
  // A one-station export hashes its station only: the thumb's gains do not touch it.
  const std::string index_only = design_hash(d, {"index"});
  EXPECT_NE(index_only, h);
  Design e = paper();
  ControlOverride o;
  o.station = "thumb", o.kp = 9.0;
  e.get<ControllerSettings>()->overrides.push_back(o);
  EXPECT_EQ(design_hash(e, {"index"}), index_only);
  EXPECT_NE(design_hash(e, {}), h);
}

/// Every byte `fivebar export` writes for the whole design but the gate's measured figures
/// (fivebar.validation, a function of the same design): the three controller formats and the URDF
/// and MJCF of every station, each with its design hash replaced by a placeholder.
std::string exported_bytes_without_hash(const Design& d) {
  const auto unstamped = [](std::string text, const std::string& hash) {
    for (std::size_t at = text.find(hash); at != std::string::npos; at = text.find(hash, at)) text.replace(at, hash.size(), "HASH");
    return text;
  };
  std::string out;
  const Json tree = controller_parameters(d, {});
  for (ExportFormat f : all_export_formats()) out += unstamped(render(f, tree), design_hash(d, {}));
  for (const Station& s : d.stations) {
    out += unstamped(render_urdf(d, s), design_hash(d, {s.name}));
    out += unstamped(render_mjcf(d, s), design_hash(d, {s.name}));
  }
  return out;
}

/// Every number of a YAML tree (its nodes, which share the tree's memory), with its path.
void yaml_numbers(YAML::Node node, const std::string& path, std::vector<std::pair<std::string, YAML::Node>>& out) {
  if (node.IsMap()) {
    for (auto e : node) yaml_numbers(e.second, path + (path.empty() ? "" : ".") + e.first.as<std::string>(), out);
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) yaml_numbers(node[i], path + "[" + std::to_string(i) + "]", out);
  } else if (node.IsScalar()) {
    double v = 0.0;
    if (node.Tag() != "!" && YAML::convert<double>::decode(node, v)) out.emplace_back(path, node);
  }
}

/// The first of a few perturbations of `v` that `load` accepts (integers and ranges refuse some).
template <class Load>
std::optional<Design> perturbed(double v, const Load& load) {
  for (double to : {v * (1.0 + 1e-3) + (v == 0.0 ? 1e-3 : 0.0), v + 1.0, v - 1.0, v * (1.0 - 1e-3), v + 0.5}) {
    try {
      return load(to);
    } catch (const std::exception&) {
    }
  }
  return std::nullopt;
}

// Issue 39 "a hash that covers what it certifies": every number of the showcase, perturbed one at a
// time; whenever an exported file changes (hash aside), the hash changes. Two walks: the numbers of
// the file itself, edited in the file's text as yaml-cpp reads it (independent of the design
// writer the hash is computed from), and every number the writer prints (defaults included,
// design_number_keys()), set through the design-edit API.
TEST(Hash, ChangesWheneverAnExportedFileChangesForEveryNumberOfTheShowcase) {
  const Design d = paper();
  const std::string bytes = exported_bytes_without_hash(d);
  const std::string hash = design_hash(d, {});
  int changed_files = 0, unchanged_files = 0;
  const auto check = [&](const std::string& key, const Design& e) {
    const bool files_change = exported_bytes_without_hash(e) != bytes;
    const bool hash_changes = design_hash(e, {}) != hash;
    (files_change ? changed_files : unchanged_files)++;
    if (files_change) EXPECT_TRUE(hash_changes) << key << ": an exported file changes, the hash does not";
    // What the view leaves out changes no exported byte.
    if (key.starts_with("sweep.") || key.starts_with("optimize.") || key.starts_with("bench.")) {
      EXPECT_FALSE(files_change) << key;
      EXPECT_FALSE(hash_changes) << key;
    }
  };

  const fs::path file = kSource / "designs" / "iros2022.yaml";
  YAML::Node root = YAML::LoadFile(file.string());
  std::vector<std::pair<std::string, YAML::Node>> in_file;
  yaml_numbers(root, "", in_file);
  ASSERT_GT(in_file.size(), 100u);
  for (auto& [key, node] : in_file) {
    const std::string text = node.Scalar();
    const auto e = perturbed(node.as<double>(), [&](double to) {
      node = format::shortest(to);
      YAML::Emitter out;
      out << root;
      node = text;
      Design loaded = load_design_from_string(std::string(out.c_str()) + "\n", "edited.yaml");
      loaded.source = d.source;  // bench files are named relative to the design's folder
      return loaded;
    });
    if (!e) {
      ADD_FAILURE() << key << " = " << text << ": no perturbation loads";
      continue;
    }
    check(key, *e);
  }
  const int from_file = changed_files + unchanged_files;

  const std::vector<std::string> keys = design_number_keys(d, "");
  for (const std::string& key : keys) {
    const auto e = perturbed(design_number(d, key), [&](double to) { return with_design_numbers(d, {{key, to}}); });
    if (!e) {
      ADD_FAILURE() << key << ": no perturbation loads";
      continue;
    }
    check(key, *e);
  }
  std::cout << from_file << " numbers of the file and " << keys.size() << " of the writer: " << changed_files
            << " perturbations change an exported file, " << unchanged_files << " do not\n";
  EXPECT_GT(changed_files, 100);
}


// --- The parameter tree against the design --------------------------------------------------------

TEST(Parameters, HoldThePapersDeviceInSiUnits) {
  const Design d = paper();
  const Json tree = controller_parameters(d, {});
  ASSERT_EQ(tree.size(), 1u);
  EXPECT_EQ(tree.begin().key(), "fivebar_controller");
  const Json& p = params_of(tree);
  EXPECT_EQ(p.at("fivebar").at("design"), "iros2022");
  EXPECT_EQ(p.at("fivebar").at("design_hash"), design_hash(d, {}));
  EXPECT_EQ(p.at("fivebar").at("tool_version"), std::string(version()));
  EXPECT_EQ(p.at("loop_rate_hz"), 100.0);
  EXPECT_TRUE(p.at("loop_rate_hz").is_number_float());
  EXPECT_EQ(p.at("pwm_hz"), 1000.0);
  EXPECT_EQ(p.at("adc").at("bits"), 16);
  EXPECT_TRUE(p.at("adc").at("bits").is_number_integer());
  EXPECT_EQ(p.at("adc").at("volts_per_count"), 20.0 / 65536.0);
  EXPECT_EQ(p.at("station_names"), Json({"index", "thumb"}));
  EXPECT_EQ(p.at("joint_names"), Json({"index_lower_theta1", "index_lower_theta2", "index_upper_theta1",
                                       "index_upper_theta2", "thumb_lower_theta1", "thumb_lower_theta2",
                                       "thumb_upper_theta1", "thumb_upper_theta2"}));
  // Table 1, in metres.
  const Json& index = p.at("stations").at("index");
  EXPECT_EQ(index.at("target").at("center_m"), Json({6.25 / 1000, 15.5 / 1000}));
  EXPECT_EQ(index.at("target").at("axes_m"), Json({15.0 / 1000, 12.0 / 1000}));
  EXPECT_EQ(index.at("upper").at("o1_m"), Json({0.0, 31.0 / 1000}));
  EXPECT_EQ(index.at("upper").at("o2_m"), Json({12.5 / 1000, 31.0 / 1000}));
  EXPECT_EQ(index.at("lower").at("link_lengths_m"), Json({0.009, 0.009, 0.015, 0.015}));
  EXPECT_EQ(p.at("stations").at("thumb").at("lower").at("link_lengths_m"), Json({0.009, 0.009, 0.0175, 0.0175}));
  EXPECT_EQ(index.at("lower").at("working_mode"), "-+");
  EXPECT_EQ(index.at("upper").at("working_mode"), "+-");
  EXPECT_EQ(index.at("upper").at("assembly_mode"), "-");
  // The showcase: limits from the hardware (below the boss of O1 at 180 deg + acos(212.25 / 225),
  // above the potentiometer's end: 3.25 V at 0 deg, 60 deg/V over 0 ... 5 V); 343.5 deg/s; pots 5 V
  // over 300 deg; mid-travel offsets.
  const Json& lim = p.at("joint_limits").at("thumb_upper_theta2");
  EXPECT_EQ(lim.at("has_position_limits"), true);
  EXPECT_NEAR(lim.at("min_position").get<double>(), -kPi + std::acos(212.25 / 225.0), 1e-12);
  EXPECT_NEAR(lim.at("max_position").get<double>(), deg(105), 1e-12);
  EXPECT_EQ(lim.at("has_velocity_limits"), true);
  // The one joint speed: below the controller's 360 deg/s, the assumed motor's steady speed at 6 V
  // less its friction, (eta N k_t V / R - tau_c) / (eta N^2 k_t k_e / R + b) from motor: typed here.
  const double ke_out = 0.5236e-3 * 60.0 / (2.0 * kPi) * 200.0;  // back_emf_mV_per_rpm 0.5236: V s/rad at the output
  const double free_speed = (0.7 * 200.0 * 0.005 * 6.0 / 5.0 - 0.5e-3) / (0.7 * 200.0 * 0.005 * ke_out / 5.0 + 0.01e-3);
  EXPECT_NEAR(lim.at("max_velocity").get<double>(), free_speed, 1e-12 * free_speed);
  // Gains: the station-mechanism scope of the tuned gains (controller.stations.index.lower.pid) over the
  // section's pid, whose i_clamp 0.2 it keeps.
  EXPECT_EQ(p.at("gains").at("index_lower_theta1"),
            Json({{"p", 6.376473352297236}, {"i", 62.44954783058385}, {"d", 0.11315351641304752}, {"i_clamp", 0.2}}));
  EXPECT_EQ(p.at("gains").at("index_lower_theta2"), p.at("gains").at("index_lower_theta1"));
  EXPECT_NE(p.at("gains").at("thumb_upper_theta1"), p.at("gains").at("index_lower_theta1"));
  EXPECT_DOUBLE_EQ(p.at("potentiometers").at("index_lower_theta1").at("rad_per_volt").get<double>(), deg(60));
  EXPECT_EQ(p.at("potentiometers").at("index_lower_theta1").at("volts_at_zero"), 0.25);
  EXPECT_EQ(p.at("potentiometers").at("thumb_upper_theta1").at("volts_at_zero"), 4.75);
  EXPECT_EQ(p.at("collision").at("priority"), "upper");
  EXPECT_EQ(p.at("collision").at("min_clearance_m"), 0.3 / 1000);
  EXPECT_EQ(p.at("collision").at("layers"), Json({0, 0, 1, 1}));
}

TEST(Parameters, OneStationAndJointLimitsOnTheCentresBranch) {
  Design d = paper();
  // Limits that hold over the index ellipse (its lower theta1 spans about 82 ... 180 deg). The
  // upper's are given from -200 deg: on the branch of its centre angle (about -135 deg) they stay
  // [-200, -60] deg rather than [160, 300].
  d.stations[0].lower->joint_limits = std::array<JointRange, 2>{JointRange{deg(60), deg(200)}, JointRange{deg(-30), deg(120)}};
  d.stations[0].upper->joint_limits = std::array<JointRange, 2>{JointRange{deg(-200), deg(-60)}, JointRange{deg(-120), deg(30)}};
  d.validate();
  const Json tree = controller_parameters(d, {"index"});
  const Json& p = params_of(tree);
  EXPECT_EQ(p.at("station_names"), Json({"index"}));
  EXPECT_FALSE(p.at("stations").contains("thumb"));
  EXPECT_FALSE(p.at("joint_limits").contains("thumb_lower_theta1"));
  const Json& l1 = p.at("joint_limits").at("index_lower_theta1");
  EXPECT_EQ(l1.at("has_position_limits"), true);
  EXPECT_NEAR(l1.at("min_position").get<double>(), deg(60), 1e-12);
  EXPECT_NEAR(l1.at("max_position").get<double>(), deg(200), 1e-12);
  const Json& u1 = p.at("joint_limits").at("index_upper_theta1");
  EXPECT_NEAR(u1.at("min_position").get<double>(), deg(-200), 1e-12);
  EXPECT_NEAR(u1.at("max_position").get<double>(), deg(-60), 1e-12);
  // The centre's angle is on the exported arc.
  const Pose c = ik(*d.stations[0].upper, d.stations[0].target.center);
  EXPECT_GT(c.theta1, u1.at("min_position").get<double>());
  EXPECT_LT(c.theta1, u1.at("max_position").get<double>());

  const ExportGate gate = export_gate(d, {.stations = {"index"}});
  EXPECT_TRUE(gate.passed()) << ::testing::PrintToString(gate.reasons());
  EXPECT_EQ(gate.stations, std::vector<std::string>{"index"});
}

// --- Every format read back --------------------------------------------------------------------------

/// Walks a yaml-cpp tree beside the parameter tree: same keys, same values, and every double
/// written with a '.' (ROS declares these parameters double).
void expect_yaml_matches(const YAML::Node& y, const Json& j, const std::string& path, int& doubles) {
  SCOPED_TRACE(path);
  if (j.is_object()) {
    ASSERT_TRUE(y.IsMap());
    EXPECT_EQ(y.size(), j.size());
    for (const auto& [key, value] : j.items()) {
      ASSERT_TRUE(y[key]) << key;
      expect_yaml_matches(y[key], value, path + "." + key, doubles);
    }
    return;
  }
  if (j.is_array()) {
    ASSERT_TRUE(y.IsSequence());
    ASSERT_EQ(y.size(), j.size());
    for (std::size_t i = 0; i < j.size(); ++i) expect_yaml_matches(y[i], j[i], path + "[" + std::to_string(i) + "]", doubles);
    return;
  }
  ASSERT_TRUE(y.IsScalar());
  const std::string text = y.Scalar();
  if (j.is_number_float()) {
    ++doubles;
    EXPECT_NE(text.find('.'), std::string::npos) << "double written as " << text;
    EXPECT_EQ(y.as<double>(), j.get<double>());
  } else if (j.is_number_integer()) {
    EXPECT_EQ(text.find_first_of(".e"), std::string::npos) << "integer written as " << text;
    EXPECT_EQ(y.as<long long>(), j.get<long long>());
  } else if (j.is_boolean()) {
    EXPECT_EQ(y.as<bool>(), j.get<bool>());
  } else {
    EXPECT_EQ(y.Tag(), "!") << "strings are quoted";
    EXPECT_EQ(text, j.get<std::string>());
  }
}

TEST(Formats, RosYamlReadByYamlCppEqualsTheDesign) {
  const Design d = paper();
  const Json tree = controller_parameters(d, {});
  const std::string text = render_ros2_yaml(tree);
  const YAML::Node y = YAML::Load(text);
  int doubles = 0;
  expect_yaml_matches(y, tree, "", doubles);
  EXPECT_GT(doubles, 100);
  // The values a controller reads, by path, against Table 1 and the showcase.
  const YAML::Node p = y["fivebar_controller"]["ros__parameters"];
  EXPECT_EQ(p["stations"]["thumb"]["upper"]["o1_m"][1].as<double>(), 35.0 / 1000);
  EXPECT_EQ(p["stations"]["index"]["lower"]["link_lengths_m"][2].as<double>(), 15.0 / 1000);
  EXPECT_EQ(p["gains"]["thumb_upper_theta2"]["d"].as<double>(), d.get<ControllerSettings>()->joint("thumb", "upper", 2).pid.kd);
  EXPECT_NE(p["gains"]["thumb_upper_theta2"]["d"].as<double>(), d.get<ControllerSettings>()->pid.kd);  // the tuned scope
  EXPECT_EQ(p["pwm_hz"].Scalar(), "1000.0");
  EXPECT_EQ(p["adc"]["bits"].Scalar(), "16");
  EXPECT_EQ(p["fivebar"]["design_hash"].as<std::string>(), design_hash(d, {}));
  // Our own reader gives the same tree, kinds included.
  const Json back = parse_export(ExportFormat::ros2, text, "<yaml>");
  EXPECT_EQ(back, tree);
}

TEST(Formats, RosYamlKeysAreStringsInYaml11) {
  // docs/reliability.md: a station named `on`, `yes` or `off` became a YAML 1.1 boolean key of the
  // ROS 2 parameters file (ROS 2's parser is YAML 1.1). Reference: the YAML 1.1 type regexps
  // (yaml.org/type/bool.html, null.html, int.html, float.html): no unquoted key may match them.
  Design d = paper();
  d.stations[0].name = "on";
  d.stations[1].name = "Yes";
  const std::string text = render_ros2_yaml(controller_parameters(d, {}));
  static const std::regex yaml11(
      "y|Y|yes|Yes|YES|n|N|no|No|NO|true|True|TRUE|false|False|FALSE|on|On|ON|off|Off|OFF|~|null|Null|NULL|"
      "[-+]?[0-9][0-9_.eE+-]*|[-+]?\\.(inf|Inf|INF|nan|NaN|NAN)");
  std::istringstream lines(text);
  std::string line;
  int quoted = 0;
  while (std::getline(lines, line)) {
    if (line.starts_with("#")) continue;
    const auto first = line.find_first_not_of(' ');
    const auto colon = line.find(':', first);
    if (first == std::string::npos || colon == std::string::npos) continue;
    const std::string key = line.substr(first, colon - first);
    EXPECT_FALSE(std::regex_match(key, yaml11)) << "unquoted YAML 1.1 non-string key: " << line;
    if (key == "\"on\"" || key == "\"Yes\"") ++quoted;
  }
  EXPECT_GE(quoted, 2);
  // Read back, the keys are the station names.
  const Json back = parse_export(ExportFormat::ros2, text, "<yaml>");
  const Json& stations = back["fivebar_controller"]["ros__parameters"]["stations"];
  EXPECT_TRUE(stations.contains("on"));
  EXPECT_TRUE(stations.contains("Yes"));
}

TEST(Formats, KeysYaml11ReadsAsBooleansOrNullAreQuoted) {
  // A station named `on` (an identifier, so the gate allows it): YAML 1.1 readers (ROS 2's
  // libyaml-based parser, PyYAML) take a plain `on:` key for the boolean true.
  Design d = paper();
  d.stations[0].name = "on";
  for (auto& o : d.get<ControllerSettings>()->overrides) {
    if (o.station == "index") o.station = "on";
  }
  for (auto& o : d.get<PatternSettings>()->overrides) {
    if (o.station == "index") o.station = "on";
  }
  Json tree = controller_parameters(d, {});
  // And every other spelling of a YAML 1.1 boolean or null as a key, in a scratch map.
  const std::vector<std::string> special{"on", "On", "ON", "off", "Off", "yes", "Yes", "no", "NO", "y", "Y", "n", "N",
                                         "true", "False", "null", "Null", "NULL", "~"};
  Json scratch = Json::object();
  for (const std::string& k : special) scratch[k] = 1.5;
  scratch["online"] = 2.5;  // not special: stays plain
  tree.begin().value()["ros__parameters"]["scratch"] = scratch;
  const std::string text = render_ros2_yaml(tree);
  EXPECT_THAT(text, HasSubstr("\n      \"on\":\n"));      // stations."on"
  EXPECT_THAT(text, HasSubstr("\n      \"~\": 1.5\n"));
  EXPECT_THAT(text, HasSubstr("\n      online: 2.5\n"));
  for (const std::string& k : special) EXPECT_THAT(text, HasSubstr("\"" + k + "\": 1.5")) << k;
  EXPECT_EQ(parse_export(ExportFormat::ros2, text, "<yaml>"), tree);
  // PyYAML, a YAML 1.1 reader, keeps every key a string (python3-yaml, .ci/setup.sh).
  const fs::path file = fs::temp_directory_path() / ("fivebar_yaml11_" + std::to_string(::getpid()) + ".yaml");
  {
    std::ofstream out(file);
    out << text;
  }
  const std::string script =
      "import sys, yaml\n"
      "p = yaml.safe_load(open(sys.argv[1]))['fivebar_controller']['ros__parameters']\n"
      "bad = [k for k in list(p['stations']) + list(p['scratch']) if not isinstance(k, str)]\n"
      "sys.exit(1 if bad or 'on' not in p['stations'] or 'on_lower_theta1' not in p['gains'] else 0)\n";
  const fs::path py = file.string() + ".py";
  {
    std::ofstream out(py);
    out << script;
  }
  const int rc = std::system(("/usr/bin/python3 " + py.string() + " " + file.string()).c_str());
  fs::remove(file);
  fs::remove(py);
  EXPECT_EQ(rc, 0) << "PyYAML read a key as a non-string";
}

TEST(Formats, EveryDoubleLineOfTheYamlHasAPointOrExponent) {
  // Line by line, independent of any YAML reader: a numeric scalar is an integer only for the
  // integer parameters (format_version, adc.bits, layers).
  const std::string text = render_ros2_yaml(controller_parameters(paper(), {}));
  std::istringstream lines(text);
  std::string line;
  int numeric = 0;
  while (std::getline(lines, line)) {
    if (line.starts_with("#")) continue;
    const auto colon = line.find(": ");
    if (colon == std::string::npos) continue;
    const std::string key = line.substr(line.find_first_not_of(' '), colon - line.find_first_not_of(' '));
    std::string value = line.substr(colon + 2);
    if (value.front() == '[') value = value.substr(1, value.size() - 2);
    std::istringstream items(value);
    std::string item;
    while (std::getline(items, item, ',')) {
      item.erase(0, item.find_first_not_of(' '));
      if (item.empty() || !(std::isdigit(static_cast<unsigned char>(item[0])) || item[0] == '-')) continue;
      ++numeric;
      const bool integer_key = key == "format_version" || key == "bits" || key == "layers";
      if (integer_key) {
        EXPECT_EQ(item.find_first_of(".e"), std::string::npos) << line;
      } else {
        EXPECT_NE(item.find('.'), std::string::npos) << line;
      }
    }
  }
  EXPECT_GT(numeric, 100);
}

TEST(Formats, JsonReadByNlohmannEqualsTheTree) {
  const Json tree = controller_parameters(paper(), {});
  const std::string text = render_json(tree);
  const nlohmann::json plain = nlohmann::json::parse(text);  // an independent (unordered) reader
  EXPECT_EQ(plain.at("fivebar_controller").at("ros__parameters").at("stations").at("index").at("upper").at("o1_m")[1],
            31.0 / 1000);
  EXPECT_TRUE(plain.at("fivebar_controller").at("ros__parameters").at("pwm_hz").is_number_float());
  EXPECT_TRUE(plain.at("fivebar_controller").at("ros__parameters").at("adc").at("bits").is_number_integer());
  EXPECT_THAT(text, HasSubstr("\"loop_rate_hz\": 100.0"));
  EXPECT_EQ(parse_export(ExportFormat::json, text, "<json>"), tree);
}

TEST(Formats, HeaderReadsBackAndDeclaresEveryValue) {
  const Json tree = controller_parameters(paper(), {});
  const std::string text = render_header(tree);
  EXPECT_THAT(text, HasSubstr("#pragma once"));
  EXPECT_THAT(text, HasSubstr("namespace fivebar_controller {"));
  EXPECT_THAT(text, HasSubstr("inline constexpr double pwm_hz = 1000.0;"));
  EXPECT_THAT(text, HasSubstr("inline constexpr long long bits = 16;"));
  EXPECT_THAT(text, HasSubstr("inline constexpr double link_lengths_m[4] = {0.009, 0.009, 0.015, 0.015};"));
  EXPECT_THAT(text, HasSubstr("inline constexpr char working_mode[] = \"-+\";"));
  EXPECT_EQ(parse_export(ExportFormat::header, text, "<hpp>"), tree);
}

TEST(Formats, RefuseWhatRosCannotHold) {
  Json tree = controller_parameters(paper(), {});
  Json bad = tree;
  bad.begin().value()["ros__parameters"]["pwm_hz"] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(render_ros2_yaml(bad), std::logic_error);
  EXPECT_THROW(render_header(bad), std::logic_error);
  bad = tree;
  bad.begin().value()["ros__parameters"]["station_names"] = Json::array();
  EXPECT_THROW(render_ros2_yaml(bad), std::logic_error);
  bad = tree;
  bad.begin().value()["ros__parameters"]["adc"]["range_v"] = Json::array({1.0, 2});
  EXPECT_THROW(render_ros2_yaml(bad), std::logic_error);
}

TEST(Formats, DetectedByExtensionOrContent) {
  EXPECT_EQ(detect_export_format("a/b.yaml", ""), ExportFormat::ros2);
  EXPECT_EQ(detect_export_format("a/b.YML", ""), ExportFormat::ros2);
  EXPECT_EQ(detect_export_format("b.json", ""), ExportFormat::json);
  EXPECT_EQ(detect_export_format("b.hpp", ""), ExportFormat::header);
  EXPECT_EQ(detect_export_format("b.txt", "  {\"a\": 1}"), ExportFormat::json);
  EXPECT_EQ(detect_export_format("b", "// x\n#pragma once"), ExportFormat::header);
  EXPECT_EQ(detect_export_format("b", "node:\n  ros__parameters: {}"), ExportFormat::ros2);
  for (ExportFormat f : all_export_formats()) EXPECT_EQ(parse_export_format(to_string(f)), f);
  EXPECT_FALSE(parse_export_format("yaml").has_value());
}

// --- The gate -----------------------------------------------------------------------------------------

std::vector<std::string> failed_kinds(const ExportGate& g) {
  std::vector<std::string> out;
  for (const GateCheck& c : g.checks) {
    if (!c.passed) out.push_back(c.subject + " " + c.kind);
  }
  return out;
}

TEST(Gate, ThePapersDevicePassesEveryCheck) {
  const ExportGate g = export_gate(paper());
  EXPECT_TRUE(g.passed()) << ::testing::PrintToString(g.reasons());
  EXPECT_THAT(g.reasons(), IsEmpty());
  std::vector<std::string> kinds;
  for (const GateCheck& c : g.checks) kinds.push_back(c.subject + " " + c.kind);
  for (const char* expected : {"design names", "design geometry", "index/lower coverage", "index/upper singularity",
                               "index/shared coverage", "thumb/lower joint_limits", "thumb/upper calibration",
                               "index stretch pattern", "thumb pivot pattern"}) {
    EXPECT_THAT(kinds, Contains(std::string(expected)));
  }
  // The patterns are checked against the one joint speed (JointSpeed below), not the controller's 360 deg/s.
  const std::string limit = "(limit " + format::fixed(motor_free_speed(paper().get<MotorSettings>()->defaults) * 180.0 / kPi, 1) + ")";
  EXPECT_EQ(limit, "(limit 343.5)");
  for (const GateCheck& c : g.checks) {
    if (c.kind == "pattern") EXPECT_THAT(c.detail, HasSubstr(limit)) << c.subject;
  }
  // Joint ranges over the index ellipse, against an independent boundary walk with ik().
  const Design d = paper();  // owned here: a Station reference into a temporary would dangle
  const Station& s = d.stations[0];
  double lo = 1e9, hi = -1e9;
  for (int k = 0; k < 3600; ++k) {
    const Pose p = ik(*s.lower, s.target.boundary_point(2.0 * kPi * k / 3600));
    ASSERT_EQ(p.status, Status::ok);
    const double t = p.theta1 < 0 ? p.theta1 + 2 * kPi : p.theta1;  // lower theta1 stays in (0, 2 pi)
    lo = std::min(lo, t), hi = std::max(hi, t);
  }
  const auto it = std::find_if(g.joints.begin(), g.joints.end(), [](const JointSweep& j) { return j.name == "index_lower_theta1"; });
  ASSERT_NE(it, g.joints.end());
  EXPECT_NEAR(it->lo, lo, 1e-3);
  EXPECT_NEAR(it->hi, hi, 1e-3);
}

// Issue 39 "one joint speed": the motor's steady speed at full duty against a bisection of its
// torque balance (a second formulation, with the driver's current limit), and that one number in
// the three controller formats and the URDF of every station.
TEST(JointSpeed, OneValueFromTheMotorInEveryExportedFile) {
  const Design d = paper();
  const MotorParams p = d.get<MotorSettings>()->defaults;
  const auto balance = [](const MotorParams& q, double w) {
    const double i = std::min((q.supply_voltage_V - q.back_emf_constant() * q.gear_ratio * w) / q.resistance(), q.current_limit_A);
    return q.gearbox_efficiency * q.gear_ratio * q.torque_constant() * i - q.viscous_friction() * w - q.coulomb_friction();
  };
  const auto bisect = [&](const MotorParams& q) {
    if (balance(q, 0.0) <= 0.0) return 0.0;
    double lo = 0.0, hi = q.supply_voltage_V / (q.back_emf_constant() * q.gear_ratio);
    for (int k = 0; k < 200; ++k) (balance(q, 0.5 * (lo + hi)) > 0.0 ? lo : hi) = 0.5 * (lo + hi);
    return 0.5 * (lo + hi);
  };
  const double no_load = p.supply_voltage_V / (p.back_emf_constant() * p.gear_ratio);
  EXPECT_NEAR(motor_free_speed(p), bisect(p), 1e-12);
  EXPECT_LT(motor_free_speed(p), no_load);
  EXPECT_NEAR(no_load * 180.0 / kPi, 343.77, 0.01);  // V / (k_e N): 6 V, 5 mV s/rad, 200
  EXPECT_NEAR(motor_free_speed(p) * 180.0 / kPi, 343.5, 0.05);
  MotorParams limited = p;  // a driver limit that binds before the speed settles
  limited.terminal_resistance_ohm = 0.05;
  limited.viscous_friction_mNm_s_per_rad = 100.0;
  limited.current_limit_A = 0.2;
  EXPECT_NEAR(motor_free_speed(limited), bisect(limited), 1e-9);
  EXPECT_NEAR(motor_free_speed(limited), (0.7 * 0.2 - 0.0005) / 0.1, 1e-12);
  limited.coulomb_friction_mNm = 1e6;  // friction holds it at rest
  EXPECT_EQ(motor_free_speed(limited), 0.0);

  const double v = std::min(d.get<ControllerSettings>()->max_velocity, motor_free_speed(p));
  EXPECT_EQ(station_joint_speed_limit(d, *d.station("index")), v);
  const Json tree = controller_parameters(d, {});
  for (ExportFormat f : all_export_formats()) {
    const Json back = parse_export(f, render(f, tree), "f");
    ASSERT_EQ(params_of(back).at("joint_limits").size(), 8u);
    for (const auto& [joint, lim] : params_of(back).at("joint_limits").items()) {
      EXPECT_EQ(lim.at("max_velocity").get<double>(), v) << to_string(f) << " " << joint;
    }
  }
  for (const Station& s : d.stations) {
    const std::string urdf = render_urdf(d, s);
    const std::regex velocity("velocity=\"([^\"]+)\"");
    int found = 0;
    for (auto it = std::sregex_iterator(urdf.begin(), urdf.end(), velocity); it != std::sregex_iterator(); ++it, ++found) {
      EXPECT_EQ(std::strtod((*it)[1].str().c_str(), nullptr), v) << s.name;
    }
    EXPECT_EQ(found, 4) << s.name;  // the four motor joints
  }
}

TEST(Gate, SingularityThresholdAgainstTheLciAtTheEllipsesBottom) {
  // The minimum over the ellipse can be no larger than the LCI at any of its points.
  Design d = paper();
  const Station& s = d.stations[0];
  const Pose bottom = ik(*s.lower, s.target.center - Vec2(0.0, s.target.axes.y() / 2));
  ASSERT_EQ(bottom.status, Status::ok);
  d.get<ControllerSettings>()->min_lci = std::min(1.0, bottom.lci + 0.01);
  const ExportGate g = export_gate(d, {.stations = {"index"}});
  EXPECT_FALSE(g.passed());
  EXPECT_THAT(failed_kinds(g), Contains(std::string("index/lower singularity")));
  EXPECT_THAT(g.reasons(), Contains(AllOf(StartsWith("index/lower singularity: min LCI over the ellipse"),
                                          HasSubstr("below"))));
  d.get<ControllerSettings>()->min_lci = 0.0;
  d.stations[0].lower->min_lci = 0.3;  // a mechanism's own threshold counts too (0.362 > 0.3)
  EXPECT_TRUE(export_gate(d, {.stations = {"index"}}).passed());
}

TEST(Gate, JointLimitsThatCutTheEllipseFailWithTheWorstAngle) {
  Design d = paper();
  d.stations[0].lower->joint_limits = std::array<JointRange, 2>{JointRange{deg(60), deg(150)}, JointRange{deg(-30), deg(120)}};
  d.validate();
  const ExportGate g = export_gate(d, {.stations = {"index"}});
  EXPECT_FALSE(g.passed());
  const auto failed = failed_kinds(g);
  EXPECT_THAT(failed, Contains(std::string("index/lower joint_limits")));
  EXPECT_THAT(failed, Contains(std::string("index/lower coverage")));  // the joint-limited region misses it too
  EXPECT_THAT(failed, Not(Contains(std::string("index/upper joint_limits"))));
  // The boundary needs theta1 up to about 179.9 deg (independent walk in the previous test).
  EXPECT_THAT(g.reasons(), Contains(AllOf(HasSubstr("index/lower joint_limits"), HasSubstr("worst: theta1 = 179."),
                                          HasSubstr("outside [60.00, 150.00] deg"))));
}

TEST(Gate, EveryFailureIsListedAtOnce) {
  Design d = paper();
  d.stations[1].target.axes = Vec2(40.0, 40.0);  // the thumb cannot cover this
  ControlOverride o;
  o.station = "index", o.mechanism = "lower", o.joint = 1, o.volts_at_zero = 9.0;  // 180 deg reads 12 V
  d.get<ControllerSettings>()->overrides.push_back(o);
  PatternSpec twist;  // index twist beyond the ~5.3 mm where L3 meets the upper's tactor joint
  twist.kind = PatternKind::twist, twist.amplitude_mm = 7.0, twist.separation_mm = 8.0;
  d.get<PatternSettings>()->overrides.emplace_back("index", twist);
  d.validate();
  const ExportGate g = export_gate(d);
  const auto failed = failed_kinds(g);
  EXPECT_THAT(failed, Contains(std::string("thumb/lower coverage")));
  EXPECT_THAT(failed, Contains(std::string("thumb/upper coverage")));
  EXPECT_THAT(failed, Contains(std::string("thumb/shared coverage")));
  EXPECT_THAT(failed, Contains(std::string("index/lower calibration")));
  EXPECT_THAT(failed, Contains(std::string("index twist pattern")));
  EXPECT_THAT(failed, Not(Contains(std::string("index/lower coverage"))));
  EXPECT_THAT(g.reasons(), Contains(AllOf(HasSubstr("index/lower calibration"), HasSubstr("OUTSIDE"))));
  EXPECT_EQ(g.reasons().size(), failed.size());
}

TEST(Gate, NamesMustBeIdentifiersInEveryFormat) {
  Design d = paper();
  d.stations[0].name = "int";
  d.reset<SweepSettings>();
  d.reset<OptimizeSettings>();
  d.get<ControllerSettings>()->node = "linux";
  for (auto& o : d.get<ControllerSettings>()->overrides) {
    if (o.station == "index") o.station = "int";
  }
  for (auto& o : d.get<PatternSettings>()->overrides) {
    if (o.station == "index") o.station = "int";
  }
  d.validate();
  const ExportGate g = export_gate(d);
  EXPECT_THAT(failed_kinds(g), Contains(std::string("design names")));
  EXPECT_THAT(g.reasons(), Contains(AllOf(HasSubstr("station 'int' is a C++ keyword"), HasSubstr("controller.node 'linux'"))));
  d.stations[0].name = "a__b";
  EXPECT_THAT(export_gate(d, {.stations = {"a__b"}}).reasons(), Contains(HasSubstr("must not contain \"__\"")));
}

TEST(Gate, NeedsTheControllerSectionAndGeometry) {
  Design d = paper();
  d.reset<ControllerSettings>();
  EXPECT_THAT([&] { export_gate(d); }, ThrowsMessage<InputError>(HasSubstr("has no controller: section")));
  d = paper();
  EXPECT_THAT([&] { export_gate(d, {.stations = {"pinky"}}); },
              ThrowsMessage<InputError>(HasSubstr("unknown station 'pinky'")));
  d.reset<Geometry>();
  const ExportGate g = export_gate(d);
  EXPECT_THAT(failed_kinds(g), Contains(std::string("design geometry")));
  EXPECT_THAT(failed_kinds(g), Contains(std::string("index stretch pattern")));
}

// --- Writing ------------------------------------------------------------------------------------------

class ExportFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    std::random_device rd;
    dir_ = fs::temp_directory_path() / ("fivebar_test_export_" + std::to_string(::getpid()) + "_" + std::to_string(rd()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

Design failing() {
  Design d = paper();
  d.get<ControllerSettings>()->min_lci = 0.99;  // no five-bar is that well conditioned over a 15 mm ellipse
  return d;
}

TEST_F(ExportFiles, AllFormatsWrittenAndReadBackEqual) {
  const Design d = paper();
  const ExportResult r = export_controller(d, all_export_formats(), dir_ / "out");
  ASSERT_TRUE(r.gate.passed());
  ASSERT_EQ(r.files.size(), 3u);
  EXPECT_EQ(r.files[0], dir_ / "out" / "iros2022_controller.yaml");
  EXPECT_EQ(r.files[1], dir_ / "out" / "iros2022_controller.json");
  EXPECT_EQ(r.files[2], dir_ / "out" / "iros2022_controller.hpp");
  for (std::size_t i = 0; i < 3; ++i) {
    const ExportFormat f = all_export_formats()[i];
    EXPECT_EQ(parse_export(f, slurp(r.files[i]), r.files[i].string()), r.parameters) << to_string(f);
    const ExportCheck c = check_export_file(r.files[i], d);
    EXPECT_TRUE(c.matches()) << to_string(f);
    EXPECT_TRUE(c.hash_matches());
    EXPECT_EQ(c.format, to_string(f));
  }
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir_ / "out")) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"iros2022_controller.hpp", "iros2022_controller.json",
                                             "iros2022_controller.yaml"}));  // no temporaries left
  const ExportResult one = export_controller(d, {ExportFormat::json}, dir_ / "one", {.stations = {"thumb"}});
  ASSERT_EQ(one.files.size(), 1u);
  EXPECT_EQ(one.files[0].filename(), "iros2022_controller_thumb.json");
}

TEST_F(ExportFiles, AFailingGateCreatesNothing) {
  const ExportResult r = export_controller(failing(), all_export_formats(), dir_ / "absent" / "export");
  EXPECT_FALSE(r.gate.passed());
  EXPECT_THAT(r.files, IsEmpty());
  EXPECT_TRUE(r.parameters.is_null());
  EXPECT_FALSE(fs::exists(dir_ / "absent"));
}

TEST_F(ExportFiles, AFailingGateLeavesAnEarlierExportUntouched) {
  const fs::path out = dir_ / "out";
  const ExportResult good = export_controller(paper(), all_export_formats(), out);
  ASSERT_EQ(good.files.size(), 3u);
  std::vector<std::string> before;
  std::vector<fs::file_time_type> times;
  for (const auto& f : good.files) before.push_back(slurp(f)), times.push_back(fs::last_write_time(f));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  const ExportResult bad = export_controller(failing(), all_export_formats(), out);
  EXPECT_FALSE(bad.gate.passed());
  for (std::size_t i = 0; i < good.files.size(); ++i) {
    EXPECT_EQ(slurp(good.files[i]), before[i]);
    EXPECT_EQ(fs::last_write_time(good.files[i]), times[i]);
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(out), fs::directory_iterator{}), 3);
}

TEST_F(ExportFiles, AnUnreplaceableTargetWritesNothing) {
  const fs::path out = dir_ / "out";
  fs::create_directories(out / "iros2022_controller.json");  // a directory where the JSON goes
  EXPECT_THROW(export_controller(paper(), all_export_formats(), out), IoError);
  EXPECT_FALSE(fs::exists(out / "iros2022_controller.yaml"));
  EXPECT_FALSE(fs::exists(out / "iros2022_controller.hpp"));
  EXPECT_EQ(std::distance(fs::directory_iterator(out), fs::directory_iterator{}), 1);
}

// --- --check ------------------------------------------------------------------------------------------

std::string replace_once(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

TEST(Check, FindsAChangedValueInEveryFormat) {
  const Design d = paper();
  const Json tree = controller_parameters(d, {});
  const std::string yaml = replace_once(render_ros2_yaml(tree), "volts_at_zero: 4.75", "volts_at_zero: 4.7");
  const ExportCheck y = check_export(yaml, ExportFormat::ros2, d, "f.yaml");
  EXPECT_TRUE(y.hash_matches());
  ASSERT_EQ(y.differences.size(), 1u);
  EXPECT_EQ(y.differences[0].path, "fivebar_controller.ros__parameters.potentiometers.index_upper_theta1.volts_at_zero");
  EXPECT_EQ(y.differences[0].expected, "4.75");
  EXPECT_EQ(y.differences[0].found, "4.7");

  const std::string json = replace_once(render_json(tree), "\"pwm_hz\": 1000.0", "\"pwm_hz\": 1000.5");
  const ExportCheck j = check_export(json, ExportFormat::json, d, "f.json");
  ASSERT_EQ(j.differences.size(), 1u);
  EXPECT_EQ(j.differences[0].path, "fivebar_controller.ros__parameters.pwm_hz");

  const std::string header =
      replace_once(render_header(tree), "link_lengths_m[4] = {0.009, 0.009, 0.015, 0.015}", "link_lengths_m[4] = {0.009, 0.009, 0.015, 0.016}");
  const ExportCheck h = check_export(header, ExportFormat::header, d, "f.hpp");
  ASSERT_EQ(h.differences.size(), 1u);
  EXPECT_EQ(h.differences[0].path, "fivebar_controller.ros__parameters.stations.index.lower.link_lengths_m[3]");
}

TEST(Check, AnIntegerWhereADoubleIsDeclaredIsADifference) {
  const Design d = paper();
  const std::string yaml = replace_once(render_ros2_yaml(controller_parameters(d, {})), "loop_rate_hz: 100.0", "loop_rate_hz: 100");
  const ExportCheck c = check_export(yaml, ExportFormat::ros2, d, "f.yaml");
  ASSERT_EQ(c.differences.size(), 1u);
  EXPECT_EQ(c.differences[0].expected, "100.0 (double)");
  EXPECT_EQ(c.differences[0].found, "100 (integer)");
}

TEST(Check, AStaleFileIsReportedByHashAndValue) {
  const std::string yaml = render_ros2_yaml(controller_parameters(paper(), {}));
  Design changed = paper();
  // kd of every joint: the section's and that of each scope giving one (the showcase's tuned
  // controller.stations.<s>.<m> scopes, which every joint runs).
  changed.get<ControllerSettings>()->pid.kd = 0.06;
  for (ControlOverride& o : changed.get<ControllerSettings>()->overrides) {
    if (o.kd) *o.kd += 0.01;
  }
  const ExportCheck c = check_export(yaml, ExportFormat::ros2, changed, "f.yaml");
  EXPECT_FALSE(c.hash_matches());
  EXPECT_FALSE(c.matches());
  EXPECT_EQ(c.file_hash, design_hash(paper(), {}));
  EXPECT_EQ(c.design_hash, design_hash(changed, {}));
  std::vector<std::string> paths;
  for (const auto& diff : c.differences) paths.push_back(diff.path);
  EXPECT_THAT(paths, Contains(std::string("fivebar_controller.ros__parameters.fivebar.design_hash")));
  EXPECT_THAT(paths, Contains(std::string("fivebar_controller.ros__parameters.gains.thumb_lower_theta1.d")));
  EXPECT_EQ(c.differences.size(), 1u + 8u);  // the hash and kd of every joint
  // A one-station file is compared with that station's export.
  const std::string index = render_json(controller_parameters(paper(), {"index"}));
  EXPECT_TRUE(check_export(index, ExportFormat::json, paper(), "i.json").matches());
}

// Issue 39: --check reads every format export writes, and a changed motor value is named.
TEST(Check, EveryFormatExportWritesRoundTripsAndAChangedGearRatioIsNamed) {
  const Design d = paper();
  Design geared = paper();
  geared.get<MotorSettings>()->defaults.gear_ratio = 150.0;
  const Json tree = controller_parameters(d, {});
  for (ExportFormat f : all_export_formats()) {
    const ExportCheck same = check_export(render(f, tree), f, d, "f");
    EXPECT_TRUE(same.matches()) << to_string(f);
    const ExportCheck stale = check_export(render(f, tree), f, geared, "f");
    ASSERT_FALSE(stale.matches()) << to_string(f);
    EXPECT_EQ(stale.differences.front().path, "fivebar_controller.ros__parameters.fivebar.design_hash");
  }
  const auto paths = [](const ExportCheck& c) {
    std::vector<std::string> out;
    for (const ExportDifference& x : c.differences) out.push_back(x.path + " = " + x.found + " (design " + x.expected + ")");
    return out;
  };
  for (const Station& s : d.stations) {
    const std::string urdf = render_urdf(d, s), mjcf = render_mjcf(d, s);
    const ExportCheck u = check_robot_export(urdf, d, "f.urdf");
    EXPECT_EQ(u.format, "urdf");
    EXPECT_EQ(u.stations, std::vector<std::string>{s.name});
    EXPECT_EQ(u.file_hash, design_hash(d, {s.name}));
    EXPECT_TRUE(u.matches()) << ::testing::PrintToString(paths(u));
    const ExportCheck x = check_robot_export(mjcf, d, "f.xml");
    EXPECT_EQ(x.format, "mjcf");
    EXPECT_TRUE(x.matches()) << ::testing::PrintToString(paths(x));

    const ExportCheck ug = check_robot_export(urdf, geared, "f.urdf");
    ASSERT_FALSE(ug.matches());
    EXPECT_EQ(ug.differences.front().path, "(stamp) design hash");
    const std::string joint = s.name + "_lower_theta1";
    EXPECT_THAT(paths(ug), Contains(HasSubstr("mechanicalReduction[#0]#text = 200 (design 150)")));
    const ExportCheck xg = check_robot_export(mjcf, geared, "f.xml");
    ASSERT_FALSE(xg.matches());
    EXPECT_THAT(paths(xg), Contains(HasSubstr("joint[" + joint + "]@armature")));
  }
  // A value changed in the file is named with its key; the hash alone still matches.
  const Station& index = *d.station("index");
  std::string urdf = render_urdf(d, index);
  const std::string from = "<mechanicalReduction>200</mechanicalReduction>";
  ASSERT_NE(urdf.find(from), std::string::npos);
  urdf.replace(urdf.find(from), from.size(), "<mechanicalReduction>100</mechanicalReduction>");
  const ExportCheck edited = check_robot_export(urdf, d, "f.urdf");
  EXPECT_TRUE(edited.hash_matches());
  ASSERT_EQ(edited.differences.size(), 1u);
  EXPECT_EQ(edited.differences[0].expected, "200");
  EXPECT_EQ(edited.differences[0].found, "100");
  EXPECT_THAT(edited.differences[0].path, AllOf(StartsWith("robot/transmission["), HasSubstr("mechanicalReduction")));
  EXPECT_THAT([&] { check_robot_export("<robot><link name=\"a\"></robot>", d, "x.urdf"); },
              ThrowsMessage<InputError>(StartsWith("x.urdf:1: not an XML document fivebar export writes")));
  EXPECT_THAT([&] { check_robot_export("<robot/>", d, "x.urdf"); },
              ThrowsMessage<InputError>(HasSubstr("no comment \"Generated by fivebar")));
}

TEST(Check, MissingAndExtraKeysAndForeignFiles) {
  const Design d = paper();
  std::string yaml = render_ros2_yaml(controller_parameters(d, {}));
  yaml = replace_once(yaml, "    pwm_hz: 1000.0\n", "    pwm: 1000.0\n");
  const ExportCheck c = check_export(yaml, ExportFormat::ros2, d, "f.yaml");
  ASSERT_EQ(c.differences.size(), 2u);
  EXPECT_EQ(c.differences[0].found, "(absent)");
  EXPECT_EQ(c.differences[1].expected, "(absent)");
  EXPECT_THAT([&] { check_export("a: 1\nb: 2\n", ExportFormat::ros2, d, "x.yaml"); },
              ThrowsMessage<InputError>(HasSubstr("x.yaml: not a fivebar controller export")));
  EXPECT_THAT([&] { check_export("{\"n\": {\"ros__parameters\": {}}}", ExportFormat::json, d, "x.json"); },
              ThrowsMessage<InputError>(HasSubstr("no fivebar: block")));
  EXPECT_THAT([&] { check_export("{\"n\": [1,", ExportFormat::json, d, "x.json"); },
              ThrowsMessage<InputError>(StartsWith("x.json:1: not valid JSON")));
  EXPECT_THAT([&] { check_export("namespace n {\nint x = 1;\n}\n", ExportFormat::header, d, "x.hpp"); },
              ThrowsMessage<InputError>(StartsWith("x.hpp:2: not a line fivebar export writes")));
  EXPECT_THAT([&] { check_export("a: [1,\n", ExportFormat::ros2, d, "x.yaml"); },
              ThrowsMessage<InputError>(HasSubstr("YAML syntax error")));
}

}  // namespace
}  // namespace fivebar
