// The HTML report and an animation in a real browser: headless Chromium (Debian `chromium`) loads
// index.html from disk with no console message and every animation's script running, every file the
// page names exists beside it, and two screenshots of an animation at two instants (#t=SECONDS)
// differ only where the linkages, tactors and paths of those instants are and match everywhere
// else (PNG pixels decoded with cairo). The page renders the summary's Markdown (no literal `*`
// emphasis) and shows a picture inline for every product that wrote one. Skipped, saying so, when
// Chromium is not installed.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cairo.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include "cli_test.hpp"

namespace {

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using ft::slurp;
using nlohmann::json;
using ::testing::HasSubstr;

const fs::path kChromium = "/usr/bin/chromium";

class Browser : public ft::CliTest {
 protected:
  Browser() : CliTest("fivebar_test_browser") {}

  void SetUp() override {
    if (!fs::exists(kChromium)) GTEST_SKIP() << kChromium << " is not installed (Debian package chromium): browser test skipped";
  }

  /// Chromium headless on `url` with `extra` flags, a new empty profile, no network services.
  Outcome chromium(const std::string& url, std::vector<std::string> extra) {
    const fs::path profile = dir_ / ("profile" + std::to_string(++profiles_));
    std::vector<std::string> args{"--headless",
                                  "--no-sandbox",
                                  "--disable-gpu",
                                  "--disable-quic",
                                  "--no-first-run",
                                  "--disable-background-networking",
                                  "--disable-component-update",
                                  "--disable-sync",
                                  "--disable-extensions",
                                  "--disable-dev-shm-usage",
                                  "--hide-scrollbars",
                                  "--force-device-scale-factor=1",
                                  "--user-data-dir=" + profile.string(),
                                  "--enable-logging=stderr",
                                  "--v=0"};
    args.insert(args.end(), extra.begin(), extra.end());
    args.push_back(url);
    Outcome r = ft::run(kChromium.string(), args, dir_, dir_, 90.0);
    EXPECT_TRUE(r.spawned);
    EXPECT_FALSE(r.timed_out) << r.err;
    return r;
  }

  static std::string file_url(const fs::path& p) { return "file://" + fs::absolute(p).generic_string(); }

  /// The console lines Chromium logged (messages, warnings, uncaught errors of the page).
  static std::vector<std::string> console_lines(const std::string& err) {
    std::vector<std::string> out;
    std::size_t pos = 0;
    while (pos < err.size()) {
      std::size_t nl = err.find('\n', pos);
      if (nl == std::string::npos) nl = err.size();
      const std::string line = err.substr(pos, nl - pos);
      if (line.find(":CONSOLE") != std::string::npos) out.push_back(line);
      pos = nl + 1;
    }
    return out;
  }

  int profiles_ = 0;
};

/// A decoded PNG: ARGB32 pixels.
struct Image {
  int width = 0, height = 0, stride = 0;
  std::vector<unsigned char> data;
  std::uint32_t at(int x, int y) const {
    std::uint32_t v = 0;
    std::memcpy(&v, data.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(stride) + 4u * static_cast<std::size_t>(x), 4);
    return v & 0x00ffffffu;  // the page is opaque; compare colours
  }
};

Image read_png(const fs::path& path) {
  Image img;
  cairo_surface_t* s = cairo_image_surface_create_from_png(path.c_str());
  if (cairo_surface_status(s) == CAIRO_STATUS_SUCCESS) {
    cairo_surface_flush(s);
    img.width = cairo_image_surface_get_width(s);
    img.height = cairo_image_surface_get_height(s);
    img.stride = cairo_image_surface_get_stride(s);
    const unsigned char* p = cairo_image_surface_get_data(s);
    img.data.assign(p, p + static_cast<std::size_t>(img.stride) * static_cast<std::size_t>(img.height));
  }
  cairo_surface_destroy(s);
  return img;
}

struct P2 {
  double x, y;
};

double segment_distance(P2 p, P2 a, P2 b) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double len2 = dx * dx + dy * dy;
  double t = len2 > 0.0 ? ((p.x - a.x) * dx + (p.y - a.y) * dy) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(p.x - (a.x + t * dx), p.y - (a.y + t * dy));
}

