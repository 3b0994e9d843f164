// fivebar studio: a local page to design a station by hand, with the figures of the command line
// recomputed as a handle is dragged (docs/studio.md). The state and the figures are the library's
// (fivebar/studio.hpp); this file is the HTTP front of it, with cpp-httplib: loopback only, a
// per-run token, Host and Origin checked, assets compiled into the binary, no shell.

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <iterator>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <random>
#include <thread>

#include "common.hpp"
#include "fivebar/csv_reader.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/scene.hpp"
#include "fivebar/studio.hpp"
#include "studio_assets.hpp"

// Last: <httplib.h> brings <resolv.h>, whose macro `_res` would rename a parameter of Eigen's headers.
#include <httplib.h>

namespace fivebar::cli {

namespace {

struct StudioOptions {
  std::string design;
  int port = 0;  ///< 0: a free port
  bool open = false;
  double exit_after_s = -1.0;  ///< < 0: serve until interrupted
};

std::string random_hex(std::size_t bytes) {
  std::random_device rd;  // the kernel's entropy: the token guards the page
  std::string out;
  static const char* kHex = "0123456789abcdef";
  for (std::size_t i = 0; i < bytes; ++i) {
    const unsigned v = rd() & 0xffu;
    out += kHex[v >> 4];
    out += kHex[v & 15u];
  }
  return out;
}

/// Constant-time comparison of the token (its length is public).
bool same_token(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

/// The edits of a request body: [{"key": K, "value": number or string}, ...].
std::vector<FileEdit> edits_of(const Json& body) {
  std::vector<FileEdit> edits;
  if (!body.contains("edits")) return edits;
  if (!body["edits"].is_array()) throw InputError("edits: expected a list");
  for (const Json& e : body["edits"]) {
    if (!e.is_object() || !e.contains("key") || !e["key"].is_string() || !e.contains("value")) {
      throw InputError("edits: each edit is {\"key\": ..., \"value\": ...}");
    }
    const Json& v = e["value"];
    if (v.is_number()) {
      edits.push_back({e["key"].get<std::string>(), v.get<double>()});
    } else if (v.is_string()) {
      edits.push_back({e["key"].get<std::string>(), v.get<std::string>()});
    } else {
      throw InputError("edits: the value of " + e["key"].get<std::string>() + " is neither a number nor a string");
    }
  }
  return edits;
}

std::optional<Vec2> point_of(const Json& body, const char* key) {
  if (!body.contains("cursor") || !body["cursor"].is_object() || !body["cursor"].contains(key)) return std::nullopt;
  const Json& p = body["cursor"][key];
  if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number()) return std::nullopt;
  const Vec2 v{p[0].get<double>(), p[1].get<double>()};
  if (!std::isfinite(v.x()) || !std::isfinite(v.y()) || std::abs(v.x()) > 1e12 || std::abs(v.y()) > 1e12) return std::nullopt;
  return v;
}

void reply(httplib::Response& res, int status, const Json& doc) {
  res.status = status;
  // With the charset, cpp-httplib leaves the answer uncompressed: it would otherwise compress it
  // with brotli at its slowest setting for a browser (measured: 0.27 s for the 99 kB of a drag's
  // figures, 7 times what computing them takes; on the loopback the bytes cost nothing).
  res.set_content(doc.dump(), "application/json; charset=utf-8");
}

/// A scene run started from the page: one at a time, its progress lines and outcome.
struct RunState {
  std::mutex mutex;
  bool running = false;
  std::vector<std::string> lines;
  Json outcome = nullptr;
  std::thread worker;
};

/// The server's shared state: the open file (guarded) and the security settings.
struct Server {
  Studio studio;
  std::mutex mutex;  // guards studio (its text and hash change on save and reload)
  std::string token;
  std::string nonce;
  int port = 0;
  RunState run;
  StudioCache cache;  // figures of the numbers a drag leaves alone (the other mechanism, ...)
  /// The newest drag answer asked for, per page (its random id): a priority request older than it
  /// is answered "stale" without its search (docs/studio.md "Speed").
  std::mutex seq_mutex;
  std::map<std::string, long long> newest_seq;
};

/// Notes the sequence number of a drag request; true when a priority request of `seq` is already
/// stale (a newer drag request of the same page has arrived).
bool note_seq(Server& s, const Json& in, bool priority) {
  const std::string page_id = in.value("page", std::string());
  const long long seq = in.value("seq", 0LL);
  const std::lock_guard<std::mutex> lock(s.seq_mutex);
  if (!s.newest_seq.count(page_id) && s.newest_seq.size() >= 64) s.newest_seq.clear();  // bounded
  long long& newest = s.newest_seq[page_id];
  if (priority) return seq < newest;
  newest = std::max(newest, seq);
  return false;
}

/// Leaves out the loops of the regions the page says it holds (`have_regions`: their ids): an
/// undragged mechanism's region is the same as in the previous answer (docs/studio.md "Speed").
void leave_out_known_regions(Json& figures, const Json& in) {
  if (!in.contains("have_regions") || !in["have_regions"].is_array() || in["have_regions"].size() > 64) return;
  const auto known = [&](const Json& region) {
    if (!region.is_object() || !region.contains("id")) return false;
    for (const Json& id : in["have_regions"]) {
      if (id == region["id"]) return true;
    }
    return false;
  };
  for (Json& m : figures["mechanisms"]) {
    if (known(m["region"])) m["region"]["loops_mm"] = nullptr;
  }
  if (known(figures["shared_region"])) figures["shared_region"]["loops_mm"] = nullptr;
}

/// The figures a request asks for: live, quick, full or priority.
std::optional<StudioFigures> figures_of(const std::string& name) {
  if (name == "live") return StudioFigures::live;
  if (name == "quick") return StudioFigures::quick;
  if (name == "full") return StudioFigures::full;
  return std::nullopt;
}

bool host_allowed(const Server& s, const std::string& host) {
  const std::string port = ":" + std::to_string(s.port);
  return host == "127.0.0.1" + port || host == "localhost" + port;
}

/// Refuses (403) what does not come from the page: a Host other than this address (DNS rebinding),
/// an Origin other than this page's, a missing or wrong token.
httplib::Server::HandlerResponse guard(const Server& s, const httplib::Request& req, httplib::Response& res) {
  const std::string host = req.get_header_value("Host");
  const std::string origin = req.get_header_value("Origin");
  std::string why;
  if (!host_allowed(s, host)) {
    why = "Host refused";
  } else if (!origin.empty() && origin != "http://" + host) {
    why = "Origin refused";
  } else {
    const std::string token = req.has_param("token") ? req.get_param_value("token") : req.get_header_value("X-Fivebar-Token");
    if (!same_token(token, s.token)) why = "token refused";
  }
  if (why.empty()) return httplib::Server::HandlerResponse::Unhandled;
  res.status = 403;
  res.set_content(why + "\n", "text/plain");
  return httplib::Server::HandlerResponse::Handled;
}

std::string page(const Server& s) {
  std::string html(studio_assets::index_html);
  auto put = [&](const std::string& mark, const std::string& text) {
    const std::size_t at = html.find(mark);
    if (at != std::string::npos) html.replace(at, mark.size(), text);
  };
  put("<!--STYLE-->", "<style nonce=\"" + s.nonce + "\">\n" + std::string(studio_assets::studio_css) + "</style>");
  put("<!--SCRIPT-->", "<script nonce=\"" + s.nonce + "\">\n" + std::string(studio_assets::studio_js) + "</script>");
  return html;
}

/// Runs `body` with the request's JSON, answering 400 for a body that is not JSON and 422 with the
/// loader's message for edits it refuses.
template <class Body>
void json_route(httplib::Response& res, const httplib::Request& req, Body body) {
  Json in;
  try {
    in = req.body.empty() ? Json::object() : Json::parse(req.body);
  } catch (const std::exception&) {
    reply(res, 400, {{"error", "the request is not JSON"}});
    return;
  }
  try {
    reply(res, 200, body(in));
  } catch (const InputError& e) {
    reply(res, 422, {{"error", e.what()}});
  } catch (const IoError& e) {
    reply(res, 500, {{"error", e.what()}});
  } catch (const std::exception& e) {
    reply(res, 500, {{"error", std::string("internal error: ") + e.what()}});
  }
}

Json state_json(Server& s) {
  const std::lock_guard<std::mutex> lock(s.mutex);
  const Design d = s.studio.design({});
  Json j = studio_controls(d);
  j["file"] = s.studio.file().filename().string();
  j["sha256"] = s.studio.text_sha256();
  return j;
}

void start_run(Server& s, const Json& in) {
  std::optional<std::vector<std::string>> products;
  if (in.contains("products") && in["products"].is_array() && !in["products"].empty()) {
    products.emplace();
    for (const Json& p : in["products"]) products->push_back(p.get<std::string>());
  }
  Design design = [&] {
    const std::lock_guard<std::mutex> lock(s.mutex);
    return s.studio.design({});  // the saved file: the products of what is on disk
  }();
  const std::lock_guard<std::mutex> lock(s.run.mutex);
  if (s.run.running) throw InputError("a run is already under way");
  if (s.run.worker.joinable()) s.run.worker.join();
  s.run.running = true;
  s.run.lines.clear();
  s.run.outcome = nullptr;
  SceneOptions options;
  options.out_root = s.studio.file().parent_path() / "outputs";  // inside the design's folder
  options.products = products;
  options.jobs = 1;
  s.run.worker = std::thread([&s, design = std::move(design), options]() mutable {
    options.progress = [&s](std::string_view line) {
      const std::lock_guard<std::mutex> l(s.run.mutex);
      s.run.lines.emplace_back(line);
    };
    Json outcome;
    try {
      const SceneReport r = run_scene(design, options);
      const std::filesystem::path rel = std::filesystem::relative(r.index_html, s.studio.file().parent_path() / "outputs");
      outcome = {{"ok", r.ok()}, {"index_html", "out/" + rel.generic_string()}, {"summary", r.to_json()}};
    } catch (const std::exception& e) {
      outcome = {{"ok", false}, {"error", e.what()}};
    }
    const std::lock_guard<std::mutex> l(s.run.mutex);
    s.run.outcome = std::move(outcome);
    s.run.running = false;
  });
}

Json run_status(Server& s) {
  const std::lock_guard<std::mutex> lock(s.run.mutex);
  return {{"running", s.run.running}, {"lines", s.run.lines}, {"outcome", s.run.outcome}};
}

/// Serves a file the run wrote, from `<design folder>/outputs` only.
void serve_output(Server& s, const httplib::Request& req, httplib::Response& res) {
  namespace fs = std::filesystem;
  const fs::path root = fs::weakly_canonical(s.studio.file().parent_path() / "outputs");
  const fs::path want = fs::weakly_canonical(root / fs::path(req.matches[1].str()));
  const auto [r, w] = std::mismatch(root.begin(), root.end(), want.begin(), want.end());
  std::error_code ec;
  if (r != root.end() || !fs::is_regular_file(want, ec)) {
    res.status = 404;
    return;
  }
  std::string body;
  try {
    body = csv::read_bounded(want, std::uintmax_t{256} << 20, "output file");  // bounded as every read
  } catch (const InputError&) {
    res.status = 404;
    return;
  }
  const std::string ext = want.extension().string();
  const char* type = ext == ".html" ? "text/html" : ext == ".svg" ? "image/svg+xml" : ext == ".png" ? "image/png"
                     : ext == ".json" ? "application/json" : "text/plain";
  res.set_content(body, type);
}

void routes(httplib::Server& http, Server& s) {
  http.set_pre_routing_handler([&s](const httplib::Request& req, httplib::Response& res) { return guard(s, req, res); });
  http.set_post_routing_handler([&s](const httplib::Request& req, httplib::Response& res) {
    // The products page of a run carries its own inline pictures, styles and animation scripts;
    // it may fetch nothing.
    res.set_header("Content-Security-Policy",
                   req.path.rfind("/out/", 0) == 0
                       ? std::string("default-src 'none'; img-src data: 'self'; style-src 'unsafe-inline'; script-src 'unsafe-inline'; frame-ancestors 'none'")
                       : "default-src 'none'; script-src 'nonce-" + s.nonce + "'; style-src 'nonce-" + s.nonce +
                             "'; connect-src 'self'; img-src 'self' data:; frame-ancestors 'none'");
    res.set_header("X-Content-Type-Options", "nosniff");
    res.set_header("Cache-Control", "no-store");
    res.set_header("Referrer-Policy", "no-referrer");
  });
  http.Get("/", [&s](const httplib::Request&, httplib::Response& res) { res.set_content(page(s), "text/html; charset=utf-8"); });
  http.Get("/api/state", [&s](const httplib::Request& req, httplib::Response& res) {
    json_route(res, req, [&](const Json&) { return state_json(s); });
  });
  http.Post("/api/figures", [&s](const httplib::Request& req, httplib::Response& res) {
    const auto start = std::chrono::steady_clock::now();
    json_route(res, req, [&](const Json& in) {
      const std::string name = in.value("figures", std::string("live"));
      const bool priority = name == "priority";
      const auto which = figures_of(name);
      if (!which && !priority) throw InputError("figures: expected live, quick, full or priority, not '" + name + "'");
      // A priority request that a newer drag request has overtaken is not searched: its answer
      // would be dropped by the page.
      if (note_seq(s, in, priority)) return Json{{"seq", in.value("seq", 0LL)}, {"stale", true}};
      // A drag's answer sets the edits in the design read once; the sampled figures, asked for when
      // the drag stops, load the edited file, so every rule of the loader has its say then too.
      Design d = [&] {
        const std::lock_guard<std::mutex> lock(s.mutex);
        return which == StudioFigures::full ? s.studio.design(edits_of(in)) : s.studio.live_design(edits_of(in));
      }();
      const std::string station = in.value("station", d.stations.empty() ? std::string() : d.stations.front().name);
      const StudioCursor cursor{point_of(in, "lower"), point_of(in, "upper")};
      Json out = priority ? Json{{"priority", studio_priority(d, station, cursor, &s.cache)}}
                          : studio_figures(d, station, cursor, *which, &s.cache);
      if (!priority) leave_out_known_regions(out, in);
      out["seq"] = in.value("seq", 0LL);
      return out;
    });
    // The server's own time for the answer, which the page sets beside its latency.
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    res.set_header("Server-Timing", "figures;dur=" + format::fixed(ms, 1));
  });
  // A pattern played on the edited state: the edited file loaded (every rule of the loader), then
  // `fivebar pattern`'s check with its samples.
  http.Post("/api/pattern", [&s](const httplib::Request& req, httplib::Response& res) {
    json_route(res, req, [&](const Json& in) {
      const Design d = [&] {
        const std::lock_guard<std::mutex> lock(s.mutex);
        return s.studio.design(edits_of(in));
      }();
      const std::string station = in.value("station", d.stations.empty() ? std::string() : d.stations.front().name);
      return studio_pattern(d, station, in.value("pattern", std::string()));
    });
  });
  http.Post("/api/preview", [&s](const httplib::Request& req, httplib::Response& res) {
    json_route(res, req, [&](const Json& in) {
      const std::lock_guard<std::mutex> lock(s.mutex);
      return s.studio.preview(edits_of(in));
    });
  });
  http.Post("/api/save", [&s](const httplib::Request& req, httplib::Response& res) {
    json_route(res, req, [&](const Json& in) {
      const std::lock_guard<std::mutex> lock(s.mutex);
      const Studio::SaveStatus st = s.studio.save(edits_of(in), in.value("sha256", std::string()));
      if (st == Studio::SaveStatus::changed_on_disk) {
        return Json{{"saved", false}, {"reason", "the file changed on disk since it was read: reload it or save elsewhere"}};
      }
      return Json{{"saved", true}, {"sha256", s.studio.text_sha256()}};
    });
  });
  http.Post("/api/reload", [&s](const httplib::Request& req, httplib::Response& res) {
    json_route(res, req, [&](const Json&) {
      { const std::lock_guard<std::mutex> lock(s.mutex); s.studio.reload(); }
      return state_json(s);
    });
  });
  http.Post("/api/run", [&s](const httplib::Request& req, httplib::Response& res) {
    json_route(res, req, [&](const Json& in) { start_run(s, in); return run_status(s); });
  });
  http.Get("/api/run", [&s](const httplib::Request& req, httplib::Response& res) {
    json_route(res, req, [&](const Json&) { return run_status(s); });
  });
  http.Get(R"(/out/(.+))", [&s](const httplib::Request& req, httplib::Response& res) { serve_output(s, req, res); });
}

int run_studio(const StudioOptions& opt) {
  if (opt.port < 0 || opt.port > 65535) throw InputError("--port " + std::to_string(opt.port) + ": expected 0 to 65535");
  namespace fs = std::filesystem;
  Server s{Studio(fs::absolute(opt.design), validate_products), {}, random_hex(16), random_hex(16), 0, {}, {}, {}, {}};
  httplib::Server http;
  http.set_payload_max_length(1 << 20);
  // An answer is written in pieces (headers, then the body): without this, Nagle's algorithm holds
  // each piece until the page acknowledges the last, which it delays (measured: 0.3 s per answer).
  http.set_tcp_nodelay(true);
  // The page's connections stay open (cpp-httplib closes one after 5 requests by default, and a
  // drag makes some 30 a second): no new connection mid-drag.
  http.set_keep_alive_max_count(100000);
  routes(http, s);
  s.port = opt.port == 0 ? http.bind_to_any_port("127.0.0.1") : (http.bind_to_port("127.0.0.1", opt.port) ? opt.port : -1);
  if (s.port <= 0) throw InputError("--port " + std::to_string(opt.port) + ": cannot listen on 127.0.0.1 there");
  const std::string address = "http://127.0.0.1:" + std::to_string(s.port) + "/?token=" + s.token;
  std::cout << address << std::endl;
  std::cerr << "fivebar studio: serving " << s.studio.file().filename().string() << " (Ctrl-C stops)\n";
  if (opt.open) {
    // xdg-open with the address as one argument: no shell reads it.
    if (fork() == 0) {
      execlp("xdg-open", "xdg-open", address.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
  }
  std::thread stopper;
  if (opt.exit_after_s >= 0.0) {
    stopper = std::thread([&http, secs = opt.exit_after_s] {
      while (!http.is_running()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
      std::this_thread::sleep_for(std::chrono::duration<double>(secs));
      http.stop();
    });
  }
  http.listen_after_bind();
  if (stopper.joinable()) stopper.join();
  const std::lock_guard<std::mutex> lock(s.run.mutex);
  if (s.run.worker.joinable()) s.run.worker.detach();
  return kOk;
}

}  // namespace

void setup_studio(CLI::App& app) {
  auto [sub, opt] = add_command<StudioOptions>(
      app, "studio",
      "Design a station by hand in the browser: a local page with the station at true scale, handles and sliders, and "
      "the coverage, regions and collision figures recomputed as you drag; saves keep the file's comments",
      run_studio);
  add_design_argument(*sub, opt->design);
  sub->add_option("--port", opt->port, "Port on 127.0.0.1 (default: a free one)");
  sub->add_flag("--open", opt->open, "Open the page in the desktop's browser (xdg-open); by default only its address is printed");
  sub->add_flag_function("--no-open", [o = opt](std::int64_t) { o->open = false; }, "Do not open a browser (the default)");
  sub->add_option("--exit-after", opt->exit_after_s, "Stop serving after this many seconds (scripts, tests); default: until interrupted")
      ->type_name("S");
  sub->footer("Prints the page's address (with its token) on stdout. Only files in the design's folder are read or written.\n" +
              exit_status({.ok = "served until stopped", .writes = true}));
}

}  // namespace fivebar::cli
