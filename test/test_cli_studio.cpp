// fivebar studio (docs/studio.md): the state module against the command line it must agree with
// (the margin of `fivebar coverage --json` on the saved file), saves that keep every other byte of
// the file, a file changed on disk, the loader's FILE:LINE: key messages for an edit it refuses,
// and the server's refusals (token, Host, Origin, paths outside the design's folder) over HTTP.
// The page itself is tested in a real browser by test/studio_browser.py.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include "cli_test.hpp"
#include "fivebar/collision.hpp"
#include "fivebar/error.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/coverage/coverage.hpp"
#include "fivebar/coverage/report.hpp"
#include "fivebar/studio.hpp"
#include "fivebar/workspace/region.hpp"

// Last: <httplib.h> brings <resolv.h>, whose macro `_res` would rename a parameter of Eigen's headers.
#include <httplib.h>

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::slurp;
using nlohmann::json;
using ::testing::HasSubstr;

namespace {

class StudioCli : public ft::CliTest {
 protected:
  StudioCli() : CliTest("fivebar-test-studio") {}
  /// The lines of `text`.
  static std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> out;
    std::size_t from = 0;
    while (from < text.size()) {
      const std::size_t end = std::min(text.find('\n', from), text.size());
      out.push_back(text.substr(from, end - from));
      from = end + 1;
    }
    return out;
  }
};

/// The first line of the paper's design that holds `needle` after the line holding `after` (1-based).
int line_of(const std::string& text, const std::string& after, const std::string& needle) {
  const std::size_t a = text.find(after);
  const std::size_t p = text.find(needle, a);
  return 1 + int(std::count(text.begin(), text.begin() + std::ptrdiff_t(p), '\n'));
}

const std::vector<fivebar::FileEdit> kEdits = {
    {"stations.index.mechanisms.lower.links[2]", 15.75},
    {"stations.index.mechanisms.lower.bases[1][0]", 12.0},
    {"stations.index.target.center[1]", 15.25},
};

TEST_F(StudioCli, TheStudiosMarginIsTheCommandLinesOnTheSavedFile) {
  const fs::path design = write("d.yaml", slurp(kDesign));
  fivebar::Studio studio(design);
  const json fig = fivebar::studio_figures(studio.design(kEdits), "index");
  ASSERT_EQ(studio.save(kEdits, studio.text_sha256()), fivebar::Studio::SaveStatus::saved);
  const ft::Outcome r = run({"coverage", design.string(), "--station", "index", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json cli = json::parse(r.out)["stations"][0];
  ASSERT_EQ(fig["coverage"]["mechanisms"].size(), cli["mechanisms"].size());
  for (std::size_t i = 0; i < cli["mechanisms"].size(); ++i) {
    EXPECT_EQ(fig["coverage"]["mechanisms"][i]["margin_mm"], cli["mechanisms"][i]["margin_mm"]);
    EXPECT_EQ(fig["coverage"]["mechanisms"][i]["worst_point_mm"], cli["mechanisms"][i]["worst_point_mm"]);
  }
  EXPECT_EQ(fig["coverage"]["shared"]["margin_mm"], cli["shared"]["margin_mm"]);
  // The edits moved the margin: the lower mechanism's longer... shorter distal link changes it.
  const json before = fivebar::studio_figures(fivebar::Studio(write("e.yaml", slurp(kDesign))).design({}), "index");
  EXPECT_NE(before["coverage"]["mechanisms"][0]["margin_mm"], fig["coverage"]["mechanisms"][0]["margin_mm"]);
}

TEST_F(StudioCli, TheRegionWithoutJointLimitsHasTheAnnuliClosedFormArea) {
  fivebar::Studio studio(write("d.yaml", slurp(kDesign)));
  const fivebar::Design d = studio.design(kEdits);
  const json fig = fivebar::studio_figures(d, "index");
  const fivebar::Mechanism& lower = *d.station("index")->lower;
  // Lens sums of the two legs' annuli (region.hpp annuli_intersection_area), not the CGAL arrangement.
  const double annuli = fivebar::annuli_intersection_area(lower);
  EXPECT_NEAR(fig["mechanisms"][0]["region"]["area_mm2"].get<double>(), annuli, 1e-9 * annuli);
  EXPECT_EQ(fig["collision_map"], "not certified yet");
  EXPECT_EQ(fig["lci_field"], "not certified yet");
  // The pose at the cursor closes the loop: |A1 - P| = L3 and |A2 - P| = L4 of the edited design.
  const json& pts = fig["mechanisms"][0]["pose"]["points_mm"];
  const auto dist = [&](int a, int b) { return std::hypot(pts[a][0].get<double>() - pts[b][0].get<double>(), pts[a][1].get<double>() - pts[b][1].get<double>()); };
  EXPECT_NEAR(dist(1, 2), 15.75, 1e-9);
  EXPECT_NEAR(dist(3, 2), 15.0, 1e-9);
  EXPECT_NEAR(pts[4][0].get<double>(), 12.0, 0.0);
}

TEST_F(StudioCli, SavingChangesOnlyTheEditedLinesAndKeepsEveryComment) {
  const std::string original = slurp(kDesign);
  const fs::path design = write("d.yaml", original);
  fivebar::Studio studio(design);
  const json preview = studio.preview(kEdits);
  ASSERT_EQ(studio.save(kEdits, studio.text_sha256()), fivebar::Studio::SaveStatus::saved);
  const std::vector<std::string> a = lines(original), b = lines(slurp(design));
  ASSERT_EQ(a.size(), b.size());
  std::vector<int> changed;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i] != b[i]) changed.push_back(int(i) + 1);
    // A comment is everything from " #" on: it survives on every line.
    const std::size_t ca = a[i].find(" #"), cb = b[i].find(" #");
    if (ca != std::string::npos) {
      ASSERT_NE(cb, std::string::npos) << "line " << i + 1;
      EXPECT_EQ(a[i].substr(ca), b[i].substr(cb)) << "line " << i + 1;
    }
  }
  const int links = line_of(original, "  index:", "links: [9, 9, 15, 15]");
  const int bases = line_of(original, "  index:", "bases: [[0, 0], [12.5, 0]]");
  const int target = line_of(original, "  index:", "target: {center: [6.25, 15.5]");
  EXPECT_EQ(changed, (std::vector<int>{target, bases, links}));
  EXPECT_THAT(b[std::size_t(links - 1)], ::testing::StartsWith("        links: [9, 9, 15.75, 15] "));
  ASSERT_EQ(preview["changes"].size(), 3u);
  EXPECT_EQ(preview["changes"][2]["line"], links);
  EXPECT_EQ(preview["changes"][2]["after"], b[std::size_t(links - 1)]);
}

