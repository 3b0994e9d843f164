// The repository's own documents (docs/): the design-file reference cannot drift from the loader,
// and no file of the repository cites a document that is not in it.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "design/design_keys.hpp"
#include "fivebar/design.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/contact.hpp"
#include "fivebar/sections/motor.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/patterns.hpp"
#include "fivebar/sections/print.hpp"
#include "fivebar/sections/sweep.hpp"
#include "fivebar/sections/tolerance.hpp"

namespace fivebar {
namespace {

namespace fs = std::filesystem;
const fs::path kSource = FIVEBAR_SOURCE_DIR;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Key shapes in the first column of the tables of docs/design-file.md: "| `key` | ...".
std::set<std::string> documented_keys() {
  std::set<std::string> keys;
  std::istringstream in(slurp(kSource / "docs" / "design-file.md"));
  const std::regex row(R"(^\|\s*`([^`]+)`\s*\|)");
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (!std::regex_search(line, m, row)) continue;
    std::string key = m[1];  // a '|' inside a table cell is written "\|"
    for (std::size_t at; (at = key.find("\\|")) != std::string::npos;) key.erase(at, 1);
    keys.insert(key);
  }
  return keys;
}

/// A key shape as docs/design-file.md writes it: maps of the same keys under several names share
/// one row (`stations.<name>.mechanisms.<lower|upper>.links`, `patterns.<stretch|slip|twist>`,
/// `controller.<scope>.pid.kp` for every override scope).
std::string documented_form(std::string key) {
  static const std::vector<std::pair<std::regex, std::string>> rules = {
      {std::regex(R"(^(stations\.<name>\.mechanisms\.)(lower|upper))"), "$1<lower|upper>"},
      {std::regex(R"(^patterns\.stations\.<name>\.(stretch|slip|twist|pivot)(\..*)?$)"), "patterns.stations.<name>.<kind>"},
      {std::regex(R"(^patterns\.(stretch|slip|twist)\b)"), "patterns.<stretch|slip|twist>"},
      {std::regex(R"(^controller\.mechanisms\.(lower|upper)(\.theta[12])?(?=\.|$))"), "controller.<scope>"},
      {std::regex(R"(^controller\.stations\.<name>(\.(lower|upper)(\.theta[12])?)?(?=\.|$))"), "controller.<scope>"},
      {std::regex(R"(^motor\.mechanisms\.(lower|upper)(\.theta[12])?(?=\.|$))"), "motor.<scope>"},
      {std::regex(R"(^motor\.stations\.<name>(\.(lower|upper)(\.theta[12])?)?(?=\.|$))"), "motor.<scope>"},
  };
  for (const auto& [from, to] : rules) key = std::regex_replace(key, from, to);
  return key;
}

const fs::path kEveryKey = kSource / "test" / "data" / "every_key.yaml";

TEST(DesignFileDoc, FixtureIsAValidDesignWithEverySection) {
  Design d;
  ASSERT_NO_THROW(d = load_design(kEveryKey));
  EXPECT_TRUE(d.get<Geometry>() && d.get<PrintSettings>() && d.get<SweepSettings>() && d.get<PatternSettings>() &&
              d.get<ControllerSettings>() && d.get<ToleranceSettings>());
  ASSERT_EQ(d.stations.size(), 1u);
  for (const Mechanism* m : d.stations[0].mechanisms()) {
    EXPECT_TRUE(m->joint_limits.has_value()) << m->name;
    EXPECT_GT(m->min_lci, 0.0) << m->name;
  }
  EXPECT_EQ(d.stations[0].mechanisms().size(), 2u);
  EXPECT_EQ(d.get<PatternSettings>()->global.size(), 4u);
  EXPECT_EQ(d.get<PatternSettings>()->overrides.size(), 4u);
  // Every override scope once: mechanisms.<m>, mechanisms.<m>.theta<j> (6), stations.<s>, its
  // mechanisms and their joints (7).
  EXPECT_EQ(d.get<ControllerSettings>()->overrides.size(), 13u);
  ASSERT_TRUE(d.get<MotorSettings>() && d.get<ContactSettings>());
  EXPECT_EQ(d.get<MotorSettings>()->overrides.size(), 13u);
}

TEST(DesignFileDoc, FixtureVisitsEveryMap) {
  // One key of every map the loader has, in the exact shape design_file_keys() gives it: a map the
  // fixture misses would leave its keys unchecked against the document.
  std::vector<std::string> maps{"name", "geometry.min_clearance", "print.fn", "sweep.collision_spacing_mm",
                                "sweep.vary.<name>", "stations.<name>.target.angle", "patterns.max_joint_speed_deg_s",
                                "controller.adc.range_v", "controller.pid.i_clamp",
                                "controller.potentiometer.volts_per_rad", "tolerance.seed"};
  for (const char* m : {"lower", "upper"}) {
    maps.push_back("stations.<name>.mechanisms." + std::string(m) + ".min_lci");
  }
  for (const char* kind : {"stretch", "slip", "twist", "pivot"}) {
    maps.push_back("patterns." + std::string(kind) + ".duration_s");
    maps.push_back("patterns.stations.<name>." + std::string(kind) + ".duration_s");
  }
  std::vector<std::string> scopes{"stations.<name>"};
  for (const char* m : {"lower", "upper"}) {
    for (const std::string& parent : {std::string("mechanisms."), std::string("stations.<name>.")}) {
      scopes.push_back(parent + m);
      scopes.push_back(parent + m + ".theta1");
      scopes.push_back(parent + m + ".theta2");
    }
  }
  for (const std::string& scope : scopes) {
    maps.push_back("controller." + scope + ".pid.kp");
    maps.push_back("controller." + scope + ".potentiometer.volts_per_rad");
    maps.push_back("motor." + scope + ".gear_ratio");
  }
  maps.push_back("motor.current_limit_A");
  maps.push_back("contact.normal_preload_N");
  const std::set<std::string> keys = detail::design_file_keys(slurp(kEveryKey));
  for (const std::string& key : maps) EXPECT_TRUE(keys.count(key)) << "test/data/every_key.yaml does not visit " << key;
}

TEST(DesignFileDoc, EveryKeyTheLoaderAcceptsIsDocumentedAndNoOther) {
  const std::string fixture = slurp(kEveryKey);
  ASSERT_NO_THROW((void)load_design_from_string(fixture, "every_key.yaml"));
  std::set<std::string> accepted;
  for (const std::string& key : detail::design_file_keys(fixture)) accepted.insert(documented_form(key));
  const std::set<std::string> documented = documented_keys();
  ASSERT_GT(accepted.size(), 60u);  // the fixture visits every map
  for (const std::string& key : accepted) {
    EXPECT_TRUE(documented.count(key)) << "docs/design-file.md does not document `" << key << "`";
  }
  for (const std::string& key : documented) {
    EXPECT_TRUE(accepted.count(key)) << "docs/design-file.md documents `" << key << "`, which the loader does not accept";
  }
}

/// Text files of the repository: every file under its source folders, and the files at the root.
std::vector<fs::path> repository_files() {
  std::vector<fs::path> files;
  for (const char* top : {"lib", "cli", "test", "designs", "scad", "docs", ".ci"}) {
    if (!fs::exists(kSource / top)) continue;
    for (const auto& e : fs::recursive_directory_iterator(kSource / top)) {
      if (e.is_regular_file()) files.push_back(e.path());
    }
  }
  // outputs/ holds generated files besides its README: only the README is the repository's.
  for (const char* top : {"README.md", "CMakeLists.txt", "run.sh", "test.sh", "outputs/README.md", "CHANGELOG.md",
                          "CITATION.cff", "setup.py", "pyproject.toml"}) {
    files.push_back(kSource / top);
  }
  return files;
}

TEST(RepositoryDocs, EveryCitedDocumentIsInTheRepository) {
  // A name ending in .md (or a path under docs/ or paper/) must resolve inside the repository:
  // relative to the root, to docs/, or to the citing file's folder.
  const std::regex cited(
      R"(([A-Za-z0-9_./-]*[A-Za-z0-9_-]+\.md)\b|\b((?:paper|docs)/[A-Za-z0-9_./-]*[A-Za-z0-9_-]))");
  for (const fs::path& file : repository_files()) {
    const std::string ext = file.extension().string();
    if (ext == ".png" || ext == ".stl" || ext == ".svg") continue;
    if (file.filename() == "test_docs.cpp") continue;  // this file names examples in its comments
    std::istringstream in(slurp(file));
    int n = 0;
    for (std::string line; std::getline(in, line);) {
      ++n;
      for (std::sregex_iterator it(line.begin(), line.end(), cited), end; it != end; ++it) {
        const std::string name = (*it)[1].matched ? (*it)[1].str() : (*it)[2].str();
        // The names of files fivebar writes, not citations: summary.md, and the README.md of an exported
        // MuJoCo bundle (export/<design>_<station>/README.md, fivebar/export/mjcf.hpp).
        if (name.ends_with("summary.md")) continue;
        if (name.ends_with("/README.md") && name.find("export/") != std::string::npos) continue;
        const bool found = fs::exists(kSource / name) || fs::exists(kSource / "docs" / name) ||
                           fs::exists(file.parent_path() / name);
        EXPECT_TRUE(found) << fs::relative(file, kSource).string() << ":" << n << " cites " << name
                           << ", which is not in the repository";
      }
    }
  }
}

TEST(RepositoryDocs, OneVersionForCMakeCitationAndChangelog) {
  // CMakeLists.txt's project(VERSION) is the version; CITATION.cff repeats it, CHANGELOG.md has a
  // section for it, and setup.py reads it from CMakeLists.txt rather than writing its own.
  std::smatch m;
  const std::string cmake = slurp(kSource / "CMakeLists.txt");
  ASSERT_TRUE(std::regex_search(cmake, m, std::regex(R"(project\(fivebar VERSION ([0-9]+\.[0-9]+\.[0-9]+))")));
  const std::string version = m[1];
  const std::string citation = slurp(kSource / "CITATION.cff");
  ASSERT_TRUE(std::regex_search(citation, m, std::regex(R"((?:^|\n)version: ([^\n]+))")));
  EXPECT_EQ(m[1].str(), version) << "CITATION.cff";
  EXPECT_THAT(slurp(kSource / "CHANGELOG.md"), ::testing::HasSubstr("\n## [" + version + "]")) << "CHANGELOG.md";
  const std::string setup = slurp(kSource / "setup.py");
  EXPECT_THAT(setup, ::testing::HasSubstr("version=project_version()"));
  EXPECT_FALSE(std::regex_search(slurp(kSource / "pyproject.toml"), std::regex(R"((?:^|\n)version\s*=)")))
      << "pyproject.toml must not state a version of its own";
}

TEST(RepositoryDocs, ReadmeStaysShort) {
  // A newcomer reads it to the end (the long tour is docs/tour.md, still run by docs_examples).
  const std::string readme = slurp(kSource / "README.md");
  EXPECT_LE(std::count(readme.begin(), readme.end(), '\n'), 400);
}

TEST(RepositoryDocs, LicenceIsNamedWhereUsersLook) {
  // The licence text, its SPDX name in CITATION.cff, and the README saying which it is.
  EXPECT_THAT(slurp(kSource / "LICENSE"), ::testing::StartsWith("BSD 3-Clause License"));
  EXPECT_THAT(slurp(kSource / "CITATION.cff"), ::testing::HasSubstr("license: BSD-3-Clause"));
  EXPECT_THAT(slurp(kSource / "README.md"), ::testing::HasSubstr("BSD-3-Clause"));
  // The paper is the preferred citation, with its DOI.
  EXPECT_THAT(slurp(kSource / "CITATION.cff"),
              ::testing::AllOf(::testing::HasSubstr("preferred-citation:"),
                               ::testing::HasSubstr("Cutaneous Feedback Interface for Teleoperated In-Hand Manipulation"),
                               ::testing::HasSubstr("doi: 10.1109/IROS47612.2022.9982247")));
}

}  // namespace
}  // namespace fivebar
