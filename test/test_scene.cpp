// The scene runner (fivebar/scene.hpp) and its product registry (lib/src/products).

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cctype>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <random>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>

#include "fivebar/error.hpp"
#include "fivebar/scene.hpp"
#include "fivebar/sections/optimize.hpp"
#include "fivebar/sections/controller.hpp"
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
  ASSERT_EQ(products::registry().size(), known.size());
  for (std::size_t i = 0; i < known.size(); ++i) {
    const products::Product& p = products::registry()[i];
    // products.def gives both lists: an entry point returning another name is caught here.
    EXPECT_EQ(p.name, known[i]);
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

/// Lines `FIVEBAR_PRODUCT(name)` of lib/src/products/products.def, in order.
std::vector<std::string> registered_in_def() {
  std::vector<std::string> names;
  std::istringstream in(slurp(fs::path(FIVEBAR_SOURCE_DIR) / "lib/src/products/products.def"));
  for (std::string line; std::getline(in, line);) {
    const std::string open = "FIVEBAR_PRODUCT(";
    if (line.rfind(open, 0) == 0) names.push_back(line.substr(open.size(), line.find(')') - open.size()));
  }
  return names;
}

TEST(Registry, EveryProductFolderIsRegisteredAndEveryRegistrationHasItsFolder) {
  // docs/architecture.md "Adding a product": the product glue lib/src/<name>/product.cpp sits in
  // its study's folder, and one line in products.def registers it; nothing else in the library
  // names the product.
  const fs::path src = fs::path(FIVEBAR_SOURCE_DIR) / "lib/src";
  std::set<std::string> folders;
  for (const auto& e : fs::directory_iterator(src)) {
    if (e.is_directory() && fs::exists(e.path() / "product.cpp")) folders.insert(e.path().filename().string());
  }
  const std::vector<std::string> def = registered_in_def();
  EXPECT_EQ(std::set<std::string>(def.begin(), def.end()), folders);
  EXPECT_EQ(def, known_products());

  // The entry point `<name>_product` is defined in its folder and named nowhere else in lib/ or cli/
  // (products.def builds the registry by token pasting).
  for (const std::string& name : def) {
    const std::string entry = name + "_product(";
    for (const char* tree : {"lib", "cli"}) {
      for (const auto& e : fs::recursive_directory_iterator(fs::path(FIVEBAR_SOURCE_DIR) / tree)) {
        if (!e.is_regular_file()) continue;
        const std::string text = slurp(e.path());
        // The name as a whole identifier: `replay_product(` is not named by `bench_replay_product(`.
        bool named = false;
        for (std::size_t at = text.find(entry); at != std::string::npos && !named; at = text.find(entry, at + 1)) {
          named = at == 0 || !(std::isalnum(static_cast<unsigned char>(text[at - 1])) || text[at - 1] == '_');
        }
        if (!named) continue;
        EXPECT_EQ(e.path(), src / name / "product.cpp") << entry << " named outside its folder";
      }
    }
  }
}

TEST(Registry, TheSceneRunnerAndTheDesignNameNoProduct) {
  // The scene, the design model and the loader learn product names from products.def only.
  for (const char* file : {"lib/src/scene.cpp", "lib/src/design/design.cpp", "lib/src/yaml/design_loader.cpp",
                           "lib/src/products/registry.cpp", "lib/include/fivebar/design.hpp"}) {
    const std::string text = slurp(fs::path(FIVEBAR_SOURCE_DIR) / file);
    for (const std::string& name : known_products()) {
      EXPECT_EQ(text.find('"' + name + '"'), std::string::npos) << file << " names product " << name;
    }
  }
}

TEST_F(Scene, BuildsEveryAvailableProductAndWritesBothSummaries) {
  Design d = load_design(kDesign);
  // The control product tunes (controller.tune): two evaluations per mechanism keep this test fast.
  ASSERT_TRUE(d.get<ControllerSettings>()->tune.has_value());
  d.get<ControllerSettings>()->tune->evaluations = 2;
  // Two evaluations cannot reach the damping and gain-margin floors from the pole placement (the
  // tuned showcase meets them: test_control.cpp); here the floors are off, the scene is the subject.
  d.get<ControllerSettings>()->tune->min_damping = 0.0;
  d.get<ControllerSettings>()->tune->min_gain_margin = 1.0;
  // The optimize product: the smallest budget it accepts (the initial populations and a round), a
  // short polish and a coarse atlas (the showcase's own search is 384 candidates, a 15-cell atlas).
  ASSERT_TRUE(d.get<OptimizeSettings>() != nullptr);
  d.get<OptimizeSettings>()->evaluations = 128;
  d.get<OptimizeSettings>()->polish_evaluations = 10;
  d.get<OptimizeSettings>()->atlas_cells = 9;
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
  std::set<std::string> expected{"summary.json", "summary.md", "index.html"};
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

  // index.html: the same sections and tables as summary.md, every pattern's animation inline.
  EXPECT_EQ(r.index_html, r.out_dir / "index.html");
  const std::string html = slurp(r.index_html);
  const std::string md = r.to_markdown();
  const auto count = [](const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count(html, "<h2 id="), count(md, "\n## "));
  EXPECT_EQ(count(html, "<table>"), count(md, "\n|---") + count(md, "\n|:---"));
  EXPECT_EQ(count(html, "<svg xmlns=\"http://www.w3.org/2000/svg\" id=\"fivebar-animation-"), 8u);  // 2 stations x 4 patterns
  EXPECT_THAT(html, HasSubstr("<h2 id=\"kinematics-at-the-target-kinematics\">Kinematics at the target (<code>kinematics</code>)</h2>"));
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

/// A product made up for the test: it needs `needs`, records that it ran and what it saw.
products::Product throwaway(std::string name, std::vector<std::string> needs, std::vector<std::string>* seen) {
  products::Product p;
  p.name = std::move(name);
  p.title = "Throwaway " + p.name;
  p.prerequisites = std::move(needs);
  p.build = [seen, pre = p.prerequisites, own = p.name](products::Context& ctx) {
    for (const auto& n : pre) {
      if (ctx.result_of(n) == nullptr) throw std::logic_error(own + " built before its prerequisite " + n);
    }
    seen->push_back(own);
    ctx.write_file(own + "/note.txt", "built\n");
    products::Built b;
    b.result = {{"prerequisites_seen", pre.size()}};
    b.markdown = "Built by the test.\n";
    b.check = "made up";
    return b;
  };
  return p;
}

TEST_F(Scene, AThrowawayProductBuildsWithItsPrerequisitesOnly) {
  // A product added to the list (as a new folder + one line of products.def would add it) runs
  // after its prerequisites, transitively, and nothing else is built.
  std::vector<products::Product> list = products::registry();
  std::vector<std::string> seen;
  list.push_back(throwaway("alpha", {"kinematics"}, &seen));
  list.push_back(throwaway("beta", {"alpha"}, &seen));
  list.push_back(throwaway("gamma", {}, &seen));
  const Design d = load_design(kDesign);
  SceneOptions o = options();
  o.products = std::vector<std::string>{"beta"};
  const SceneReport r = products::run_scene_with(d, o, list);

  EXPECT_EQ(seen, (std::vector<std::string>{"alpha", "beta"}));
  ASSERT_EQ(r.products.size(), list.size());
  for (const ProductOutcome& p : r.products) {
    const bool built = p.name == "kinematics" || p.name == "alpha" || p.name == "beta";
    EXPECT_EQ(p.state == ProductOutcome::State::built, built) << p.name;
    EXPECT_EQ(p.requested, p.name == "beta") << p.name;
    EXPECT_EQ(p.prerequisite, p.name == "kinematics" || p.name == "alpha") << p.name;
  }
  EXPECT_TRUE(fs::exists(r.out_dir / "beta" / "note.txt"));
  EXPECT_FALSE(fs::exists(r.out_dir / "gamma"));
  const std::string md = slurp(r.summary_md);
  EXPECT_THAT(md, HasSubstr("| `alpha` | built (prerequisite) |"));
  EXPECT_THAT(md, HasSubstr("| `kinematics` | built (prerequisite) |"));
  EXPECT_THAT(md, HasSubstr("## Throwaway beta (`beta`)"));
  const auto json = Json::parse(slurp(r.summary_json));
  EXPECT_EQ(json["results"]["beta"]["prerequisites_seen"], 1);
  EXPECT_EQ(json["built"].size(), 3u);
}

TEST_F(Scene, OneWorkerStartsTheLongestChainFirstAndAnEarlierRunsTimesReplaceTheHints) {
  // "quick" (0.5 s) and "slow" (1 s) need nothing; "tail" (3 s) needs slow. The chains: slow 4 s,
  // tail 3 s, quick 0.5 s, so one worker builds slow, tail, quick although quick comes first in
  // the list. An earlier run's summary.json in the output folder saying quick took 10 s puts it
  // first; the results are the same either way.
  std::vector<products::Product> list = products::registry();
  std::vector<std::string> seen;
  list.push_back(throwaway("quick", {}, &seen));
  list.back().cost_s = 0.5;
  list.push_back(throwaway("slow", {}, &seen));
  list.back().cost_s = 1.0;
  list.push_back(throwaway("tail", {"slow"}, &seen));
  list.back().cost_s = 3.0;
  const Design d = load_design(kDesign);
  SceneOptions o = options();
  o.products = std::vector<std::string>{"quick", "slow", "tail"};
  o.jobs = 1;
  const SceneReport first = products::run_scene_with(d, o, list);
  EXPECT_EQ(seen, (std::vector<std::string>{"slow", "tail", "quick"}));
  Json earlier = Json::parse(slurp(first.summary_json));
  for (Json& b : earlier["built"]) b["wall_s"] = b["name"] == "quick" ? 10.0 : 0.01;
  std::ofstream(first.summary_json, std::ios::trunc) << earlier.dump(2);
  seen.clear();
  const SceneReport second = products::run_scene_with(d, o, list);
  EXPECT_EQ(seen, (std::vector<std::string>{"quick", "slow", "tail"}));
  Json a = Json::parse(slurp(first.summary_json)), b = Json::parse(slurp(second.summary_json));
  for (Json* j : {&a, &b})
    for (Json& x : (*j)["built"]) x.erase("wall_s");
  EXPECT_EQ(a["results"], b["results"]);
}

TEST_F(Scene, AProductWhosePrerequisiteCannotBeBuiltIsLeftOutWithTheReason) {
  std::vector<products::Product> list = products::registry();
  std::vector<std::string> seen;
  products::Product never = throwaway("never", {}, &seen);
  never.unavailable = [](const Design&) -> std::optional<std::string> { return "no data for it"; };
  list.push_back(never);
  list.push_back(throwaway("after", {"never"}, &seen));
  SceneOptions o = options();
  o.products = std::vector<std::string>{"after"};
  const SceneReport r = products::run_scene_with(load_design(kDesign), o, list);
  EXPECT_TRUE(seen.empty());
  EXPECT_EQ(r.products.back().state, ProductOutcome::State::left_out);
  EXPECT_THAT(r.products.back().reason, HasSubstr("needs never, which could not be built"));
  EXPECT_EQ(r.missing(), std::vector<std::string>{"after"});
  EXPECT_FALSE(r.ok());
}

TEST_F(Scene, ADesignNameEscapingTheRootIsRefused) {
  Design d = load_design(kDesign);
  d.name = "../escape";
  EXPECT_THROW((void)run_scene(d, options()), InputError);
  EXPECT_FALSE(fs::exists(root_));
}

TEST_F(Scene, IndependentProductsRunSideBySideAndTheOutputsDoNotDependOnTheWorkers) {
  // "left" and "right" need nothing: with two workers each starts while the other runs (each
  // waits for the other's start); "join" needs left and reads right when it is built (after), so
  // it starts only when both are done; with one worker the same scene builds one product at a
  // time. The summaries are the same but for the wall times.
  struct Shared {
    std::mutex lock;
    std::condition_variable cv;
    std::set<std::string> started;
    bool wait = false;
  };
  const auto shared = std::make_shared<Shared>();
  const auto side = [shared](const std::string& own, const std::string& other) {
    products::Product p;
    p.name = own;
    p.title = "Side " + own;
    p.build = [shared, own, other](products::Context& ctx) {
      bool saw = false;
      {
        std::unique_lock<std::mutex> g(shared->lock);
        shared->started.insert(own);
        shared->cv.notify_all();
        if (shared->wait) {
          saw = shared->cv.wait_for(g, std::chrono::seconds(30), [&] { return shared->started.count(other) > 0; });
        }
      }
      ctx.write_file(own + "/note.txt", "built\n");
      products::Built b;
      b.result = {{"saw_other_running", saw}};
      b.markdown = "Built by the test.\n";
      b.check = "made up";
      return b;
    };
    return p;
  };
  std::vector<products::Product> list = products::registry();
  list.push_back(side("left", "right"));
  list.push_back(side("right", "left"));
  products::Product join;
  join.name = "join";
  join.title = "Join";
  join.prerequisites = {"left"};
  join.after = {"right", "absent"};  // "absent" is not built: nothing to wait for
  join.build = [](products::Context& ctx) {
    products::Built b;
    b.result = {{"left", ctx.result_of("left") != nullptr}, {"right", ctx.result_of("right") != nullptr}};
    b.check = "made up";
    return b;
  };
  list.push_back(join);
  const Design d = load_design(kDesign);
  SceneOptions o = options();
  o.products = std::vector<std::string>{"left", "right", "join"};
  const auto without_times = [](Json j) {
    for (Json& b : j["built"]) {
      EXPECT_GE(b["wall_s"].get<double>(), 0.0);
      b.erase("wall_s");
    }
    return j;
  };
  o.jobs = 1;
  const SceneReport one = products::run_scene_with(d, o, list);
  const Json one_json = without_times(Json::parse(slurp(one.summary_json)));
  shared->started.clear();
  shared->wait = true;
  o.jobs = 2;
  const SceneReport two = products::run_scene_with(d, o, list);
  const Json two_json = without_times(Json::parse(slurp(two.summary_json)));
  EXPECT_EQ(two_json["results"]["left"]["saw_other_running"], true);
  EXPECT_EQ(two_json["results"]["right"]["saw_other_running"], true);
  EXPECT_EQ(two_json["results"]["join"]["left"], true);
  EXPECT_EQ(two_json["results"]["join"]["right"], true);
  // Same products, order, checks, files and results, whatever the workers.
  Json a = one_json, b = two_json;
  for (Json* j : {&a, &b}) (*j)["results"]["left"].erase("saw_other_running"), (*j)["results"]["right"].erase("saw_other_running");
  EXPECT_EQ(a, b);
  std::vector<std::string> order;
  for (const ProductOutcome& p : two.products) order.push_back(p.name);
  ASSERT_GE(order.size(), 3u);
  EXPECT_EQ(std::vector<std::string>(order.end() - 3, order.end()), (std::vector<std::string>{"left", "right", "join"}));
  const std::string md = slurp(two.summary_md);
  EXPECT_THAT(md, HasSubstr("| product | state | check | time (s) | files |"));
}

}  // namespace
}  // namespace fivebar