TEST_F(StudioCli, AFileChangedOnDiskIsNotOverwritten) {
  const fs::path design = write("d.yaml", slurp(kDesign));
  fivebar::Studio studio(design);
  const std::string sha = studio.text_sha256();
  const std::string theirs = slurp(kDesign) + "# edited elsewhere\n";
  write("d.yaml", theirs);
  EXPECT_EQ(studio.save(kEdits, sha), fivebar::Studio::SaveStatus::changed_on_disk);
  EXPECT_EQ(slurp(design), theirs);
  studio.reload();
  EXPECT_EQ(studio.save(kEdits, studio.text_sha256()), fivebar::Studio::SaveStatus::saved);
  EXPECT_THAT(slurp(design), HasSubstr("# edited elsewhere\n"));
}

TEST_F(StudioCli, AnEditTheLoaderRefusesNamesTheFileLineAndKeyAndWritesNothing) {
  const std::string original = slurp(kDesign);
  const fs::path design = write("d.yaml", original);
  fivebar::Studio studio(design);
  const std::vector<fivebar::FileEdit> bad = {{"stations.index.mechanisms.lower.links[0]", -1.0}};
  const int links = line_of(original, "  index:", "links: [9, 9, 15, 15]");
  try {
    (void)studio.design(bad);
    ADD_FAILURE() << "a negative link was accepted";
  } catch (const fivebar::InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr(design.string() + ":" + std::to_string(links) + ":"));
    EXPECT_THAT(e.what(), HasSubstr("links[0]"));
  }
  EXPECT_THROW((void)studio.save(bad, studio.text_sha256()), fivebar::InputError);
  EXPECT_EQ(slurp(design), original);
  EXPECT_THROW((void)studio.design({{"stations.index.mechanisms.lower.joint_limits[0][0]", 10.0}}), fivebar::InputError);
}

