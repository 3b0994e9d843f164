// One way to edit a design (fivebar/design/edit.hpp, docs/reliability.md): key
// paths canonicalised once (two spellings are one key), the optimize section's "each number in
// one variable only" rule on canonical keys, set_design_number() against the design file's own
// round trip, the minimum-length rule stated once and met identically by the sweep, the optimiser
// and the design file, and loading linear in the number of keys.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "fivebar/design/edit.hpp"
#include "fivebar/design/file_edit.hpp"
#include "fivebar/error.hpp"
#include "fivebar/optimize.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/optimize.hpp"
#include "fivebar/sections/sweep.hpp"
#include "fivebar/sweep.hpp"
#include "process.hpp"

namespace fivebar {
namespace {

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ::testing::HasSubstr;

// The paper's index station (Table 1: O1 (0,0), O2 (12.5,0), L1 = L2 = 9, L3 = L4 = 15), and a
// second station whose name holds a dot (allowed by is_safe_name) and so is quoted in key paths.
const std::string kDesign =
    "name: edit\n"
    "stations:\n"
    "  index:\n"
    "    target: {center: [6.25, 15.5], axes: [15, 12], angle: 0}\n"
    "    mechanisms:\n"
    "      lower: {bases: [[0, 0], [12.5, 0]], links: [9, 9, 15, 15], working_mode: \"-+\", assembly_mode: \"+\"}\n"
    "  a.b:\n"
    "    target: {center: [6.25, 15.5], axes: [15, 12], angle: 0}\n"
    "    mechanisms:\n"
    "      lower: {bases: [[0, 0], [12.5, 0]], links: [9, 9, 17.5, 17.5], working_mode: \"-+\", assembly_mode: \"+\"}\n"
    "geometry: {boss_diameter: 5}\n";

Design design() { return load_design_from_string(kDesign, "edit.yaml"); }

TEST(DesignKeys, EverySpellingOfANumberIsOneCanonicalKey) {
  const Design d = design();
  const std::string canonical = "stations.index.mechanisms.lower.links[2]";
  for (const char* spelling : {"stations.index.mechanisms.lower.links[2]", "stations.index.mechanisms.lower.links[02]",
                               "stations.index.mechanisms.lower.links[ 2 ]", "stations.index.mechanisms.lower.links[0002]",
                               "stations[\"index\"].mechanisms.lower.links[2]", "stations['index'].mechanisms.lower.links[2]",
                               "stations[\"index\"][\"mechanisms\"].lower[\"links\"][2]"}) {
    SCOPED_TRACE(spelling);
    const DesignKey k = design_key(d, spelling);
    EXPECT_EQ(k.path, canonical);
    EXPECT_EQ(k.value, 15.0);  // Table 1: L3
    EXPECT_EQ(k.field, DesignKey::Field::link);
    EXPECT_EQ(k.station, "index");
    EXPECT_EQ(k.i, 2);
  }
  // A dotted station name: bare (the longest name wins) and quoted spellings agree, and the
  // canonical form quotes it as every message does.
  for (const char* spelling : {"stations.a.b.mechanisms.lower.links[3]", "stations[\"a.b\"].mechanisms.lower.links[3]",
                               "stations['a.b'].mechanisms.lower.links[03]"}) {
    SCOPED_TRACE(spelling);
    const DesignKey k = design_key(d, spelling);
    EXPECT_EQ(k.path, "stations[\"a.b\"].mechanisms.lower.links[3]");
    EXPECT_EQ(k.value, 17.5);
    EXPECT_EQ(k.station, "a.b");
  }
  EXPECT_EQ(canonical_design_key(d, "geometry.link_width[01]"), "geometry.link_width[1]");
  EXPECT_EQ(design_key(d, "geometry.link_width[01]").field, DesignKey::Field::other);
  // Malformed or missing paths are refused naming the spelling given.
  for (const char* bad : {"stations.index.mechanisms.lower.links[-1]", "stations.index.mechanisms.lower.links[2",
                          "stations[\"index].target.angle", "stations.index.mechanisms.lower.links[4]",
                          "stations.index.target", "", "stations..index"}) {
    SCOPED_TRACE(bad);
    try {
      (void)design_key(d, bad);
      ADD_FAILURE() << "accepted";
    } catch (const ValidationError& e) {
      EXPECT_EQ(e.key(), bad);
    }
  }
}

std::string with_optimize(const std::string& variables) {
  return kDesign + "optimize:\n  variables:\n" + variables + "  objectives: [margin]\n  evaluations: 64\n  population: 8\n";
}

TEST(DesignKeys, TwoVariablesCannotSetOneNumberBySpellingItTwice) {
  // docs/reliability.md: links[2] and links[02] were two keys to the optimize section, so two
  // variables set one number and the reports showed a value that never reached chosen.yaml.
  for (const std::string& second : {std::string("\"stations.index.mechanisms.lower.links[02]\""),
                                    std::string("'stations[\"index\"].mechanisms.lower.links[2]'"),
                                    std::string("\"stations['index'].mechanisms.lower.links[ 2 ]\"")}) {
    SCOPED_TRACE(second);
    const std::string text = with_optimize("    a: {key: \"stations.index.mechanisms.lower.links[2]\", range: [12, 18]}\n"
                                           "    b: {key: " + second + ", range: [12, 18]}\n");
    try {
      (void)load_design_from_string(text, "twice.yaml");
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("optimize.variables.b.key"));
      EXPECT_THAT(e.what(), HasSubstr("already set by optimize.variables.a.key"));
      EXPECT_THAT(e.what(), HasSubstr("'stations.index.mechanisms.lower.links[2]'"));
    }
  }
  // Tied keys of one variable that are the same number are refused too.
  EXPECT_THROW((void)load_design_from_string(
                   with_optimize("    a: {keys: [\"stations.index.mechanisms.lower.links[2]\", \"stations.index.mechanisms.lower.links[002]\"], "
                                 "range: [12, 18]}\n"),
                   "tied.yaml"),
               InputError);
  // Distinct numbers stay accepted, and the optimiser works on their canonical spellings.
  const Design ok = load_design_from_string(
      with_optimize("    a: {key: \"stations['index'].mechanisms.lower.links[02]\", range: [12, 18]}\n"
                    "    b: {key: \"stations.index.mechanisms.lower.links[3]\", range: [12, 18]}\n"),
      "ok.yaml");
  const OptimizeProblem problem(ok);
  EXPECT_EQ(problem.settings().variables[0].keys[0], "stations.index.mechanisms.lower.links[2]");
  EXPECT_TRUE(problem.fast_path());
  EXPECT_EQ(problem.stations(), std::vector<std::string>{"index"});
}

TEST(DesignEdit, SetDesignNumberEqualsTheDesignFilesRoundTrip) {
  // Two formulations: in place (a station's number) and through to_yaml and the loader.
  const Design d = design();
  for (const auto& [key, value] : std::vector<std::pair<std::string, double>>{
           {"stations.index.mechanisms.lower.links[02]", 16.25},
           {"stations.index.mechanisms.lower.bases[1][0]", 13.0},
           {"stations[\"a.b\"].target.center[1]", 16.0},
           {"stations.index.target.axes[0]", 14.0},
           {"stations.index.target.angle", 12.5},
           {"geometry.boss_diameter", 4.5}}) {
    SCOPED_TRACE(key);
    Design edited = d;
    set_design_number(edited, key, value);
    const Design reference = with_design_numbers(d, {{key, value}});
    EXPECT_EQ(to_yaml(edited), to_yaml(reference));
    EXPECT_EQ(design_number(edited, key), value);
  }
}

TEST(DesignEdit, TheMinimumLengthRuleIsOneRuleForTheFileTheSweepAndTheOptimiser) {
  const Design d = design();
  const std::string message = "shorter than geometry.boss_diameter (5 mm)";
  // The design file.
  try {
    (void)with_design_numbers(d, {{"stations.index.mechanisms.lower.links[1]", 4.0}});
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("stations.index.mechanisms.lower.links[1] = 4 mm: " + message));
  }
  // set_design_number(), in place, and the design is left unchanged.
  Design edited = d;
  try {
    set_design_number(edited, "stations.index.mechanisms.lower.links[01]", 4.0);
    ADD_FAILURE() << "accepted";
  } catch (const ValidationError& e) {
    EXPECT_THAT(e.what(), HasSubstr("mechanisms.lower.links[1] = 4 mm: " + message));
  }
  EXPECT_EQ(to_yaml(edited), to_yaml(d));
  // The sweep.
  SweepSettings s;
  s.station = "index";
  s.vary = {{"L2", 3.0, 6.0, 2}};
  try {
    (void)apply_sweep(d, s, {4.0});
    ADD_FAILURE() << "accepted";
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.key(), "mechanisms.lower.links[1]");
    EXPECT_THAT(e.rule(), HasSubstr(message));
  }
  EXPECT_NO_THROW((void)apply_sweep(d, s, {5.0}));  // at the bound: printable
  // The optimiser's fast path.
  const Design o = load_design_from_string(with_optimize("    a: {key: \"stations.index.mechanisms.lower.links[1]\", range: [3, 9]}\n"),
                                           "o.yaml");
  const OptimizeProblem problem(o);
  ASSERT_TRUE(problem.fast_path());
  const OptimizeCandidate c = problem.evaluate({4.0});
  EXPECT_EQ(c.verdict, OptimizeVerdict::invalid);
  EXPECT_THAT(c.status, HasSubstr("stations.index.mechanisms.lower.links[1] = 4 mm: " + message));
}

