// Sweeps: enumeration, agreement with single-design coverage, shards and threads equal the
// serial run, resume after an interruption equals an uninterrupted run, the Pareto set is the
// brute-force non-dominated set, the best design is a loadable design file.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <unistd.h>

#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/patterns.hpp"
#include "fivebar/sections/print.hpp"
#include "fivebar/sections/sweep.hpp"
#include "fivebar/collision.hpp"
#include "fivebar/coverage/coverage.hpp"
#include "fivebar/sections/tolerance.hpp"
#include "fivebar/sweep.hpp"
#include "paper.hpp"

namespace fivebar {
namespace {
using ::fivebar::testing::test_seed;

Design paper_design() { return load_design(std::filesystem::path(FIVEBAR_SOURCE_DIR) / "designs/iros2022.yaml"); }

Design with_sweep(SweepSettings s) {
  Design d = paper_design();
  d.set<SweepSettings>(std::move(s));
  d.validate();
  return d;
}

SweepSettings grid(std::vector<SweepVariable> vars, std::string mechanism = "") {
  SweepSettings s;
  s.station = "index";
  s.mechanism = std::move(mechanism);
  s.vary = std::move(vars);
  return s;
}

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::filesystem::path temp_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("fivebar_test_sweep_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  return dir;
}

TEST(Enumeration, GridVisitsEveryCombinationWithExactEnds) {
  const SweepSettings s = grid({{"L3", 10, 20, 3}, {"L4", 12, 13, 5}});
  ASSERT_EQ(sweep_size(s), 15u);
  std::set<std::pair<double, double>> seen;
  for (std::uint64_t i = 0; i < 15; ++i) {
    const auto v = sweep_point(s, i);
    seen.insert({v[0], v[1]});
  }
  EXPECT_EQ(seen.size(), 15u);
  EXPECT_EQ(sweep_point(s, 0), (std::vector<double>{10, 12}));
  EXPECT_EQ(sweep_point(s, 1), (std::vector<double>{10, 12.25}));  // the last variable runs fastest
  EXPECT_EQ(sweep_point(s, 14), (std::vector<double>{20, 13}));
  EXPECT_EQ(sweep_point(s, 5), (std::vector<double>{15, 12}));
}

TEST(Enumeration, RandomAndSobolStayInRangeAndDependOnlyOnIndexAndSeed) {
  for (const char* sample : {"random", "sobol"}) {
    SweepSettings s = grid({{"L3", 10, 20, 1}, {"L4", 12, 13, 1}});
    s.sample = sample;
    s.count = 1000;
    s.seed = 7;
    double mean0 = 0;
    for (std::uint64_t i = 0; i < 1000; ++i) {
      const auto v = sweep_point(s, i);
      EXPECT_GE(v[0], 10.0);
      EXPECT_LT(v[0], 20.0);
      EXPECT_GE(v[1], 12.0);
      EXPECT_LT(v[1], 13.0);
      mean0 += v[0] / 1000;
    }
    EXPECT_NEAR(mean0, 15.0, 0.3) << sample;  // uniform on [10, 20)
    EXPECT_EQ(sweep_point(s, 123), sweep_point(s, 123));
    SweepSettings other = s;
    other.seed = 8;
    EXPECT_NE(sweep_point(s, 123), sweep_point(other, 123)) << sample;
  }
}

TEST(Enumeration, SobolIsMoreUniformThanRandom) {
  // Star discrepancy proxy: worst count deviation over a grid of anchored boxes.
  auto discrepancy = [](const SweepSettings& s) {
    double worst = 0;
    for (double a = 0.1; a <= 1.0; a += 0.1) {
      for (double b = 0.1; b <= 1.0; b += 0.1) {
        int in = 0;
        for (std::uint64_t i = 0; i < 1024; ++i) {
          const auto v = sweep_point(s, i);
          in += (v[0] - 1) < a && (v[1] - 1) < b;
        }
        worst = std::max(worst, std::fabs(in / 1024.0 - a * b));
      }
    }
    return worst;
  };
  SweepSettings s = grid({{"L3", 1, 2, 1}, {"L4", 1, 2, 1}});
  s.count = 1024;
  s.sample = "sobol";
  s.seed = 0;
  const double sobol = discrepancy(s);
  s.sample = "random";
  const double random = discrepancy(s);
  EXPECT_LT(sobol, random);
  EXPECT_LT(sobol, 0.01);
}

TEST(Evaluation, RowsAgreeWithSingleDesignCoverage) {
  const Design d = with_sweep(grid({{"L34", 11, 19, 25}, {"L12", 6, 12, 25}}));
  std::mt19937_64 rng(test_seed());
  std::uniform_int_distribution<std::uint64_t> pick(0, sweep_size(*d.get<SweepSettings>()) - 1);
  int covered = 0, not_covered = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const std::uint64_t i = pick(rng);
    const SweepRow row = evaluate_sweep_design(d, *d.get<SweepSettings>(), i);
    const Station st = apply_sweep(d, *d.get<SweepSettings>(), row.values);
    EXPECT_EQ(st.lower->L[2], row.values[0]);
    EXPECT_EQ(st.upper->L[0], row.values[1]);
    const StationCoverage ref = station_coverage(st);
    SCOPED_TRACE(::testing::Message() << "design " << i << ": " << row.status);
    EXPECT_EQ(row.covered, ref.covered());
    EXPECT_NEAR(row.margin_lower_mm, ref.lower->margin_mm, 1e-12);
    if (row.covered) {
      ++covered;
      EXPECT_NEAR(row.margin_upper_mm, ref.upper->margin_mm, 1e-12);
      EXPECT_NEAR(row.margin_shared_mm, ref.shared->margin_mm, 1e-12);
      EXPECT_NEAR(row.min_lci, ref.shared->min_lci, 1e-4);  // the sweep refines more coarsely
      EXPECT_GT(row.footprint_mm2, 15.0 * 12.0);
    } else {
      ++not_covered;
    }
  }
  EXPECT_GT(covered, 3);
  EXPECT_GT(not_covered, 3);
}

TEST(Evaluation, RobustObjectiveIsTheMarginLessTheTolerancesShare) {
  // The `robust` objective: with every tolerance zero the robust margin is the margin itself; with
  // tolerances it is smaller, and halving them (sigma is linear in the tolerances) about halves
  // the loss.
  SweepSettings s = grid({{"L34", 14, 17, 4}});
  s.objectives = {"margin", "robust"};
  s.collision_spacing_mm = 0.0;
  const auto with_tolerance = [&](double scale) {
    Design d = with_sweep(s);
    ToleranceSettings t;
    t.link_sigma_mm = 0.05 * scale;
    t.pin_sigma_mm = 0.025 * scale;
    t.base_sigma_mm = 0.1 * scale;
    d.set(t);
    return d;
  };
  const Design none = with_tolerance(0.0), full = with_tolerance(1.0), half = with_tolerance(0.5);
  int covered = 0;
  for (std::uint64_t i = 0; i < sweep_size(s); ++i) {
    const SweepRow a = evaluate_sweep_design(none, s, i), b = evaluate_sweep_design(full, s, i),
                   c = evaluate_sweep_design(half, s, i);
    SCOPED_TRACE(::testing::Message() << "design " << i << ": " << b.status);
    if (!b.covered) {
      EXPECT_TRUE(std::isnan(b.robust_margin_mm));
      continue;
    }
    ++covered;
    const double margin = std::fmin(b.margin_lower_mm, b.margin_upper_mm);
    EXPECT_NEAR(a.robust_margin_mm, margin, 1e-9);
    EXPECT_LT(b.robust_margin_mm, margin - 0.05);
    // min_b (d(b) - s z sigma(b)) is concave in the scale s: halving the tolerances loses at most
    // half, and about half where one boundary point stays the worst.
    EXPECT_LE(margin - c.robust_margin_mm, 0.5 * (margin - b.robust_margin_mm) + 1e-9);
    EXPECT_GT(margin - c.robust_margin_mm, 0.45 * (margin - b.robust_margin_mm));
    EXPECT_EQ(b.score("robust"), b.robust_margin_mm);
  }
  EXPECT_GT(covered, 1);
  // Without the objective the column stays empty.
  SweepSettings plain = s;
  plain.objectives = {"margin"};
  EXPECT_TRUE(std::isnan(evaluate_sweep_design(with_sweep(plain), plain, 1).robust_margin_mm));
}

TEST(Evaluation, InvalidDesignsAreRowsNotErrors) {
  // L12 down to 2 mm is shorter than the geometry's 5 mm pin bosses.
  const Design d = with_sweep(grid({{"L12", 2, 9, 8}}));
  const SweepRow bad = evaluate_sweep_design(d, *d.get<SweepSettings>(), 0);
  EXPECT_THAT(bad.status, ::testing::StartsWith("invalid: "));
  EXPECT_THAT(bad.status, ::testing::HasSubstr("boss_diameter"));
  EXPECT_FALSE(bad.covered);
  EXPECT_TRUE(std::isnan(bad.margin_lower_mm));
}

TEST(Evaluation, CollisionFractionOfCoveredDesignsOnly) {
  // The paper's design has geometry: covered rows carry the collision fraction of their own
  // station (the swept links), computed on the sweep's grid; uncovered ones do not.
  SweepSettings s = grid({{"L34", 11, 19, 9}});
  s.collision_spacing_mm = 2.5;
  s.objectives = {"margin", "collision"};
  const Design d = with_sweep(s);
  int covered = 0;
  std::set<double> fractions;
  for (std::uint64_t i = 0; i < sweep_size(s); ++i) {
    const SweepRow row = evaluate_sweep_design(d, s, i);
    SCOPED_TRACE(::testing::Message() << "design " << i << ": " << row.status);
    if (!row.covered) {
      EXPECT_TRUE(std::isnan(row.collision_fraction));
      continue;
    }
    ++covered;
    const Station st = apply_sweep(d, s, row.values);
    const CollisionFraction ref = collision_fraction(st, *d.get<Geometry>(), 2.5);
    EXPECT_EQ(row.collision_fraction, ref.fraction);
    EXPECT_GT(row.collision_fraction, 0.0);
    EXPECT_LT(row.collision_fraction, 1.0);
    EXPECT_EQ(row.score("collision"), -row.collision_fraction);  // minimised
    fractions.insert(row.collision_fraction);
  }
  EXPECT_GE(covered, 3);
  EXPECT_GE(fractions.size(), 2u);  // the distal length changes what collides
  // Off: spacing 0, or no geometry.
  s.collision_spacing_mm = 0.0;
  s.objectives = {"margin"};
  const Design off = with_sweep(s);
  Design bare = paper_design();
  bare.reset<Geometry>();
  bare.reset<PrintSettings>();
  bare.reset<ControllerSettings>();
  bare.reset<PatternSettings>();
  bare.set<SweepSettings>(grid({{"L34", 11, 19, 9}}));
  bare.validate();
  for (std::uint64_t i = 0; i < sweep_size(s); ++i) {
    EXPECT_TRUE(std::isnan(evaluate_sweep_design(off, *off.get<SweepSettings>(), i).collision_fraction));
    EXPECT_TRUE(std::isnan(evaluate_sweep_design(bare, *bare.get<SweepSettings>(), i).collision_fraction));
  }
}

TEST(Evaluation, CollisionGridIsNeverFinerThanTwentyFourStepsAcross) {
  // 0.05 mm on the 15 mm index ellipse would be 300 steps across (5e9 pairs per design): the grid
  // is coarsened to 15/24 mm, and the row equals the collision fraction on that grid.
  SweepSettings s = grid({{"L34", 15, 15, 1}});
  s.collision_spacing_mm = 0.05;
  const Design d = with_sweep(s);
  const Station st = apply_sweep(d, s, {15.0});
  EXPECT_DOUBLE_EQ(sweep_collision_spacing(s, st.target), 15.0 / 24.0);
  const SweepRow row = evaluate_sweep_design(d, s, 0);
  ASSERT_TRUE(row.covered) << row.status;
  EXPECT_EQ(row.collision_fraction, collision_fraction(st, *d.get<Geometry>(), 15.0 / 24.0).fraction);
  // A spacing coarser than that is kept as it is.
  s.collision_spacing_mm = 3.0;
  EXPECT_EQ(sweep_collision_spacing(s, st.target), 3.0);
}

TEST(Evaluation, CollisionObjectiveNeedsGeometryAndBothMechanisms) {
  SweepSettings s = grid({{"L34", 11, 19, 3}});
  s.objectives = {"collision"};
  Design d = paper_design();
  d.reset<Geometry>();
  d.reset<PrintSettings>();
  d.reset<ControllerSettings>();
  d.reset<PatternSettings>();
  d.set<SweepSettings>(s);
  EXPECT_THAT([&] { d.validate(); },
              ::testing::ThrowsMessage<ValidationError>(::testing::HasSubstr("needs the geometry: section")));
  Design one = paper_design();
  one.stations[0].upper.reset();
  one.reset<ControllerSettings>();
  one.reset<PatternSettings>();
  one.set<SweepSettings>(s);
  EXPECT_THAT([&] { one.validate(); }, ::testing::ThrowsMessage<ValidationError>(::testing::HasSubstr("both a lower and an upper")));
}

TEST(Run, ShardsAndThreadsReproduceTheSerialRowsAndResumeContinuesExactly) {
  const Design d = with_sweep(grid({{"L3", 11, 19, 23}, {"L4", 11, 19, 19}}, "lower"));
  const auto serial_dir = temp_dir("serial");
  SweepOptions o;
  o.out_dir = serial_dir;
  o.threads = 1;
  o.chunk = 100;
  o.plots = false;
  const SweepResult serial = run_sweep(d, o);
  ASSERT_EQ(serial.done, 23u * 19u);
  const std::string rows = slurp(serial.csv);

  SweepOptions two = o;
  two.threads = 2;
  two.out_dir = temp_dir("threads");
  EXPECT_EQ(slurp(run_sweep(d, two).csv), rows);

  std::string joined = sweep_csv_header(*d.get<SweepSettings>()) + "\n";
  for (std::uint64_t k = 0; k < 3; ++k) {
    SweepOptions shard = o;
    shard.out_dir = temp_dir("shards");
    shard.shard = k;
    shard.shards = 3;
    if (k > 0) shard.out_dir = temp_dir("shards" + std::to_string(k));
    const std::string text = slurp(run_sweep(d, shard).csv);
    joined += text.substr(text.find('\n') + 1);
  }
  EXPECT_EQ(joined, rows);

  // Interrupt after the first chunk (the stop flag is already set), then resume.
  std::atomic<bool> stop{true};
  SweepOptions first = o;
  first.out_dir = temp_dir("resume");
  first.stop = &stop;
  const SweepResult part = run_sweep(d, first);
  EXPECT_TRUE(part.interrupted);
  EXPECT_EQ(part.done, 100u);
  SweepOptions rest = first;
  rest.stop = nullptr;
  rest.resume = true;
  const SweepResult whole = run_sweep(d, rest);
  EXPECT_FALSE(whole.interrupted);
  EXPECT_EQ(whole.evaluated, 23u * 19u - 100u);
  EXPECT_EQ(slurp(whole.csv), rows);
  EXPECT_EQ(slurp(first.out_dir / "pareto.csv"), slurp(serial_dir / "pareto.csv"));
  for (const auto& dir : {serial_dir, two.out_dir, first.out_dir}) std::filesystem::remove_all(dir);
}

TEST(Run, ResumeRefusesAnotherSweepsCsv) {
  const Design a = with_sweep(grid({{"L3", 11, 19, 5}}, "lower"));
  const Design b = with_sweep(grid({{"L4", 11, 19, 5}}, "lower"));
  SweepOptions o;
  o.out_dir = temp_dir("refuse");
  o.plots = false;
  run_sweep(a, o);
  o.resume = true;
  EXPECT_THAT([&] { run_sweep(b, o); }, ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("not the same sweep")));
  std::filesystem::remove_all(o.out_dir);
}

