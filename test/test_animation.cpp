// Tests of fivebar/animation.hpp and of the scene's HTML page (products/html.hpp): the frames read
// back from the SVG put the elbows where the motor angles put them (A_i = O_i + L_i (cos, sin),
// typed here), keep every link at the design's length and the tactor on the commanded point; the
// static picture draws the first frame; the simulated track is the last simulated sample at each
// frame; text is escaped; the page renders the summary's Markdown as HTML and places animations
// inline. The browser itself is test_browser.cpp.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "fivebar/animation.hpp"
#include "fivebar/design.hpp"
#include "fivebar/error.hpp"
#include "fivebar/pattern.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/patterns.hpp"
#include "products/html.hpp"

namespace fivebar {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using ::testing::HasSubstr;
using ::testing::Not;

const fs::path kDesign = fs::path(FIVEBAR_SOURCE_DIR) / "designs" / "iros2022.yaml";

/// The JSON of the <metadata> element of an animation.
json frames_of(const std::string& svg) {
  const std::string open = "<metadata class=\"fivebar-animation-data\">";
  const std::size_t a = svg.find(open);
  const std::size_t b = svg.find("</metadata>", a);
  EXPECT_NE(a, std::string::npos);
  EXPECT_NE(b, std::string::npos);
  if (a == std::string::npos || b == std::string::npos) return json();
  return json::parse(svg.substr(a + open.size(), b - a - open.size()));
}

/// The value of attribute `name` of the first element with class `cls`.
std::string attribute(const std::string& svg, const std::string& cls, const std::string& name) {
  const std::size_t at = svg.find("class=\"" + cls + "\"");
  if (at == std::string::npos) return "";
  const std::size_t start = svg.rfind('<', at);
  const std::size_t end = svg.find('>', at);
  const std::string tag = svg.substr(start, end - start);
  const std::smatch m = [&] {
    std::smatch out;
    std::regex_search(tag, out, std::regex(" " + name + "=\"([^\"]*)\""));
    return out;
  }();
  return m.size() > 1 ? m[1].str() : "";
}

Vec2 vec(const json& a, std::size_t i = 0) { return {a[i].get<double>(), a[i + 1].get<double>()}; }

class Animation : public ::testing::Test {
 protected:
  void SetUp() override {
    design_ = load_design(kDesign);
    geometry_ = *design_.get<Geometry>();
    settings_ = *design_.get<PatternSettings>();
  }
  PatternResult pattern(const std::string& station, PatternKind kind) const {
    const Station& s = *design_.station(station);
    for (const PatternSpec& spec : settings_.for_station(station)) {
      if (spec.kind == kind) return check_pattern(s, geometry_, spec, settings_.max_joint_speed);
    }
    ADD_FAILURE() << "no pattern";
    return {};
  }
  Design design_;
  Geometry geometry_;
  PatternSettings settings_;
};

TEST_F(Animation, ElbowsAreWhereTheMotorAnglesPutThemAndLinksKeepTheirLengths) {
  for (const std::string station : {"index", "thumb"}) {
    for (const PatternKind kind : {PatternKind::stretch, PatternKind::slip, PatternKind::twist, PatternKind::pivot}) {
      SCOPED_TRACE(station + " " + std::string(to_string(kind)));
      const Station& s = *design_.station(station);
      const PatternResult r = pattern(station, kind);
      ASSERT_FALSE(r.samples.empty());
      const json d = frames_of(animate_pattern_svg(s, r));
      ASSERT_EQ(d["mechanisms"].size(), 2u);
      const auto& times = d["t_s"];
      ASSERT_EQ(times.size(), r.samples.size());  // 101 or 201 samples: every one is a frame
      for (const json& jm : d["mechanisms"]) {
        const Mechanism& m = *s.mechanism(jm["name"].get<std::string>());
        EXPECT_EQ(vec(jm["O1"]), m.O1);
        EXPECT_EQ(vec(jm["O2"]), m.O2);
        for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(jm["links_mm"][i].get<double>(), m.L[i]);
        for (std::size_t k = 0; k < times.size(); ++k) {
          const std::size_t sample = d["sample"][k].get<std::size_t>();
          ASSERT_EQ(sample, k);
          // True speed: frame k is at the sample's time, k / rate.
          EXPECT_NEAR(times[k].get<double>(), static_cast<double>(k) / r.spec.rate_hz, 1e-12);
          const TactorSample& ts = m.name == "upper" ? r.samples[k].upper : r.samples[k].lower;
          const json& f = jm["frames"][k];
          ASSERT_TRUE(f.is_array()) << "frame " << k << " of a renderable pattern has no linkage";
          const Vec2 A1 = vec(f, 0), P = vec(f, 2), A2 = vec(f, 4);
          // Elbows by the closed form of the proximal links (paper Sec. II-A), typed here.
          const Vec2 A1_ref = m.O1 + m.L[0] * Vec2(std::cos(ts.theta[0]), std::sin(ts.theta[0]));
          const Vec2 A2_ref = m.O2 + m.L[1] * Vec2(std::cos(ts.theta[1]), std::sin(ts.theta[1]));
          EXPECT_LT((A1 - A1_ref).norm(), 1e-4) << "frame " << k;
          EXPECT_LT((A2 - A2_ref).norm(), 1e-4) << "frame " << k;
          // The tactor is the commanded point (the pattern's IK), and every link has its length.
          EXPECT_LT((P - ts.point).norm(), 1e-4) << "frame " << k;
          EXPECT_NEAR((A1 - m.O1).norm(), m.L[0], 2e-4);
          EXPECT_NEAR((A2 - m.O2).norm(), m.L[1], 2e-4);
          EXPECT_NEAR((P - A1).norm(), m.L[2], 2e-4);
          EXPECT_NEAR((P - A2).norm(), m.L[3], 2e-4);
          EXPECT_LT((vec(jm["targets"][k]) - ts.target).norm(), 1e-4);
        }
      }
    }
  }
}

TEST_F(Animation, TheStaticPictureDrawsTheFirstFrameThroughTheView) {
  const Station& s = *design_.station("index");
  const PatternResult r = pattern("index", PatternKind::twist);
  const std::string svg = animate_pattern_svg(s, r);
  const json d = frames_of(svg);
  const json& view = d["views"][0];  // the station's panel, drawn first
  const double xmin = view["xmin_mm"].get<double>(), ymax = view["ymax_mm"].get<double>();
  const double scale = view["px_per_mm"].get<double>();
  // The first <polyline class="fivebar-link"> is the upper linkage: O1 A1 P A2 O2 in panel pixels.
  std::istringstream points(attribute(svg, "fivebar-link", "points"));
  std::vector<Vec2> px;
  std::string pair;
  while (points >> pair) {
    const std::size_t comma = pair.find(',');
    px.emplace_back(std::stod(pair.substr(0, comma)), std::stod(pair.substr(comma + 1)));
  }
  ASSERT_EQ(px.size(), 5u);
  const json& f = d["mechanisms"][0]["frames"][0];
  const Mechanism& up = *s.upper;
  const std::vector<Vec2> mm{up.O1, vec(f, 0), vec(f, 2), vec(f, 4), up.O2};
  for (std::size_t i = 0; i < 5; ++i) {
    const Vec2 back(xmin + px[i].x() / scale, ymax - px[i].y() / scale);  // pixels back to mm
    EXPECT_LT((back - mm[i]).norm(), 0.006 / scale + 1e-4) << "joint " << i;
  }
  // The second panel shows every tactor point, enlarged.
  const json& detail = d["views"][1];
  EXPECT_GT(detail["px_per_mm"].get<double>(), 2.0 * scale);
  for (const json& m : d["mechanisms"]) {
    for (const json& f : m["frames"]) {
      const double u = (f[2].get<double>() - detail["xmin_mm"].get<double>()) * detail["px_per_mm"].get<double>();
      const double v = (detail["ymax_mm"].get<double>() - f[3].get<double>()) * detail["px_per_mm"].get<double>();
      EXPECT_TRUE(u > 0.0 && u < detail["width_px"].get<double>() && v > 0.0 && v < detail["height_px"].get<double>());
    }
  }
  // A self-contained document: no reference to another file or site.
  EXPECT_THAT(svg, Not(HasSubstr("href")));
  EXPECT_THAT(svg, Not(HasSubstr("http://www.w3.org/1999/xlink")));
  EXPECT_THAT(svg, HasSubstr("<script type=\"text/javascript\"><![CDATA["));
}

TEST_F(Animation, LongPatternsAreShownEveryKthSampleWithTheEndKept) {
  const Station& s = *design_.station("index");
  const PatternResult r = pattern("index", PatternKind::pivot);  // 201 samples
  const std::vector<AnimationFrame> frames = animation_frames(s, r, 10);
  ASSERT_LE(frames.size(), 10u);
  ASSERT_GE(frames.size(), 9u);
  EXPECT_EQ(frames.front().sample, 0u);
  EXPECT_EQ(frames.back().sample, r.samples.size() - 1);
  const std::size_t stride = frames[1].sample;
  for (std::size_t k = 1; k + 1 < frames.size(); ++k) EXPECT_EQ(frames[k].sample, k * stride);
  for (const AnimationFrame& f : frames) EXPECT_DOUBLE_EQ(f.time_s, r.samples[f.sample].time_s);
}

TEST_F(Animation, TheSimulatedTactorIsTheLastSimulatedSampleAtEachFrame) {
  const Station& s = *design_.station("index");
  const PatternResult r = pattern("index", PatternKind::stretch);
  // A made-up time series at half the frame rate, lower only, offset so that it is recognisable.
  std::string csv = "t_s,mechanism,theta1_ref_deg,x_mm,y_mm\n";
  for (int k = 0; k <= 50; ++k) {
    const double t = 0.02 * k;
    csv += std::to_string(t) + ",lower,0," + std::to_string(1.0 + t) + "," + std::to_string(2.0 - t) + "\n";
  }
  std::istringstream in(csv);
  AnimationOptions options;
  options.simulated = read_simulated_tracks(in, "sim.csv");
  ASSERT_EQ(options.simulated.size(), 1u);
  EXPECT_EQ(options.simulated[0].mechanism, "lower");
  EXPECT_EQ(options.simulated[0].time_s.size(), 51u);
  const json d = frames_of(animate_pattern_svg(s, r, options));
  EXPECT_FALSE(d["mechanisms"][0].contains("simulated"));  // upper: none given
  const json& sim = d["mechanisms"][1]["simulated"];
  ASSERT_EQ(sim.size(), r.samples.size());
  for (std::size_t k = 0; k < sim.size(); ++k) {
    const double t_sim = 0.02 * std::floor(static_cast<double>(k) / 2.0 + 1e-9);  // last sample at or before k/100
    EXPECT_NEAR(sim[k][0].get<double>(), 1.0 + t_sim, 1e-4) << k;
    EXPECT_NEAR(sim[k][1].get<double>(), 2.0 - t_sim, 1e-4) << k;
  }
}

TEST_F(Animation, UnreachableSamplesHaveNoLinkageInTheirFrames) {
  const Station& s = *design_.station("index");
  PatternSpec spec;
  spec.kind = PatternKind::stretch;
  spec.amplitude_mm = 40.0;  // far beyond both workspaces at the end
  spec.separation_mm = 8.0;
  spec.duration_s = 1.0;
  spec.rate_hz = 20.0;
  const PatternResult r = check_pattern(s, geometry_, spec, settings_.max_joint_speed);
  ASSERT_FALSE(r.passed);
  const json d = frames_of(animate_pattern_svg(s, r));
  std::size_t missing = 0;
  for (std::size_t i = 0; i < 2; ++i) {
    const json& m = d["mechanisms"][i];
    for (std::size_t k = 0; k < r.samples.size(); ++k) {
      const TactorSample& ts = i == 0 ? r.samples[k].upper : r.samples[k].lower;
      const bool reachable = ts.pose.status != Status::unreachable;
      EXPECT_EQ(m["frames"][k].is_array(), reachable) << m["name"] << " frame " << k;
      missing += reachable ? 0 : 1;
      EXPECT_LT((vec(m["targets"][k]) - ts.target).norm(), 1e-4);  // the target is shown all the same
    }
  }
  EXPECT_GT(missing, 0u);
  EXPECT_THAT(animate_pattern_svg(s, r), HasSubstr("NOT renderable"));
}

TEST(AnimationInput, BadTimeSeriesNameFileAndLine) {
  std::istringstream no_column("t_s,mechanism,x_mm\n0,lower,1\n");
  try {
    (void)read_simulated_tracks(no_column, "a.csv");
    ADD_FAILURE() << "no throw";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("a.csv:1: column 'y_mm' is missing"));
  }
  std::istringstream bad_number("t_s,mechanism,x_mm,y_mm\n0,lower,1,2\n0.01,lower,abc,2\n");
  try {
    (void)read_simulated_tracks(bad_number, "b.csv");
    ADD_FAILURE() << "no throw";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("b.csv:3: column 'x_mm' = 'abc': not a finite decimal number"));
  }
  std::istringstream backwards("t_s,mechanism,x_mm,y_mm\n0.5,lower,1,2\n0.1,lower,1,2\n");
  EXPECT_THROW((void)read_simulated_tracks(backwards, "c.csv"), InputError);
}