/// A changed value for each control of a station: a number moved by 3 % (and 0.01), a mode to
/// another of its choices.
std::vector<fivebar::FileEdit> changed_controls(const json& controls, const std::string& station) {
  std::vector<fivebar::FileEdit> edits;
  for (const json& st : controls["stations"]) {
    if (st["station"] != station) continue;
    for (const json& k : st["keys"]) {
      if (k.contains("choices")) {
        const std::string now = k["value"];
        for (const json& c : k["choices"]) {
          if (c != now) {
            edits.push_back({k["key"], c.get<std::string>()});
            break;
          }
        }
      } else {
        edits.push_back({k["key"], k["value"].get<double>() * 1.03 + 0.01});
      }
    }
  }
  return edits;
}

TEST_F(StudioCli, AnEditSetInMemoryGivesTheDesignTheLoaderReadsFromTheEditedFile) {
  // The paper's file, and one whose index lower mechanism has joint limits (their four numbers).
  const fs::path limited = design_with("limited.yaml", "links: [9, 9, 15, 15]",
                                       "links: [9, 9, 15, 15]\n        joint_limits: [[-30, 210], [-30, 210]]");
  for (const fs::path& file : {write("d.yaml", slurp(kDesign)), limited}) {
    fivebar::Studio s(file);
    ASSERT_TRUE(s.live_edits()) << file;
    const fivebar::Design base = s.design({});
    for (const std::string station : {"index", "thumb"}) {
      const std::vector<fivebar::FileEdit> all = changed_controls(fivebar::studio_controls(base), station);
      ASSERT_GE(all.size(), 20u);
      // Every key alone (a number, a mode), then all of them at once: the same design, every
      // number to the bit (to_yaml writes the shortest text that reads back as the same double).
      for (const fivebar::FileEdit& e : all) {
        const fivebar::Design live = s.live_design({e}), loaded = s.design({e});
        EXPECT_EQ(fivebar::to_yaml(live), fivebar::to_yaml(loaded)) << file << " " << e.key;
        EXPECT_NE(fivebar::to_yaml(live), fivebar::to_yaml(base)) << e.key << ": the edit changed nothing";
      }
      EXPECT_EQ(fivebar::to_yaml(s.live_design(all)), fivebar::to_yaml(s.design(all))) << file << " " << station;
    }
  }
  EXPECT_THAT(fivebar::studio_controls(fivebar::Studio(limited).design({})).dump(), HasSubstr("joint_limits[1][1]"));
  fivebar::Studio studio(write("d.yaml", slurp(kDesign)));
  // A value the rules refuse gets the loader's message, with the file's line.
  const std::string original = slurp(kDesign);
  const int links = line_of(original, "  index:", "links: [9, 9, 15, 15]");
  for (const double bad : {-1.0, 1.0}) {  // not > 0; shorter than geometry.boss_diameter
    try {
      (void)studio.live_design({{"stations.index.mechanisms.lower.links[0]", bad}});
      ADD_FAILURE() << "links[0] = " << bad << " was accepted";
    } catch (const fivebar::InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(":" + std::to_string(links) + ":"));
      EXPECT_THAT(e.what(), HasSubstr("links[0]"));
    }
  }
  EXPECT_THROW((void)studio.live_design({{"stations.index.mechanisms.lower.working_mode", std::string("+")}}), fivebar::InputError);
  EXPECT_THROW((void)studio.live_design({{"stations.index.mechanisms.lower.joint_limits[0][0]", 10.0}}), fivebar::InputError);
}

TEST_F(StudioCli, AFileWhoseAnchorTiesTwoNumbersIsLoadedForEveryEdit) {
  // One anchor for both mechanisms' links: an edit of the lower's changes the upper's in the file.
  const fs::path file = design_with("tied.yaml", "links: [9, 9, 15, 15]", "links: &L [9, 9, 15, 15]");
  std::string text = slurp(file);
  const std::size_t second = text.find("links: [9, 9, 15, 15]");
  ASSERT_NE(second, std::string::npos);
  text.replace(second, std::string("links: [9, 9, 15, 15]").size(), "links: *L");
  fivebar::Studio studio(write("tied.yaml", text));
  EXPECT_FALSE(studio.live_edits());
  const std::vector<fivebar::FileEdit> e = {{"stations.index.mechanisms.lower.links[2]", 16.0}};
  const fivebar::Design d = studio.live_design(e);
  EXPECT_EQ(d.station("index")->upper->L[2], 16.0);
  EXPECT_EQ(fivebar::to_yaml(d), fivebar::to_yaml(studio.design(e)));
}