json frames_of(const std::string& svg) {
  const std::string open = "<metadata class=\"fivebar-animation-data\">";
  const std::size_t a = svg.find(open);
  const std::size_t b = svg.find("</metadata>", a);
  if (a == std::string::npos || b == std::string::npos) return json();
  return json::parse(svg.substr(a + open.size(), b - a - open.size()));
}

double number_after(const std::string& text, const std::string& key) {
  const std::size_t at = text.find(key);
  return at == std::string::npos ? -1.0 : std::stod(text.substr(at + key.size()));
}

TEST_F(Browser, TheReportLoadsOfflineWithNoConsoleMessageAndEveryAnimationRuns) {
  // The cheap products that write pictures beside the animations: collision, pattern, sweep and
  // tolerance (their pictures named in the products table or in links, shown inline by the page).
  const Outcome run_scene =
      run({"run", kDesign, "--products", "kinematics,animate,collision,sweep,tolerance", "--out", "out", "-q"});
  ASSERT_EQ(run_scene.code, 0) << run_scene.err;
  const fs::path page = dir_ / "out" / "iros2022" / "index.html";
  ASSERT_TRUE(fs::exists(page));
  const std::string html = slurp(page);

  // Offline: the only web address is the SVG namespace; every file named exists beside the page.
  const std::string no_ns = std::regex_replace(html, std::regex("http://www\\.w3\\.org/2000/svg"), "");
  EXPECT_EQ(no_ns.find("http://"), std::string::npos);
  EXPECT_EQ(no_ns.find("https://"), std::string::npos);
  const std::regex link(R"re((?:src|href)="([^"#][^"]*)")re");
  std::size_t named = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), link); it != std::sregex_iterator(); ++it) {
    const std::string target = (*it)[1].str();
    if (target.rfind("data:", 0) == 0) continue;
    ++named;
    EXPECT_TRUE(fs::exists(page.parent_path() / target)) << target;
  }
  EXPECT_GE(named, 8u);  // at least the trajectory CSVs and the pattern pictures

  const Outcome r = chromium(file_url(page), {"--virtual-time-budget=1500", "--dump-dom"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(console_lines(r.err), ::testing::IsEmpty());
  // The DOM after the scripts ran: each of the 8 animations (2 stations x 4 patterns) started.
  std::size_t ready = 0;
  for (std::size_t at = r.out.find("data-fivebar-ready=\"1\""); at != std::string::npos;
       at = r.out.find("data-fivebar-ready=\"1\"", at + 1)) {
    ++ready;
  }
  EXPECT_EQ(ready, 8u);
  EXPECT_THAT(r.out, HasSubstr("<table>"));

  // Every picture the page shows is a picture: a PNG (its signature) or an SVG document.
  const std::regex img(R"re(<img src="([^"]+)")re");
  std::size_t images = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), img); it != std::sregex_iterator(); ++it) {
    const fs::path file = page.parent_path() / (*it)[1].str();
    const std::string bytes = slurp(file);
    ++images;
    const bool png = bytes.rfind("\x89PNG\r\n\x1a\n", 0) == 0;
    const bool svg = file.extension() == ".svg" && bytes.find("<svg") != std::string::npos;
    EXPECT_TRUE(png || svg) << file;
  }
  EXPECT_GE(images, 8u);  // collision and patterns (2 stations), sweep (2), tolerance (2)

  // Markdown emphasis is rendered: no `*word` left in the text Chromium shows (pictures, scripts
  // and code aside); the kinematics section's *LCI* is <em>.
  // (By hand: std::regex recurses per character and overflows the stack on a page this size.)
  std::string text;
  for (std::size_t at = 0; at < r.out.size();) {
    bool skipped = false;
    for (const std::string tag : {"svg", "script", "style", "code"}) {
      if (r.out.compare(at, tag.size() + 1, "<" + tag) == 0) {
        const std::size_t end = r.out.find("</" + tag + ">", at);
        at = end == std::string::npos ? r.out.size() : end + tag.size() + 3;
        text += ' ';
        skipped = true;
        break;
      }
    }
    if (skipped) continue;
    if (r.out[at] == '<') {
      const std::size_t end = r.out.find('>', at);
      at = end == std::string::npos ? r.out.size() : end + 1;
      text += ' ';
      continue;
    }
    text += r.out[at++];
  }
  bool literal_emphasis = false;
  for (std::size_t at = text.find('*'); at != std::string::npos; at = text.find('*', at + 1)) {
    const bool opens = at == 0 || std::isspace(static_cast<unsigned char>(text[at - 1])) || text[at - 1] == '(';
    std::size_t next = at;
    while (next < text.size() && text[next] == '*') ++next;
    if (opens && next < text.size() && std::isalpha(static_cast<unsigned char>(text[next]))) {
      literal_emphasis = true;
      ADD_FAILURE() << "literal emphasis in the page's text: " << text.substr(at, 40);
    }
  }
  EXPECT_FALSE(literal_emphasis);
  EXPECT_THAT(r.out, HasSubstr("<em>LCI</em>"));

  // Every product that wrote a picture shows one inline (an <img> of its folder, or the inline
  // SVG of an animation), each linking to its file.
  const json summary = json::parse(slurp(dir_ / "out" / "iros2022" / "summary.json"));
  std::size_t with_pictures = 0;
  for (const json& b : summary.at("built")) {
    std::vector<std::string> pictures;
    for (const json& f : b.at("files")) {
      const std::string name = f.get<std::string>();
      if (name.size() > 4 && (name.ends_with(".png") || name.ends_with(".svg"))) pictures.push_back(name);
    }
    if (pictures.empty()) continue;
    ++with_pictures;
    const bool shown = std::any_of(pictures.begin(), pictures.end(), [&](const std::string& f) {
      return html.find("<a href=\"" + f + "\"><img src=\"" + f + "\"") != std::string::npos ||
             (f.rfind("animations/", 0) == 0 && html.find("data-fivebar") != std::string::npos);
    });
    EXPECT_TRUE(shown) << b.at("name") << " wrote pictures but the page shows none of them inline";
  }
  EXPECT_GE(with_pictures, 5u);  // collision, pattern, sweep, tolerance, animate
}