TEST_F(Animation, TextIsEscapedAndAStationWithoutAPairIsRefused) {
  Station s = *design_.station("index");
  const PatternResult r = pattern("index", PatternKind::slip);
  s.name = "a<b&c\"d";
  const std::string svg = animate_pattern_svg(s, r);
  EXPECT_THAT(svg, Not(HasSubstr("a<b")));
  EXPECT_THAT(svg, HasSubstr("a&lt;b&amp;c&quot;d"));
  EXPECT_EQ(frames_of(svg)["station"], "a<b&c\"d");  // the JSON reads back to the name
  EXPECT_THAT(svg, HasSubstr("id=\"fivebar-animation-a_b_c_d-slip\""));
  Station lonely = *design_.station("index");
  lonely.upper.reset();
  EXPECT_THROW((void)animate_pattern_svg(lonely, r), InputError);
  PatternResult empty = r;
  empty.samples.clear();
  EXPECT_THROW((void)animate_pattern_svg(*design_.station("index"), empty), InputError);
}

// --- The page (products/html.hpp) ----------------------------------------------------------------

TEST(HtmlPage, RendersTheSummaryMarkdownWithEveryTextEscaped) {
  const std::string markdown =
      "# fivebar scene `x<y>`\n\n"
      "Some **bold** text & a [link](patterns/a.csv), a [bad one](javascript:alert(1)).\n\n"
      "## Products\n\n"
      "| product | value | note |\n|---|---:|:---:|\n| `a\\|b` | 1.5 | <script>alert(1)</script> |\n\n"
      "- one\n- two: `pics/p.svg` and `pics/none.csv`\n\n"
      "![picture](pics/p.png)\n\n"
      "![movie](animations/m.svg)\n\n"
      "## Products\n";
  md::HtmlFiles files;
  files.exists = [](const std::string& rel) { return rel == "pics/p.svg"; };
  files.read = [](const std::string& rel) -> std::optional<std::string> {
    if (rel == "animations/m.svg") return std::string("<?xml version=\"1.0\"?>\n<svg id=\"m\"><script>go()</script></svg>\n");
    return std::nullopt;
  };
  const std::string page = md::to_html_page(markdown, "t & t", files);
  EXPECT_THAT(page, HasSubstr("<!DOCTYPE html>"));
  EXPECT_THAT(page, HasSubstr("<title>t &amp; t</title>"));
  EXPECT_THAT(page, HasSubstr("<h1 id=\"fivebar-scene-x-y\">fivebar scene <code>x&lt;y&gt;</code></h1>"));
  EXPECT_THAT(page, HasSubstr("<strong>bold</strong> text &amp; a <a href=\"patterns/a.csv\">link</a>"));
  EXPECT_THAT(page, Not(HasSubstr("javascript:")));
  EXPECT_THAT(page, HasSubstr("<th>product</th><th class=\"r\">value</th><th class=\"c\">note</th>"));
  EXPECT_THAT(page, HasSubstr("<td><code>a|b</code></td><td class=\"r\">1.5</td>"));
  EXPECT_THAT(page, HasSubstr("&lt;script&gt;alert(1)&lt;/script&gt;"));
  EXPECT_THAT(page, Not(HasSubstr("<script>alert")));
  EXPECT_THAT(page, HasSubstr("<ul>\n<li>one</li>\n<li>two: <a href=\"pics/p.svg\"><code>pics/p.svg</code></a> and "
                              "<code>pics/none.csv</code></li>\n</ul>"));  // a file beside the page is linked
  // The SVG beside the PNG is shown; the animation is inline (its script would not run in an <img>).
  EXPECT_THAT(page, HasSubstr("<img src=\"pics/p.svg\" alt=\"picture\">"));
  EXPECT_THAT(page, HasSubstr("<figure><svg id=\"m\"><script>go()</script></svg>\n<figcaption>movie</figcaption>"));
  EXPECT_THAT(page, Not(HasSubstr("<?xml")));
  // Two headings of one name get two ids; the contents list links both.
  EXPECT_THAT(page, HasSubstr("<h2 id=\"products\">"));
  EXPECT_THAT(page, HasSubstr("<h2 id=\"products-2\">"));
  EXPECT_THAT(page, HasSubstr("<a href=\"#products-2\">"));
  // Offline: nothing is fetched from elsewhere.
  EXPECT_THAT(page, Not(HasSubstr("http")));
}

