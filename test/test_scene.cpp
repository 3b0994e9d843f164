// The scene runner (fivebar/scene.hpp) and its product registry (lib/src/products).

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "fivebar/error.hpp"
#include "fivebar/scene.hpp"
#include "products/product.hpp"

namespace fivebar {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

const fs::path kDesign = fs::path(FIVEBAR_SOURCE_DIR) / "designs" / "iros2022.yaml";

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class Scene : public ::testing::Test {
 protected:
  void SetUp() override {
    std::random_device rd;
    root_ = fs::temp_directory_path() / ("fivebar_test_scene_" + std::to_string(::getpid()) + "_" + std::to_string(rd()));
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(root_, ec);
  }
  SceneOptions options() const {
    SceneOptions o;
    o.out_root = root_;
    return o;
  }
  fs::path root_;
};

TEST(Registry, EveryEntryIsAKnownProductOnce) {
  const auto& known = known_products();
  std::set<std::string> seen;
  for (const auto& p : products::registry()) {
    EXPECT_TRUE(std::find(known.begin(), known.end(), p.name) != known.end()) << p.name;
    EXPECT_TRUE(seen.insert(p.name).second) << "duplicate " << p.name;
    EXPECT_FALSE(p.title.empty()) << p.name;
    EXPECT_TRUE(p.build) << p.name;
    for (const auto& pre : p.prerequisites) {
      // Prerequisites come earlier in the build order.
      const auto at = std::find(known.begin(), known.end(), pre);
      EXPECT_TRUE(at < std::find(known.begin(), known.end(), p.name)) << p.name << " needs " << pre;
    }
  }
  EXPECT_NE(products::find_product("kinematics"), nullptr);
  EXPECT_EQ(products::find_product("teleport"), nullptr);
}

TEST_F(Scene, BuildsEveryAvailableProductAndWritesBothSummaries) {
  const Design d = load_design(kDesign);
  std::vector<std::string> progress;
  SceneOptions o = options();
  o.progress = [&](std::string_view line) { progress.emplace_back(line); };
  const SceneReport r = run_scene(d, o);

  EXPECT_TRUE(r.ok());
  EXPECT_FALSE(r.products_listed);
  EXPECT_EQ(r.out_dir, root_ / "iros2022");
  ASSERT_EQ(r.products.size(), known_products().size());
  for (std::size_t i = 0; i < r.products.size(); ++i) {
    const auto& p = r.products[i];
    EXPECT_EQ(p.name, known_products()[i]);
    if (p.state == ProductOutcome::State::left_out) {
      EXPECT_FALSE(p.reason.empty()) << p.name << " left out without a reason";
    }
  }
  EXPECT_EQ(r.products.front().state, ProductOutcome::State::built);
  EXPECT_THAT(progress, ::testing::Contains("building kinematics"));

  // The top level holds the summaries and the first component of every file a product wrote.
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(r.out_dir)) files.push_back(e.path().filename().string());
  std::sort(files.begin(), files.end());
  std::set<std::string> expected{"summary.json", "summary.md"};
  for (const auto& p : r.products) {
    for (const auto& f : p.files) expected.insert(f.begin()->string());
  }
  EXPECT_EQ(files, std::vector<std::string>(expected.begin(), expected.end()));

  const auto json = Json::parse(slurp(r.summary_json));
  EXPECT_EQ(json, r.to_json());
  EXPECT_EQ(json["built"][0]["name"], "kinematics");
  EXPECT_EQ(json["results"]["kinematics"]["stations"].size(), 2u);
  EXPECT_EQ(slurp(r.summary_md), r.to_markdown());
  EXPECT_THAT(r.to_markdown(), HasSubstr("## Kinematics at the target"));
}

TEST_F(Scene, AnExplicitListBuildsOnlyWhatItNames) {
  const Design d = load_design(kDesign);
  SceneOptions o = options();
  o.products = std::vector<std::string>{};
  const SceneReport r = run_scene(d, o);
  EXPECT_TRUE(r.products_listed);
  for (const auto& p : r.products) {
    EXPECT_EQ(p.state, ProductOutcome::State::left_out) << p.name;
    EXPECT_THAT(p.reason, HasSubstr("not listed"));
  }
  EXPECT_TRUE(r.ok());
  EXPECT_TRUE(fs::exists(r.summary_md));

  o.products = std::vector<std::string>{"kinematics"};
  const SceneReport k = run_scene(d, o);
  EXPECT_TRUE(k.products.front().requested);
  EXPECT_EQ(k.products.front().state, ProductOutcome::State::built);
}

TEST_F(Scene, UnknownProductIsAnInputErrorAndWritesNothing) {
  const Design d = load_design(kDesign);
  SceneOptions o = options();
  o.products = std::vector<std::string>{"kinematics", "teleport"};
  EXPECT_THAT([&] { (void)run_scene(d, o); },
              ::testing::ThrowsMessage<InputError>(AllOf(HasSubstr("teleport"), HasSubstr("kinematics"))));
  EXPECT_FALSE(fs::exists(root_));
}

TEST_F(Scene, AFailingKinematicsCheckIsReportedNotThrown) {
  Design d = load_design(kDesign);
  d.stations[0].target.center = Vec2(100.0, 100.0);  // far out of reach of both mechanisms
  const SceneReport r = run_scene(d, options());
  EXPECT_FALSE(r.ok());
  ASSERT_EQ(r.products.front().state, ProductOutcome::State::built);
  EXPECT_FALSE(r.products.front().passed);
  EXPECT_THAT(r.products.front().check, HasSubstr("2 of 4"));
  const std::string md = slurp(r.summary_md);
  EXPECT_THAT(md, HasSubstr("attention needed"));
  EXPECT_THAT(md, HasSubstr("index/lower: target centre unreachable"));
}

TEST_F(Scene, ADesignNameEscapingTheRootIsRefused) {
  Design d = load_design(kDesign);
  d.name = "../escape";
  EXPECT_THROW((void)run_scene(d, options()), InputError);
  EXPECT_FALSE(fs::exists(root_));
}

}  // namespace
}  // namespace fivebar