TEST_F(Browser, TwoInstantsDifferWhereTheLinkagesAreAndMatchElsewhere) {
  const Outcome made = run({"animate", kDesign, "-s", "index", "--pattern", "twist", "--out", "anim"});
  ASSERT_EQ(made.code, 0) << made.err;
  const std::string svg = slurp(dir_ / "anim" / "index-twist.svg");
  const json d = frames_of(svg);
  ASSERT_TRUE(d.is_object());
  const int width = static_cast<int>(number_after(svg, "width=\""));
  const int height = static_cast<int>(number_after(svg, "height=\""));
  ASSERT_GT(width, 0);

  const std::vector<double> instants{0.15, 0.85};
  std::vector<Image> shots;
  for (const double t : instants) {
    const fs::path png = dir_ / ("t" + std::to_string(shots.size()) + ".png");
    const Outcome r = chromium(file_url(dir_ / "anim" / "index-twist.svg") + "#t=" + std::to_string(t),
                               {"--window-size=" + std::to_string(width) + "," + std::to_string(height),
                                "--virtual-time-budget=1000", "--screenshot=" + png.string()});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_THAT(console_lines(r.err), ::testing::IsEmpty());
    shots.push_back(read_png(png));
    ASSERT_EQ(shots.back().width, width);
    ASSERT_EQ(shots.back().height, height);
  }

  // Where things move, in page pixels: each panel (the station, the enlarged target region) maps
  // mm to pixels by its view in the data.
  const double rate = d["rate_hz"];
  const auto frame = [&](double t) { return static_cast<std::size_t>(std::floor(t * rate + 1e-9)); };
  struct Capsule {
    P2 a, b;
    double r;
  };
  std::vector<Capsule> moving;
  const double aa = 3.0;  // anti-aliasing and rounding
  const double tactor_d = d["tactor_diameter_mm"];
  ASSERT_GT(tactor_d, 0.0);
  for (const json& view : d["views"]) {
    const double x0 = view["x_px"], y0 = view["y_px"];
    const double xmin = view["xmin_mm"], ymax = view["ymax_mm"], scale = view["px_per_mm"];
    const auto px = [&](double x, double y) { return P2{x0 + (x - xmin) * scale, y0 + (ymax - y) * scale}; };
    const double tactor_r = 0.5 * tactor_d * scale;
    for (const json& m : d["mechanisms"]) {
      const P2 O1 = px(m["O1"][0], m["O1"][1]), O2 = px(m["O2"][0], m["O2"][1]);
      for (const double t : instants) {
        const json& f = m["frames"][frame(t)];
        const P2 A1 = px(f[0], f[1]), P = px(f[2], f[3]), A2 = px(f[4], f[5]);
        for (const auto& [a, b] : std::vector<std::pair<P2, P2>>{{O1, A1}, {A1, P}, {P, A2}, {A2, O2}}) {
          moving.push_back({a, b, 2.0 + aa});  // links: 4 px wide
        }
        moving.push_back({A1, A1, 4.0 + 0.75 + aa});  // elbows
        moving.push_back({A2, A2, 4.0 + 0.75 + aa});
        moving.push_back({P, P, tactor_r + 0.75 + aa});
        const json& target = m["targets"][frame(t)];
        moving.push_back({px(target[0], target[1]), px(target[0], target[1]), 2.2 + aa});
      }
      // The tactor path drawn between the two instants (3 px wide).
      for (std::size_t k = frame(instants[0]); k < frame(instants[1]); ++k) {
        const json& f = m["frames"][k];
        const json& g = m["frames"][k + 1];
        moving.push_back({px(f[2], f[3]), px(g[2], g[3]), 1.5 + aa});
      }
    }
  }
  const double controls_y = static_cast<double>(height) - 92.0;  // the slider and the time below the panel
  const auto near_moving = [&](P2 p) {
    return std::any_of(moving.begin(), moving.end(), [&](const Capsule& c) { return segment_distance(p, c.a, c.b) <= c.r; });
  };
  std::size_t differ_near = 0, same_away = 0, differ_away = 0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const P2 p{x + 0.5, y + 0.5};
      if (p.y >= controls_y) continue;
      const bool differ = shots[0].at(x, y) != shots[1].at(x, y);
      if (near_moving(p)) {
        differ_near += differ ? 1 : 0;
      } else if (differ) {
        if (++differ_away <= 5) ADD_FAILURE() << "pixel (" << x << ", " << y << ") changed away from the linkages";
      } else {
        ++same_away;
      }
    }
  }
  EXPECT_EQ(differ_away, 0u);
  EXPECT_GT(same_away, static_cast<std::size_t>(width * (controls_y - 0.0)) / 2);  // most of the picture is background
  EXPECT_GT(differ_near, 2000u);
  // Each elbow and tactor that moved by more than 10 px changed its own pixel (the station's panel).
  const json& view = d["views"][0];
  const double x0 = view["x_px"], y0 = view["y_px"];
  const double xmin = view["xmin_mm"], ymax = view["ymax_mm"], scale = view["px_per_mm"];
  const auto px = [&](double x, double y) { return P2{x0 + (x - xmin) * scale, y0 + (ymax - y) * scale}; };
  for (const json& m : d["mechanisms"]) {
    const json& f0 = m["frames"][frame(instants[0])];
    const json& f1 = m["frames"][frame(instants[1])];
    for (std::size_t j = 0; j < 6; j += 2) {
      const P2 a = px(f0[j], f0[j + 1]), b = px(f1[j], f1[j + 1]);
      if (std::hypot(a.x - b.x, a.y - b.y) < 10.0) continue;
      const int x = static_cast<int>(a.x), y = static_cast<int>(a.y);
      EXPECT_NE(shots[0].at(x, y), shots[1].at(x, y)) << m["name"] << " joint " << j / 2;
    }
  }
}

}  // namespace