TEST_F(StudioCli, TheCacheGivesTheFiguresComputedAfresh) {
  fivebar::Studio studio(write("d.yaml", slurp(kDesign)));
  fivebar::StudioCache cache;
  const std::vector<std::vector<fivebar::FileEdit>> states = {
      {{"stations.index.mechanisms.lower.links[2]", 15.5}},
      {{"stations.index.mechanisms.lower.links[2]", 15.5}, {"stations.index.mechanisms.upper.bases[0][1]", 0.5}},
      {{"stations.index.mechanisms.lower.links[2]", 15.5}},  // back: every entry from the cache
      {{"stations.index.target.axes[0]", 14.0}},             // the regions kept, the coverage not
      {{"stations.index.mechanisms.lower.bases[1][0]", 20.0}},  // the target not inside: the fraction
  };
  const fivebar::StudioCursor at{fivebar::Vec2(6.0, 14.0), fivebar::Vec2(6.5, 17.0)};
  for (std::size_t i = 0; i < states.size(); ++i) {
    for (const fivebar::StudioCursor& c : {fivebar::StudioCursor{}, at}) {
      const fivebar::Design d = studio.live_design(states[i]);
      const json warm = fivebar::studio_figures(d, "index", c, fivebar::StudioFigures::live, &cache);
      const json fresh = fivebar::studio_figures(studio.design(states[i]), "index", c);
      EXPECT_EQ(warm.dump(), fresh.dump()) << "state " << i;
      // The coverage record is `fivebar coverage --json`'s (station_coverage of the station).
      EXPECT_EQ(warm["coverage"], fivebar::to_json(fivebar::station_coverage(*d.station("index")), "index")) << "state " << i;
    }
  }
  const fivebar::Design last = studio.design(states.back());
  EXPECT_FALSE(fivebar::station_coverage(*last.station("index")).lower->inside);
}

TEST_F(StudioCli, TheQuickAnswerIsTheLiveOneWithThePriorityRuleInASecondAnswer) {
  fivebar::Studio studio(write("d.yaml", slurp(kDesign)));
  fivebar::StudioCache cache;
  const std::vector<fivebar::FileEdit> e = {{"stations.index.mechanisms.lower.links[2]", 15.25}};
  const fivebar::Design d = studio.live_design(e);
  const fivebar::Station& s = *d.station("index");
  const fivebar::Geometry& g = *d.get<fivebar::Geometry>();
  // Both tactors at the centre (they collide: the rule moves the lower), then apart (clear).
  const fivebar::StudioCursor apart{fivebar::Vec2(5.0, 10.0), fivebar::Vec2(7.0, 19.0)};
  for (const fivebar::StudioCursor& c : {fivebar::StudioCursor{}, apart}) {
    const json quick = fivebar::studio_figures(d, "index", c, fivebar::StudioFigures::quick, &cache);
    json live = fivebar::studio_figures(d, "index", c, fivebar::StudioFigures::live);
    EXPECT_EQ(quick["priority"], "not certified yet");
    // The rule as `fivebar collision --upper --lower` applies it, computed here directly.
    const json rule = json::parse(fivebar::to_json(fivebar::apply_priority(*s.upper, *s.lower, g, c.upper.value_or(s.target.center),
                                                               c.lower.value_or(s.target.center))).dump());
    EXPECT_EQ(json::parse(fivebar::studio_priority(d, "index", c, &cache).dump()), rule);
    EXPECT_EQ(live["priority"], rule);
    // Everything else of the quick answer is the live answer's.
    json q = quick;
    q.erase("priority");
    q.erase("figures");
    live.erase("priority");
    live.erase("figures");
    EXPECT_EQ(q.dump(), live.dump());
    // Once computed, the quick answer of the same numbers carries it.
    EXPECT_EQ(json::parse(fivebar::studio_figures(d, "index", c, fivebar::StudioFigures::quick, &cache)["priority"].dump()), rule);
  }
  EXPECT_EQ(fivebar::studio_priority(d, "index", {}, nullptr)["status"], "moved");
  EXPECT_EQ(fivebar::studio_priority(d, "index", apart, nullptr)["status"], "clear");
}