TEST(HtmlPage, RendersEmphasisCodeTablesAndListsAsCommonMarkDoes) {
  const std::string markdown =
      "# t\n\n"
      "The *exact area* and _the margin_; a region *covers* it; N*mm and 2 * 3 stay as written; `a*b*c` is code.\n\n"
      "1. first\n2. second with **bold**\n\n"
      "| a | b |\n|:--|--:|\n| *x* | `y` |\n";
  md::HtmlFiles files;
  files.exists = [](const std::string&) { return false; };
  files.read = [](const std::string&) -> std::optional<std::string> { return std::nullopt; };
  const std::string page = md::to_html_page(markdown, "t", files);
  EXPECT_THAT(page, HasSubstr("The <em>exact area</em> and <em>the margin</em>; a region <em>covers</em> it; "
                              "N*mm and 2 * 3 stay as written; <code>a*b*c</code> is code."));
  EXPECT_THAT(page, HasSubstr("<ol>\n<li>first</li>\n<li>second with <strong>bold</strong></li>\n</ol>"));
  EXPECT_THAT(page, HasSubstr("<th>a</th><th class=\"r\">b</th>"));
  EXPECT_THAT(page, HasSubstr("<td><em>x</em></td><td class=\"r\"><code>y</code></td>"));
}

// A file of the scene named in code links to itself, once: as a link's text (the products' "Files:"
// lines, [`a/b.json`](a/b.json)) it is that link's, never an anchor inside an anchor (HTML forbids
// nested links; browsers split them).
TEST(HtmlPage, AFileNamedInALinksTextIsOneLink) {
  md::HtmlFiles files;
  files.exists = [](const std::string& f) { return f == "export/a.json" || f == "export/b.yaml"; };
  files.read = [](const std::string&) -> std::optional<std::string> { return std::nullopt; };
  const std::string page = md::to_html_page("# t\n\nFiles: [`export/a.json`](export/a.json), `export/b.yaml`.\n", "t", files);
  EXPECT_THAT(page, HasSubstr("Files: <a href=\"export/a.json\"><code>export/a.json</code></a>, "
                              "<a href=\"export/b.yaml\"><code>export/b.yaml</code></a>."));
  EXPECT_THAT(page, Not(HasSubstr("<a href=\"export/a.json\"><a href")));
}