/// A design of `stations` stations whose optimize section ties every station number (13 a
/// station) in one variable: 1,300 distinct keys for 100 stations.
std::string many_keys(int stations) {
  std::string text = "name: many\nstations:\n";
  std::string keys;
  for (int s = 0; s < stations; ++s) {
    const std::string n = "s" + std::to_string(s);
    text += "  " + n + ":\n    target: {center: [6.25, 15.5], axes: [15, 12], angle: 0}\n"
            "    mechanisms:\n      lower: {bases: [[0, 0], [12.5, 0]], links: [15, 15, 15, 15], working_mode: \"-+\", "
            "assembly_mode: \"+\"}\n";
    const std::string p = "stations." + n + ".";
    const auto q = [](const std::string& k) { return "\"" + k + "\", "; };  // quoted: [ ] are flow indicators
    for (int i = 0; i < 4; ++i) keys += q(p + "mechanisms.lower.links[" + std::to_string(i) + "]");
    for (int i = 0; i < 2; ++i) {
      for (int j = 0; j < 2; ++j) keys += q(p + "mechanisms.lower.bases[" + std::to_string(i) + "][" + std::to_string(j) + "]");
    }
    for (int i = 0; i < 2; ++i) keys += q(p + "target.center[" + std::to_string(i) + "]") + q(p + "target.axes[" + std::to_string(i) + "]");
    keys += q(p + "target.angle");
  }
  keys.resize(keys.size() - 2);
  return text + "optimize:\n  variables:\n    all: {keys: [" + keys + "], range: [12, 18]}\n  objectives: [margin]\n";
}