TEST_F(StudioCli, ThePatternPlayedIsTheCommandLinesWithLinkagesOfTheDesignsLengths) {
  fivebar::Studio studio(write("d.yaml", slurp(kDesign)));
  // Tactors 3 mm apart at the start of the stretch: they collide, and the priority rule moves the lower.
  const std::vector<fivebar::FileEdit> e = {{"patterns.stretch.separation_mm", 3.0}};
  const fivebar::Design d = studio.design(e);
  const json played = json::parse(fivebar::studio_pattern(d, "index", "stretch").dump());
  const fs::path edited = write("edited.yaml", studio.edited_text(e));
  const ft::Outcome r = run({"pattern", edited.string(), "--station", "index", "--pattern", "stretch", "--json", "--samples",
                             "--out", (dir_ / "out").string()});
  ASSERT_TRUE(r.code == 0 || r.code == 1) << r.err;
  const json cli = json::parse(r.out);
  EXPECT_EQ(played["samples"], cli["samples"]);
  EXPECT_EQ(played["passed"], cli["passed"]);
  EXPECT_GT(cli["worst"]["moved_samples"].get<int>(), 0);
  // Each frame is the linkage at the commanded point: its tactor joint is the point, its links the design's.
  const fivebar::Station& s = *d.station("index");
  ASSERT_EQ(played["frames"].size(), played["samples"].size());
  for (std::size_t k = 0; k < played["frames"].size(); ++k) {
    for (const json& m : played["samples"][k]["mechanisms"]) {
      const std::string name = m["mechanism"];
      const json& joints = played["frames"][k][name];
      ASSERT_TRUE(joints.is_array());
      const fivebar::Mechanism& mech = name == "lower" ? *s.lower : *s.upper;
      const auto at = [&](int i) { return fivebar::Vec2(joints[i][0].get<double>(), joints[i][1].get<double>()); };
      EXPECT_NEAR((at(2) - fivebar::Vec2(m["point_mm"][0].get<double>(), m["point_mm"][1].get<double>())).norm(), 0.0, 1e-9);
      // O1 A1 = L1, O2 A2 = L2, A1 P = L3, A2 P = L4 (fivebar/design.hpp), O1 and O2 the bases.
      EXPECT_NEAR((at(0) - mech.O1).norm(), 0.0, 1e-12);
      EXPECT_NEAR((at(4) - mech.O2).norm(), 0.0, 1e-12);
      EXPECT_NEAR((at(1) - at(0)).norm(), mech.L[0], 1e-9);
      EXPECT_NEAR((at(3) - at(4)).norm(), mech.L[1], 1e-9);
      EXPECT_NEAR((at(2) - at(1)).norm(), mech.L[2], 1e-9);
      EXPECT_NEAR((at(2) - at(3)).norm(), mech.L[3], 1e-9);
    }
  }
  EXPECT_THROW(fivebar::studio_pattern(d, "index", "wobble"), fivebar::InputError);
}