TEST(Run, DensePlotsEmbedOneRasterAndStaySmall) {
  // 121 x 121 designs: one rectangle per cell and one path per point would make megabytes.
  SweepSettings s = grid({{"L34", 12, 19, 121}, {"L12", 6, 12, 121}});
  s.collision_spacing_mm = 0.0;
  const Design d = with_sweep(s);
  SweepOptions o;
  o.out_dir = temp_dir("dense_plots");
  const SweepResult r = run_sweep(d, o);
  const std::string heat = slurp(o.out_dir / "sweep_heatmap.svg"), scatter = slurp(o.out_dir / "sweep_scatter.svg");
  auto count = [](const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  };
  std::uint64_t covered = 0;
  read_sweep_csv(r.csv, s, [&](const SweepRow& row, const std::string&) { covered += row.covered; });
  ASSERT_GT(covered, 2000u);  // more points than the scatter draws as vectors
  // The heat map's cells are one image (121 x 121 pixels); the scatter's points another.
  EXPECT_GE(count(heat, "<image"), 1u);
  EXPECT_THAT(heat, ::testing::HasSubstr("width=\"121\""));
  EXPECT_GE(count(scatter, "<image"), 1u);
  // Vector elements are the axes, labels and legend only: far fewer than the 14,641 cells.
  EXPECT_LT(count(heat, "<path"), 2000u);
  EXPECT_LT(count(scatter, "<path"), 2000u);
  EXPECT_LT(heat.size(), 1000000u);
  EXPECT_LT(scatter.size(), 1000000u);
  std::filesystem::remove_all(o.out_dir);
}