TEST(DesignKeys, LoadingIsLinearInTheKeys) {
  // docs/reliability.md: each key was resolved by writing and re-reading the whole design, so a
  // design of 1,200 keys took 29 s to load (every command, even fk). The child's time bound is
  // the hostile corpus's (10 s, FIVEBAR_TEST_CHILD_TIMEOUT_S under the sanitizers); the figure
  // is BM_LoadDesignWithManyOptimizeKeys in test/bench/bench_optimize.cpp.
  ft::ScratchDir io("fivebar_edit_io");
  ft::ScratchDir scratch("fivebar_edit");
  const std::string text = many_keys(100);
  ASSERT_LT(text.size(), kMaxDesignFileBytes);
  { std::ofstream(scratch.path() / "many.yaml") << text; }
  const ft::Outcome r = ft::run(FIVEBAR_BINARY, {"fk", "many.yaml", "--station", "s99", "--mechanism", "lower", "--theta", "100,80"},
                                scratch.path(), io.path(), ft::child_timeout_s(10.0));
  EXPECT_FALSE(r.timed_out);
  EXPECT_EQ(r.code, 0) << r.err;
  // The library gives the same answer on the same text: every key resolved, none twice.
  const Design d = load_design_from_string(text, "many.yaml");
  EXPECT_EQ(d.get<OptimizeSettings>()->variables[0].keys.size(), 1300u);
}