TEST(HtmlPage, EverySectionShowsThePicturesOfItsProductInline) {
  // The products table lists each product's files; a section names some in links or code, shows
  // others as figures already, and names none at all (simulate): each picture is shown once, in
  // its product's section, linking to its file, with a caption; a CSV or a missing file is not.
  const std::string markdown =
      "# scene\n\n## Products\n\n"
      "| product | state | files |\n|---|---|---|\n"
      "| `simulate` | built | `simulate/a.csv`, `simulate/a.svg`, `simulate/a.png`, `simulate/b.png` |\n"
      "| `tolerance` | built | `tolerance/t.png` |\n"
      "| `collision` | built | `collision/c.png` |\n"
      "| `animate` | built | `animations/m.svg` |\n\n"
      "## Dynamics (`simulate`)\n\nA table only.\n\n"
      "## Tolerance (`tolerance`)\n\nPicture: [tolerance/t.png](tolerance/t.png); also [the gone one](tolerance/gone.png).\n\n"
      "## Collision (`collision`)\n\n![collision map](collision/c.png)\n\n"
      "## Animations (`animate`)\n\n![movie](animations/m.svg)\n";
  const std::vector<std::string> present{"simulate/a.csv", "simulate/a.svg", "simulate/a.png", "simulate/b.png",
                                         "tolerance/t.png", "collision/c.png", "animations/m.svg"};
  md::HtmlFiles files;
  files.exists = [&](const std::string& rel) { return std::find(present.begin(), present.end(), rel) != present.end(); };
  files.read = [](const std::string& rel) -> std::optional<std::string> {
    if (rel == "animations/m.svg") return std::string("<svg id=\"m\"><script>go()</script></svg>\n");
    return std::string("<svg></svg>");
  };
  const std::string page = md::to_html_page(markdown, "t", files);
  const auto count = [&](const std::string& needle) {
    std::size_t n = 0;
    for (std::size_t at = page.find(needle); at != std::string::npos; at = page.find(needle, at + 1)) ++n;
    return n;
  };
  // simulate: a (its SVG shown and linked) and b, after the section's text, before the next section.
  const std::size_t sim = page.find("<h2 id=\"dynamics-simulate\">"), tol = page.find("<h2 id=\"tolerance-tolerance\">");
  const std::size_t a = page.find("<figure><a href=\"simulate/a.svg\"><img src=\"simulate/a.svg\" alt=\"simulate: a.png\"></a>"
                                  "<figcaption>simulate: a.png</figcaption></figure>");
  const std::size_t b = page.find("<img src=\"simulate/b.png\"");
  ASSERT_NE(sim, std::string::npos);
  ASSERT_NE(tol, std::string::npos);
  EXPECT_TRUE(a > sim && a < tol) << page;
  EXPECT_TRUE(b > sim && b < tol) << page;
  EXPECT_EQ(count("src=\"simulate/a."), 1u);
  EXPECT_THAT(page, Not(HasSubstr("<img src=\"simulate/a.csv\"")));
  // tolerance: the linked picture inline once, in its section; the missing one is not.
  const std::size_t t = page.find("<img src=\"tolerance/t.png\"");
  EXPECT_TRUE(t > tol && t < page.find("<h2 id=\"collision-collision\">")) << page;
  EXPECT_EQ(count("<img src=\"tolerance/t.png\""), 1u);
  EXPECT_THAT(page, Not(HasSubstr("<img src=\"tolerance/gone.png\"")));
  // A picture already shown as a figure, and an animation (inline SVG), are not repeated.
  EXPECT_EQ(count("<img src=\"collision/c.png\""), 1u);
  EXPECT_EQ(count("<svg id=\"m\">"), 1u);
  EXPECT_THAT(page, HasSubstr("<figcaption>collision map</figcaption>"));
}