TEST(Run, ParetoSetIsExactlyTheBruteForceNonDominatedSet) {
  SweepSettings s = grid({{"L34", 12, 18, 13}, {"L12", 7, 12, 11}});
  s.objectives = {"margin", "min_lci", "footprint"};
  const Design d = with_sweep(s);
  SweepOptions o;
  o.out_dir = temp_dir("pareto");
  o.plots = false;
  const SweepResult r = run_sweep(d, o);
  std::vector<SweepRow> rows;
  read_sweep_csv(r.csv, s, [&](const SweepRow& row, const std::string&) {
    if (row.covered) rows.push_back(row);
  });
  ASSERT_GT(rows.size(), 10u);
  auto dominates = [&](const SweepRow& a, const SweepRow& b) {
    bool better = false;
    for (const auto& obj : s.objectives) {
      if (a.score(obj) < b.score(obj)) return false;
      if (a.score(obj) > b.score(obj)) better = true;
    }
    return better;
  };
  std::set<std::uint64_t> brute;
  for (const auto& a : rows) {
    bool dominated = false;
    for (const auto& b : rows) dominated = dominated || dominates(b, a);
    if (!dominated) brute.insert(a.index);
  }
  std::set<std::uint64_t> got;
  for (const auto& p : r.pareto) got.insert(p.index);
  EXPECT_EQ(got, brute);
  // The best design is on the front and is the lexicographic optimum; its file loads.
  ASSERT_TRUE(r.best.has_value());
  EXPECT_TRUE(brute.count(r.best->index));
  for (const auto& row : rows) EXPECT_LE(row.score("margin"), r.best->score("margin"));
  const Design best = load_design(o.out_dir / "best.yaml");
  EXPECT_EQ(best.name, "iros2022-best");  // its outputs do not overwrite the swept design's
  EXPECT_EQ(best.station("index")->lower->L[2], r.best->values[0]);
  EXPECT_EQ(best.station("index")->upper->L[0], r.best->values[1]);
  EXPECT_FALSE(best.has<SweepSettings>());
  std::filesystem::remove_all(o.out_dir);
}