// edit_design_text (fivebar/design/file_edit.hpp): the file's own text with one scalar replaced,
// against set_design_number's round trip through to_yaml and the loader (a second formulation).
TEST(FileEdit, EditingTheTextEqualsSetDesignNumberAndKeepsEveryOtherByte) {
  const std::string text =
      "# a comment that must survive\n"
      "name: edit   # trailing comment\n"
      "stations:\n"
      "  index:\n"
      "    target: {center: [6.25, 15.5], axes: [15, 12], angle: 0}   # centre\n"
      "    mechanisms:\n"
      "      lower:\n"
      "        bases: [[0, 0], [12.5, 0]]\n"
      "        links:\n"
      "          - 9      # L1\n"
      "          - 9.0\n"
      "          - 1.5e1  # L3, written with an exponent\n"
      "          - 15\n"
      "        working_mode: '-+'   # quoted singly\n"
      "        assembly_mode: \"+\"\n";
  const std::vector<FileEdit> edits = {{"stations.index.mechanisms.lower.links[02]", 16.25},
                                       {"stations.index.mechanisms.lower.links[0]", 9.5},
                                       {"stations.index.target.center[1]", 16.0},
                                       {"stations.index.target.angle", 12.5},
                                       {"stations.index.mechanisms.lower.bases[1][0]", 13.0},
                                       {"stations.index.mechanisms.lower.working_mode", std::string("+-")}};
  const std::string edited = edit_design_text(text, "t.yaml", edits);
  const std::string expected =
      "# a comment that must survive\n"
      "name: edit   # trailing comment\n"
      "stations:\n"
      "  index:\n"
      "    target: {center: [6.25, 16], axes: [15, 12], angle: 12.5}   # centre\n"
      "    mechanisms:\n"
      "      lower:\n"
      "        bases: [[0, 0], [13, 0]]\n"
      "        links:\n"
      "          - 9.5      # L1\n"
      "          - 9.0\n"
      "          - 16.25  # L3, written with an exponent\n"
      "          - 15\n"
      "        working_mode: \"+-\"   # quoted singly\n"
      "        assembly_mode: \"+\"\n";
  EXPECT_EQ(edited, expected);
  Design reference = load_design_from_string(text, "t.yaml");
  for (std::size_t i = 0; i + 1 < edits.size(); ++i) set_design_number(reference, edits[i].key, std::get<double>(edits[i].value));
  Design loaded = load_design_from_string(edited, "t.yaml");
  EXPECT_EQ(loaded.stations[0].lower->working_mode, parse_working_mode("+-").value());
  loaded.stations[0].lower->working_mode = reference.stations[0].lower->working_mode;
  EXPECT_EQ(to_yaml(loaded), to_yaml(reference));
  // The last edit of a key wins; an empty list changes nothing.
  EXPECT_EQ(edit_design_text(text, "t.yaml", {{"stations.index.target.angle", 1.0}, {"stations.index.target.angle", 2.0}}),
            edit_design_text(text, "t.yaml", {{"stations.index.target.angle", 2.0}}));
  EXPECT_EQ(edit_design_text(text, "t.yaml", {}), text);
}

TEST(FileEdit, AKeyThatIsNotAValueOfTheFileIsRefusedNamingIt) {
  const std::string text = "name: edit\nstations:\n  index:\n    target: {center: [6.25, 15.5], axes: [15, 12], angle: 0}\n";
  const auto refused = [&](const FileEdit& e, const std::string& words) {
    SCOPED_TRACE(e.key);
    try {
      (void)edit_design_text(text, "t.yaml", {e});
      ADD_FAILURE() << "accepted";
    } catch (const InputError& error) {
      EXPECT_THAT(error.what(), HasSubstr("t.yaml"));
      EXPECT_THAT(error.what(), HasSubstr(words));
    }
  };
  refused({"stations.index.mechanisms.lower.joint_limits[0][0]", 10.0}, "is not in the file");
  refused({"stations.index.target", 1.0}, "t.yaml:4: key 'stations.index.target': not a single value");
  refused({"name", 1.0}, "not a number");
  refused({"stations.index.target.angle", std::nan("")}, "not a finite number");
}

}  // namespace
}  // namespace fivebar