TEST_F(StudioCli, TheToleranceBandAtTheTargetCentreIsTheCommandLines) {
  const fs::path design = write("d.yaml", slurp(kDesign));
  const json fig = fivebar::studio_figures(fivebar::Studio(design).design({}), "index");
  const ft::Outcome r = run({"tolerance", design.string(), "--station", "index", "--json", "--no-files"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json cli = json::parse(r.out)["stations"][0]["mechanisms"];
  ASSERT_EQ(cli.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const json& t = fig["mechanisms"][i]["tolerance"];
    ASSERT_EQ(fig["mechanisms"][i]["mechanism"], cli[i]["mechanism"]);
    EXPECT_EQ(t["status"], cli[i]["centre_status"]);
    EXPECT_EQ(t["at_mm"], fig["target"]["center_mm"]);
    EXPECT_EQ(t["three_sigma_first_order_mm"], cli[i]["centre_3sigma_first_order_mm"]);
    EXPECT_EQ(t["three_sigma_minor_first_order_mm"], cli[i]["centre_3sigma_minor_first_order_mm"]);
    EXPECT_NEAR(t["three_sigma_angle_first_order_deg"].get<double>(), cli[i]["centre_3sigma_angle_first_order_deg"].get<double>(), 1e-9);
    EXPECT_EQ(t["worst_case_first_order_mm"], cli[i]["centre_worst_case_first_order_mm"]);
    // The Monte Carlo of the command line agrees with the linearisation to a few per cent.
    EXPECT_NEAR(t["three_sigma_first_order_mm"].get<double>(), cli[i]["centre_monte_carlo_3sigma_mm"].get<double>(),
                0.05 * cli[i]["centre_monte_carlo_3sigma_mm"].get<double>());
  }
  // Elsewhere: the band moves with the cursor (it is not the centre's).
  const json moved = fivebar::studio_figures(fivebar::Studio(design).design({}), "index", {fivebar::Vec2(6.25, 11.0), std::nullopt});
  EXPECT_NE(moved["mechanisms"][0]["tolerance"]["three_sigma_first_order_mm"], fig["mechanisms"][0]["tolerance"]["three_sigma_first_order_mm"]);
  EXPECT_EQ(moved["mechanisms"][1]["tolerance"], fig["mechanisms"][1]["tolerance"]);
}

/// `fivebar studio` started in the background; its address read from its first line of stdout.
class StudioServer : public StudioCli {
 protected:
  void SetUp() override {
    design_ = write("d.yaml", slurp(kDesign));
    child_ = ft::spawn(FIVEBAR_BINARY, {"studio", design_.string(), "--exit-after", "120"}, dir_, dir_);
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (std::chrono::steady_clock::now() < until) {
      const std::string out = slurp(child_.out);
      if (out.find('\n') != std::string::npos) {
        address_ = out.substr(0, out.find('\n'));
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    ASSERT_THAT(address_, ::testing::MatchesRegex("http://127\\.0\\.0\\.1:[0-9]+/\\?token=[0-9a-f]{32}"));
    const std::size_t colon = address_.find(':', 7), slash = address_.find('/', colon);
    port_ = std::stoi(address_.substr(colon + 1, slash - colon - 1));
    token_ = address_.substr(address_.find("token=") + 6);
  }
  void TearDown() override {
    if (child_.pid > 0) {
      ::kill(child_.pid, SIGTERM);
      (void)ft::wait(child_, 30.0);
    }
  }
  httplib::Client client() const {
    httplib::Client c("127.0.0.1", port_);
    c.set_read_timeout(60, 0);
    return c;
  }
  httplib::Headers ok_headers() const { return {{"X-Fivebar-Token", token_}}; }
  fs::path design_;
  ft::Child child_;
  std::string address_, token_;
  int port_ = 0;
};

TEST_F(StudioServer, ServesThePageWithItsTokenAndRefusesEverythingElse) {
  httplib::Client c = client();
  auto page = c.Get("/?token=" + token_);
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_THAT(page->body, HasSubstr("fivebar studio"));
  EXPECT_THAT(page->get_header_value("Content-Security-Policy"), HasSubstr("default-src 'none'"));
  EXPECT_EQ(c.Get("/")->status, 403);                                 // no token
  EXPECT_EQ(c.Get("/?token=" + std::string(32, '0'))->status, 403);   // a wrong one
  EXPECT_EQ(c.Get("/api/state")->status, 403);
  // DNS rebinding: a page of another name resolving to 127.0.0.1 sends its own Host.
  EXPECT_EQ(c.Get("/?token=" + token_, {{"Host", "evil.example:" + std::to_string(port_)}})->status, 403);
  // Another origin's page, even with the token.
  httplib::Headers cross = ok_headers();
  cross.emplace("Origin", "http://evil.example");
  EXPECT_EQ(c.Post("/api/figures", cross, "{}", "application/json")->status, 403);
  httplib::Headers same = ok_headers();
  same.emplace("Origin", "http://127.0.0.1:" + std::to_string(port_));
  EXPECT_EQ(c.Post("/api/figures", same, "{}", "application/json")->status, 200);
  // Nothing outside the design's outputs folder: a path that climbs out is not served.
  auto climb = c.Get("/out/../../d.yaml?token=" + token_);
  EXPECT_NE(climb->status, 200);
  auto climb2 = c.Get("/out/%2e%2e/%2e%2e/etc/passwd?token=" + token_);
  EXPECT_NE(climb2->status, 200);
}

TEST_F(StudioServer, FiguresAndRefusalsOverHttp) {
  httplib::Client c = client();
  const json edits = {{"edits", {{{"key", "stations.index.mechanisms.lower.links[2]"}, {"value", 15.75}}}}, {"station", "index"}};
  auto r = c.Post("/api/figures", ok_headers(), edits.dump(), "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  fivebar::Studio studio(design_);
  const json local = fivebar::studio_figures(studio.design({{"stations.index.mechanisms.lower.links[2]", 15.75}}), "index");
  EXPECT_EQ(json::parse(r->body)["coverage"], local["coverage"]);
  const json bad = {{"edits", {{{"key", "stations.index.mechanisms.lower.links[0]"}, {"value", -1}}}}};
  auto refused = c.Post("/api/figures", ok_headers(), bad.dump(), "application/json");
  EXPECT_EQ(refused->status, 422);
  EXPECT_THAT(json::parse(refused->body)["error"].get<std::string>(), HasSubstr("links[0]"));
  EXPECT_EQ(c.Post("/api/figures", ok_headers(), "not json", "application/json")->status, 400);
}

TEST_F(StudioServer, ADragsAnswerLeavesOutTheRegionsThePageHoldsAndAStalePriorityRequest) {
  httplib::Client c = client();
  const auto ask = [&](const json& body) {
    auto r = c.Post("/api/figures", ok_headers(), body.dump(), "application/json");
    EXPECT_TRUE(r);
    EXPECT_EQ(r->status, 200) << r->body;
    return json::parse(r->body);
  };
  const json link = {{"key", "stations.index.mechanisms.lower.links[2]"}, {"value", 15.75}};
  const json first = ask({{"edits", {link}}, {"station", "index"}, {"figures", "quick"}, {"seq", 1}, {"page", "p"}});
  const fivebar::Design d = fivebar::Studio(design_).design({{"stations.index.mechanisms.lower.links[2]", 15.75}});
  EXPECT_EQ(first["priority"], "not certified yet");
  EXPECT_EQ(first["mechanisms"][0]["region"], fivebar::studio_figures(d, "index")["mechanisms"][0]["region"]);
  // The lower base moved: the page holds the upper region of the first answer, not the new lower one.
  const json base = {{"key", "stations.index.mechanisms.lower.bases[1][0]"}, {"value", 13.0}};
  const json held = {first["mechanisms"][0]["region"]["id"], first["mechanisms"][1]["region"]["id"]};
  const json second = ask({{"edits", {link, base}}, {"station", "index"}, {"figures", "quick"}, {"seq", 2}, {"page", "p"},
                           {"have_regions", held}});
  EXPECT_NE(second["mechanisms"][0]["region"]["id"], first["mechanisms"][0]["region"]["id"]);
  EXPECT_TRUE(second["mechanisms"][0]["region"]["loops_mm"].is_array());
  EXPECT_EQ(second["mechanisms"][1]["region"]["id"], first["mechanisms"][1]["region"]["id"]);
  EXPECT_TRUE(second["mechanisms"][1]["region"]["loops_mm"].is_null());
  EXPECT_TRUE(second["shared_region"]["loops_mm"].is_array());
  // The priority rule of the first state, asked after the second: stale, not searched.
  const json stale = ask({{"edits", {link}}, {"station", "index"}, {"figures", "priority"}, {"seq", 1}, {"page", "p"}});
  EXPECT_EQ(stale["stale"], true);
  EXPECT_FALSE(stale.contains("priority"));
  // Of the current state (and of another page, whose requests are its own): the library's rule.
  const fivebar::Design d2 = fivebar::Studio(design_).design({{"stations.index.mechanisms.lower.links[2]", 15.75},
                                                              {"stations.index.mechanisms.lower.bases[1][0]", 13.0}});
  for (const char* page : {"p", "q"}) {
    const json now = ask({{"edits", {link, base}}, {"station", "index"}, {"figures", "priority"}, {"seq", 2}, {"page", page}});
    EXPECT_EQ(now["priority"], json::parse(fivebar::studio_priority(d2, "index").dump())) << page;
  }
  const json wrong = {{"figures", "everything"}};
  EXPECT_EQ(c.Post("/api/figures", ok_headers(), wrong.dump(), "application/json")->status, 422);
}

TEST_F(StudioCli, PrintsItsAddressAndStops) {
  const ft::Outcome r = run({"studio", kDesign, "--exit-after", "0"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, ::testing::MatchesRegex("http://127\\.0\\.0\\.1:[0-9]+/\\?token=[0-9a-f]{32}\n"));
}

TEST_F(StudioCli, BadInputIsExitTwo) {
  EXPECT_EQ(run({"studio", "missing.yaml", "--exit-after", "0"}).code, 2);
  const ft::Outcome r = run({"studio", design_with("bad.yaml", "links: [9, 9, 15, 15]", "links: [9, 9, -15, 15]").string(), "--exit-after", "0"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("links[2]"));
  EXPECT_EQ(run({"studio", kDesign, "--port", "70000", "--exit-after", "0"}).code, 2);
}

}  // namespace