TEST(HtmlPage, CaptionsSayWhatThePictureShows) {
  // Pictures a section does not caption (listed in the products table only, or named by a bare
  // word) get a caption saying what they show, from their product's folder and name; a caption
  // the summary wrote in words stays; a name this table does not know keeps "product: file".
  const std::string markdown =
      "# scene\n\n## Products\n\n"
      "| product | state | files |\n|---|---|---|\n"
      "| `workspace` | built | `workspace/index-workspace.png` |\n"
      "| `optimize` | built | `optimize/hypervolume.png`, `optimize/x-optimized/collision/index.png`, `optimize/odd.png` |\n"
      "| `control` | built | `control/thumb-stability.png` |\n"
      "| `report` | built | `report/accuracy_index_margin.png` |\n\n"
      "## Workspace (`workspace`)\n\n![Station index workspace](workspace/index-workspace.png)\n\n"
      "## Optimize (`optimize`)\n\nText.\n\n"
      "## Control (`control`)\n\n![thumb](control/thumb-stability.png)\n\n"
      "## Report (`report`)\n\n`report/accuracy_index_margin.png`\n";
  md::HtmlFiles files;
  files.exists = [](const std::string&) { return true; };
  files.read = [](const std::string&) -> std::optional<std::string> { return std::string("<svg></svg>"); };
  const std::string page = md::to_html_page(markdown, "t", files);
  EXPECT_THAT(page, HasSubstr("<figcaption>Station index workspace</figcaption>"));
  EXPECT_THAT(page, HasSubstr("<figcaption>Hypervolume of the front (normalised) against the evaluations spent (hypervolume.png)</figcaption>"));
  EXPECT_THAT(page, HasSubstr("<figcaption>Station index of the optimised design: which pairs of tactor targets make the two linkages collide (index.png)</figcaption>"));
  EXPECT_THAT(page, HasSubstr("<figcaption>optimize: odd.png</figcaption>"));
  EXPECT_THAT(page, HasSubstr("<figcaption>Station thumb: spectral radius of the sampled PID loop over the reachable region, the target and its worst pose</figcaption>"));
  EXPECT_THAT(page, HasSubstr("<figcaption>Station index, coverage margin: error against run time of each method (accuracy_index_margin.png)</figcaption>"));
  // No caption is a bare file name any more for the products this table knows.
  EXPECT_THAT(page, Not(HasSubstr("<figcaption>optimize: index.png</figcaption>")));
}

}  // namespace
}  // namespace fivebar
