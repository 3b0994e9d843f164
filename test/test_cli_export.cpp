// End-to-end tests of `fivebar export`, `fivebar export --check` and the `export` product of
// `fivebar run`: real processes, their output, the files they write (or do not write) and their
// exit codes. Expected values come from the paper (Table 1, Sec. II-D) and the showcase's
// controller section, typed here.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cli_test.hpp"

namespace {

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using ft::slurp;
using nlohmann::json;
using ::testing::AllOf;
using ::testing::Contains;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::Not;

std::vector<std::string> listing(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

/// The paper's design and a scratch directory per test, the binary's working directory so that a
/// default outputs/ would land there (test/cli_test.hpp).
class CliExport : public ft::CliTest {
 protected:
  CliExport() : CliTest("fivebar_test_cli_export") {}
};

TEST_F(CliExport, WritesTheThreeFormatsWhichCheckAgainstTheDesign) {
  const Outcome r = run({"export", kDesign, "--out", "ctl"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, AllOf(HasSubstr("export of design iros2022 for node fivebar_controller"),
                           HasSubstr("design hash sha256:"), HasSubstr("index/lower"), HasSubstr("thumb pivot")));
  EXPECT_THAT(r.out, Not(HasSubstr("FAILED")));
  EXPECT_EQ(listing(dir_ / "ctl"), (std::vector<std::string>{"iros2022_controller.hpp", "iros2022_controller.json",
                                                             "iros2022_controller.yaml", "iros2022_index",
                                                             "iros2022_index.urdf", "iros2022_thumb",
                                                             "iros2022_thumb.urdf"}));
  // The MuJoCo bundle of a station (fivebar/export/mjcf.hpp), laid out as MuJoCo Menagerie's models.
  EXPECT_EQ(listing(dir_ / "ctl" / "iros2022_index"),
            (std::vector<std::string>{"LICENSE", "README.md", "iros2022_index.xml", "iros2022_index_position.xml",
                                      "preview.svg", "scene.xml", "scene_position.xml"}));
  // The ROS file with yaml-cpp: the paper's numbers in SI units, doubles as doubles.
  const YAML::Node p = YAML::LoadFile((dir_ / "ctl" / "iros2022_controller.yaml").string())["fivebar_controller"]["ros__parameters"];
  EXPECT_EQ(p["loop_rate_hz"].Scalar(), "100.0");
  EXPECT_EQ(p["pwm_hz"].Scalar(), "1000.0");
  EXPECT_EQ(p["adc"]["bits"].Scalar(), "16");
  EXPECT_EQ(p["stations"]["thumb"]["lower"]["link_lengths_m"][3].as<double>(), 0.0175);
  // The usable range from the hardware: the potentiometer's end (4.75 V at 0 deg, 60 deg/V, 300 deg
  // of travel: -285 deg) and the boss of the other motor (acos(212.25 / 225) = 19.38 deg from 180).
  EXPECT_EQ(p["joint_limits"]["index_upper_theta1"]["has_position_limits"].as<bool>(), true);
  EXPECT_NEAR(p["joint_limits"]["index_upper_theta1"]["min_position"].as<double>(), -285.0 * std::numbers::pi / 180, 1e-12);
  EXPECT_NEAR(p["joint_limits"]["index_upper_theta1"]["max_position"].as<double>(), -std::acos(212.25 / 225.0), 1e-12);
  // The motor's steady speed at 6 V less friction (343.5 deg/s), below the controller's 360 deg/s.
  EXPECT_NEAR(p["joint_limits"]["index_upper_theta1"]["max_velocity"].as<double>() * 180.0 / std::numbers::pi, 343.5, 0.05);
  // The tuned gains of the showcase's controller.stations.index.upper scope, in shortest round-trip form.
  EXPECT_EQ(p["gains"]["index_upper_theta1"]["p"].Scalar(), "6.376242079532782");
  EXPECT_EQ(p["collision"]["priority"].as<std::string>(), "upper");
  // The JSON with nlohmann: the same values.
  const json j = json::parse(slurp(dir_ / "ctl" / "iros2022_controller.json"))["fivebar_controller"]["ros__parameters"];
  EXPECT_EQ(j["stations"]["thumb"]["lower"]["link_lengths_m"][3], 0.0175);
  EXPECT_EQ(j["fivebar"]["design_hash"], p["fivebar"]["design_hash"].as<std::string>());

  // Every file export writes reads back through --check (issue 39), the URDF and MJCF included: the
  // files at the top and each MuJoCo bundle's model (<design>_<station>/<design>_<station>.xml).
  std::vector<std::string> checked;
  for (const std::string& file : listing(dir_ / "ctl")) {
    checked.push_back(fs::is_directory(dir_ / "ctl" / file) ? file + "/" + file + ".xml" : file);
  }
  for (const std::string& file : checked) {
    const Outcome c = run({"export", "--check", (dir_ / "ctl" / file).string(), kDesign});
    EXPECT_EQ(c.code, 0) << file << "\n" << c.out << c.err;
    EXPECT_THAT(c.out, AllOf(HasSubstr("the file matches the design"), HasSubstr("(same)")));
  }
  // A changed motor value: every file is stale, and the URDF names the gearing's key.
  const fs::path geared = design_with("geared.yaml", "  gear_ratio: 200", "  gear_ratio: 150");
  for (const std::string& file : checked) {
    const Outcome c = run({"export", "--check", (dir_ / "ctl" / file).string(), geared.string()});
    EXPECT_EQ(c.code, 1) << file << "\n" << c.out << c.err;
    EXPECT_THAT(c.out, HasSubstr("STALE")) << file;
  }
  const Outcome u = run({"export", "--check", (dir_ / "ctl" / "iros2022_index.urdf").string(), geared.string(), "--json"});
  EXPECT_EQ(u.code, 1);
  const json doc = parse(u);
  EXPECT_EQ(doc["format"], "urdf");
  std::vector<std::string> paths;
  for (const auto& d : doc["differences"]) paths.push_back(d["path"].get<std::string>() + ": " + d["expected"].get<std::string>() + " / " + d["found"].get<std::string>());
  EXPECT_THAT(paths, Contains(std::string("robot/transmission[index_lower_theta1_transmission]/actuator[index_lower_theta1_motor]/"
                                          "mechanicalReduction[#0]#text: 150 / 200")));
}

TEST_F(CliExport, JsonOutputAndOneFormatForOneStation) {
  const Outcome r = run({"export", kDesign, "--station", "index", "--format", "header", "--out", "h", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json doc = parse(r);
  EXPECT_EQ(doc["command"], "export");
  EXPECT_EQ(doc["exported"], true);
  EXPECT_EQ(doc["node"], "fivebar_controller");
  EXPECT_EQ(doc["gate"]["passed"], true);
  EXPECT_EQ(doc["gate"]["stations"], json({"index"}));
  ASSERT_EQ(doc["files"].size(), 1u);
  EXPECT_EQ(doc["files"][0], "h/iros2022_controller_index.hpp");
  const std::string header = slurp(dir_ / "h" / "iros2022_controller_index.hpp");
  EXPECT_THAT(header, AllOf(HasSubstr("namespace index {"), HasSubstr("inline constexpr double loop_rate_hz = 100.0;"),
                            Not(HasSubstr("thumb"))));
  EXPECT_THAT(header, HasSubstr(doc["design_hash"].get<std::string>()));
  // Every gate check is listed with its verdict.
  std::vector<std::string> kinds;
  for (const auto& c : doc["gate"]["checks"]) kinds.push_back(c["kind"].get<std::string>() + " " + c["subject"].get<std::string>());
  for (const char* k : {"coverage index/lower", "singularity index/upper", "joint_limits index/lower",
                        "calibration index/upper", "coverage index/shared", "pattern index twist"}) {
    EXPECT_THAT(kinds, Contains(std::string(k)));
  }
}

TEST_F(CliExport, ARefusedExportWritesNothingAndListsEveryReason) {
  // Above the paper's worst LCI (0.36) and a potentiometer offset that reads 180 deg as 12 V.
  fs::path bad = design_with("bad.yaml", "  min_lci: 0.05", "  min_lci: 0.5");
  std::string text = slurp(bad);
  text.replace(text.find("volts_at_zero: 0.25"), 19, "volts_at_zero: 9.00");
  std::ofstream(bad) << text;

  const Outcome r = run({"export", bad.string(), "--out", "refused/export"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("refused, nothing written"), HasSubstr("index/lower singularity"),
                           HasSubstr("thumb/upper singularity"), HasSubstr("index/lower calibration")));
  EXPECT_THAT(r.out, HasSubstr("FAILED"));
  EXPECT_FALSE(fs::exists(dir_ / "refused"));

  // Without --out the default outputs/<name>/export is not created either.
  const Outcome d = run({"export", bad.string(), "--json"});
  EXPECT_EQ(d.code, 1);
  const json doc = parse(d);
  EXPECT_EQ(doc["exported"], false);
  EXPECT_THAT(doc["files"], IsEmpty());
  EXPECT_GE(doc["gate"]["reasons"].size(), 5u);  // four mechanisms below the LCI threshold, one calibration
  EXPECT_FALSE(fs::exists(dir_ / "outputs"));

  // An earlier export in the same place is left as it was.
  ASSERT_EQ(run({"export", kDesign, "--out", "kept"}).code, 0);
  const std::string before = slurp(dir_ / "kept" / "iros2022_controller.yaml");
  EXPECT_EQ(run({"export", bad.string(), "--out", "kept"}).code, 1);
  EXPECT_EQ(slurp(dir_ / "kept" / "iros2022_controller.yaml"), before);
  EXPECT_EQ(listing(dir_ / "kept").size(), 7u);  // three formats, two URDFs and two MuJoCo bundles
}

TEST_F(CliExport, FormatMjcfWritesOnlyTheMujocoBundle) {
  const Outcome r = run({"export", kDesign, "--station", "index", "--format", "mjcf", "--out", "m"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(listing(dir_ / "m"), (std::vector<std::string>{"iros2022_index"}));
  EXPECT_THAT(slurp(dir_ / "m" / "iros2022_index" / "iros2022_index.xml"),
              AllOf(HasSubstr("<mujoco model=\"iros2022_index\">"), HasSubstr("<connect name=\"index_lower_loop\""),
                    HasSubstr("armature=\"0.002\""), HasSubstr("<general name=\"index_upper_theta2\"")));
}

TEST_F(CliExport, Ros2PackageWritesTheDescriptionPackageAlone) {
  const Outcome r = run({"export", kDesign, "--ros2-package", "pkg"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(listing(dir_ / "pkg"), (std::vector<std::string>{"CMakeLists.txt", "README.md", "config", "launch", "package.xml",
                                                             "urdf"}));
  EXPECT_EQ(listing(dir_ / "pkg" / "urdf"), (std::vector<std::string>{"iros2022_index.urdf", "iros2022_thumb.urdf"}));
  EXPECT_EQ(listing(dir_ / "pkg" / "config"),
            (std::vector<std::string>{"iros2022_controller.yaml", "ros2_controllers.yaml"}));
  // Without the parts' renders there are no meshes: CMakeLists installs only the folders there are.
  EXPECT_THAT(slurp(dir_ / "pkg" / "CMakeLists.txt"), HasSubstr("install(DIRECTORY urdf config launch DESTINATION"));
  EXPECT_THAT(slurp(dir_ / "pkg" / "urdf" / "iros2022_index.urdf"), HasSubstr("<link name=\"world\"/>"));
  // The parameters file in it checks against the design as any exported one.
  EXPECT_EQ(run({"export", "--check", (dir_ / "pkg" / "config" / "iros2022_controller.yaml").string(), kDesign}).code, 0);
  // It writes the package alone: --out and --format do not apply (usage, exit 2, nothing written).
  EXPECT_EQ(run({"export", kDesign, "--ros2-package", "p2", "--out", "x"}).code, 2);
  EXPECT_EQ(run({"export", kDesign, "--ros2-package", "p3", "--format", "urdf"}).code, 2);
  EXPECT_FALSE(fs::exists(dir_ / "p2"));
  EXPECT_FALSE(fs::exists(dir_ / "x"));
}

TEST_F(CliExport, BadInputIsExitTwo) {
  const fs::path no_controller = (kSource / "designs" / "iros2022-index.yaml");
  const Outcome a = run({"export", no_controller.string(), "--out", "x"});
  EXPECT_EQ(a.code, 2);
  EXPECT_THAT(a.err, HasSubstr("has no controller: section"));
  EXPECT_EQ(run({"export", kDesign, "--format", "yaml"}).code, 2);
  const Outcome s = run({"export", kDesign, "--station", "pinky"});
  EXPECT_EQ(s.code, 2);
  EXPECT_THAT(s.err, HasSubstr("unknown station 'pinky'"));
  EXPECT_EQ(run({"export", "--check", "nowhere.yaml", kDesign}).code, 2);
  EXPECT_EQ(run({"export", "--check", "nowhere.yaml", kDesign, "--format", "json"}).code, 2);
  const fs::path broken = design_with("broken.yaml", "  pwm_hz: 1000", "  pwm_hz: 10");
  const Outcome b = run({"export", broken.string()});
  EXPECT_EQ(b.code, 2);
  EXPECT_THAT(b.err, HasSubstr("controller.pwm_hz = 10 Hz: must be >= loop_rate_hz (100 Hz)"));
  EXPECT_FALSE(fs::exists(dir_ / "x"));
  EXPECT_FALSE(fs::exists(dir_ / "outputs"));
}

TEST_F(CliExport, CheckFindsAChangedValueAndAStaleHash) {
  ASSERT_EQ(run({"export", kDesign, "--out", "c"}).code, 0);
  const fs::path yaml = dir_ / "c" / "iros2022_controller.yaml";
  std::string text = slurp(yaml);
  const auto at = text.find("      i_clamp: 0.2\n");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 19, "      i_clamp: 0.25\n");
  const fs::path edited = dir_ / "edited.yaml";
  std::ofstream(edited) << text;
  const Outcome e = run({"export", "--check", edited.string(), kDesign});
  EXPECT_EQ(e.code, 1);
  EXPECT_THAT(e.out, AllOf(HasSubstr("1 difference(s)"),
                           HasSubstr("fivebar_controller.ros__parameters.gains.index_lower_theta1.i_clamp: design 0.2, file 0.25"),
                           HasSubstr("(same)")));
  EXPECT_THAT(e.err, HasSubstr("does not match design iros2022"));

  // The design moves on: the exported header is stale.
  const fs::path newer = design_with("newer.yaml", "  pwm_hz: 1000", "  pwm_hz: 2000");
  const Outcome s = run({"export", "--check", (dir_ / "c" / "iros2022_controller.hpp").string(), newer.string(), "--json"});
  EXPECT_EQ(s.code, 1);
  const json doc = parse(s);
  EXPECT_EQ(doc["matches"], false);
  EXPECT_EQ(doc["hash_matches"], false);
  EXPECT_EQ(doc["format"], "header");
  std::vector<std::string> paths;
  for (const auto& d : doc["differences"]) paths.push_back(d["path"]);
  EXPECT_THAT(paths, Contains(std::string("fivebar_controller.ros__parameters.pwm_hz")));
  EXPECT_THAT(paths, Contains(std::string("fivebar_controller.ros__parameters.fivebar.design_hash")));
  const Outcome text_out = run({"export", "--check", (dir_ / "c" / "iros2022_controller.json").string(), newer.string()});
  EXPECT_THAT(text_out.out, HasSubstr("STALE"));
}

TEST_F(CliExport, RunBuildsTheExportProduct) {
  const Outcome r = run({"run", kDesign, "--products", "export", "--out", "scene", "--json", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json doc = parse(r);
  EXPECT_EQ(doc["results"]["export"]["exported"], true);
  EXPECT_EQ(doc["results"]["export"]["files"],
            json({"export/iros2022_controller.yaml", "export/iros2022_controller.json", "export/iros2022_controller.hpp",
                  "export/iros2022_index.urdf", "export/iros2022_thumb.urdf", "export/iros2022_index/iros2022_index.xml",
                  "export/iros2022_index/iros2022_index_position.xml", "export/iros2022_index/scene.xml",
                  "export/iros2022_index/scene_position.xml", "export/iros2022_index/preview.svg",
                  "export/iros2022_index/LICENSE", "export/iros2022_index/README.md",
                  "export/iros2022_thumb/iros2022_thumb.xml", "export/iros2022_thumb/iros2022_thumb_position.xml",
                  "export/iros2022_thumb/scene.xml", "export/iros2022_thumb/scene_position.xml",
                  "export/iros2022_thumb/preview.svg", "export/iros2022_thumb/LICENSE", "export/iros2022_thumb/README.md"}));
  EXPECT_EQ(listing(dir_ / "scene" / "iros2022" / "export").size(), 7u);
  EXPECT_EQ(run({"export", "--check", (dir_ / "scene" / "iros2022" / "export" / "iros2022_controller.json").string(), kDesign}).code, 0);
  EXPECT_THAT(slurp(dir_ / "scene" / "iros2022" / "summary.md"), AllOf(HasSubstr("## Controller export (`export`)"),
                                                                       HasSubstr("Files:")));
  // The report links the MJCF beside the URDF (summary.md, and the HTML page rendered from it).
  EXPECT_THAT(slurp(dir_ / "scene" / "iros2022" / "summary.md"),
              HasSubstr("[`export/iros2022_index/iros2022_index.xml`](export/iros2022_index/iros2022_index.xml)"));
  EXPECT_THAT(slurp(dir_ / "scene" / "iros2022" / "index.html"),
              HasSubstr("href=\"export/iros2022_index/iros2022_index.xml\""));

  // A refused export fails the scene and writes no export/ folder.
  const fs::path bad = design_with("bad.yaml", "  min_lci: 0.05", "  min_lci: 0.5");
  const Outcome f = run({"run", bad.string(), "--products", "export", "--out", "failing", "--quiet"});
  EXPECT_EQ(f.code, 1);
  EXPECT_FALSE(fs::exists(dir_ / "failing" / "iros2022" / "export"));
  EXPECT_THAT(slurp(dir_ / "failing" / "iros2022" / "summary.md"), HasSubstr("**Export refused**: no file written."));

  // A design without a controller section cannot have the product: asked for, it is missing.
  const Outcome n = run({"run", (kSource / "designs" / "iros2022-index.yaml").string(), "--products",
                         "kinematics,export", "--out", "none", "--json", "--quiet"});
  EXPECT_EQ(n.code, 1) << n.err;
  const json none = parse(n);
  EXPECT_EQ(none["missing"], json({"export"}));
  bool found = false;
  for (const auto& l : none["left_out"]) {
    if (l["name"] != "export") continue;
    found = true;
    EXPECT_THAT(l["reason"].get<std::string>(), HasSubstr("no `controller:` section"));
  }
  EXPECT_TRUE(found);
}

}  // namespace