TEST(DesignFile, ToYamlRoundTrips) {
  Design d = paper_design();
  d.stations[0].lower->joint_limits = std::array<JointRange, 2>{JointRange{0.1, 3.0}, JointRange{-0.5, 2.0}};
  d.stations[0].lower->min_lci = 0.125;
  d.stations[1].target.angle = 0.3;
  d.set<SweepSettings>(grid({{"L34", 12, 18, 13}}));
  d.products = std::vector<std::string>{"kinematics"};
  const Design back = load_design_from_string(to_yaml(d), "<to_yaml>");
  EXPECT_EQ(to_yaml(back), to_yaml(d));
  const Mechanism& m = *back.stations[0].lower;
  EXPECT_EQ(m.L, d.stations[0].lower->L);
  EXPECT_NEAR(m.joint_limits->at(0).lo, 0.1, 1e-12);
  EXPECT_NEAR(m.joint_limits->at(1).span(), 2.5, 1e-12);
  EXPECT_EQ(m.min_lci, 0.125);
  EXPECT_NEAR(back.stations[1].target.angle, 0.3, 1e-12);
  EXPECT_EQ(back.get<Geometry>()->link_width, d.get<Geometry>()->link_width);
  EXPECT_EQ(back.get<PrintSettings>()->material, d.get<PrintSettings>()->material);
}


}  // namespace
}  // namespace fivebar
