// summary.md as an offline HTML page (products/html.hpp).

#include "products/html.hpp"

#include "fivebar/format.hpp"

// GitHub's CommonMark parser with its pipe tables (Debian libcmark-gfm-dev, libcmark-gfm-extensions-dev):
// the Markdown is parsed by it; this file renders its tree, escaping every text.
#include <cmark-gfm-core-extensions.h>
#include <cmark-gfm.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace fivebar::md {

namespace {

constexpr const char* kStyle = R"CSS(
:root { --ink: #1f2328; --muted: #59636e; --line: #d5dbe3; --accent: #2961c7; --soft: #f3f5f8; }
* { box-sizing: border-box; }
body { margin: 0; background: var(--soft); color: var(--ink);
       font: 15px/1.55 "DejaVu Sans", "Segoe UI", Helvetica, Arial, sans-serif; }
main { max-width: 1200px; margin: 0 auto; padding: 20px 36px 64px; background: #ffffff;
       border-left: 1px solid var(--line); border-right: 1px solid var(--line); min-height: 100vh; }
h1 { font-size: 26px; margin: 8px 0 12px; padding-bottom: 8px; border-bottom: 3px solid var(--accent); }
h2 { font-size: 20px; margin: 40px 0 10px; padding-top: 14px; border-top: 1px solid var(--line); }
h3 { font-size: 16px; margin: 24px 0 8px; }
p, li { max-width: 980px; }
a { color: var(--accent); text-decoration: none; }
a:hover { text-decoration: underline; }
code { font: 12.5px "DejaVu Sans Mono", Menlo, Consolas, monospace; background: #eef1f4; padding: 1px 4px;
       border-radius: 4px; }
.table { overflow-x: auto; margin: 10px 0 20px; }
table { border-collapse: collapse; font-size: 13px; }
th, td { border: 1px solid var(--line); padding: 4px 9px; vertical-align: top; text-align: left; }
th { background: #e9eef6; font-weight: 600; }
tbody tr:nth-child(even) td { background: #f8f9fb; }
.r { text-align: right; font-variant-numeric: tabular-nums; }
.c { text-align: center; }
figure { margin: 16px 0 24px; }
figure img, figure svg { display: block; max-width: 100%; height: auto; border: 1px solid var(--line);
                         border-radius: 6px; background: #ffffff; }
figcaption { color: var(--muted); font-size: 13px; margin-top: 4px; }
.gallery { display: grid; grid-template-columns: repeat(auto-fill, minmax(340px, 1fr)); gap: 4px 20px; }
.gallery figure { margin: 8px 0 16px; }
pre { background: #eef1f4; padding: 8px 12px; border-radius: 6px; overflow-x: auto; }
nav.toc { background: var(--soft); border: 1px solid var(--line); border-radius: 6px; padding: 8px 14px;
          margin: 12px 0 8px; font-size: 13.5px; }
nav.toc ol { margin: 4px 0; padding-left: 22px; columns: 2; }
footer { color: var(--muted); font-size: 12px; margin-top: 48px; border-top: 1px solid var(--line); padding-top: 8px; }
)CSS";

bool starts_with(std::string_view s, std::string_view p) { return s.substr(0, p.size()) == p; }
bool ends_with(std::string_view s, std::string_view p) { return s.size() >= p.size() && s.substr(s.size() - p.size()) == p; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

/// A link target the page may follow: a relative path or a web address (no other scheme).
bool safe_href(std::string_view href) {
  if (starts_with(href, "https://") || starts_with(href, "http://")) return true;
  for (const char c : href) {
    if (c == ':') return false;
    if (c == '/' || c == '?' || c == '#') break;
  }
  return !href.empty();
}

/// A file of the scene the page may read: relative, without "..".
bool local_file(std::string_view src) {
  if (src.empty() || src.front() == '/' || !safe_href(src) || starts_with(src, "http")) return false;
  return src.find("..") == std::string_view::npos && src.find('\\') == std::string_view::npos;
}

std::string slug(std::string_view text) {
  std::string out;
  for (const char c : text) {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } else if (!out.empty() && out.back() != '-') {
      out += '-';
    }
  }
  while (!out.empty() && out.back() == '-') out.pop_back();
  return out.empty() ? "section" : out;
}

/// The text of a node's inline children, without markup (headings' ids, images' alt text).
std::string plain_text(cmark_node* node) {
  std::string out;
  for (cmark_node* c = cmark_node_first_child(node); c != nullptr; c = cmark_node_next(c)) {
    const cmark_node_type type = cmark_node_get_type(c);
    if (type == CMARK_NODE_TEXT || type == CMARK_NODE_CODE || type == CMARK_NODE_HTML_INLINE) {
      const char* literal = cmark_node_get_literal(c);
      out += literal != nullptr ? literal : "";
    } else if (type == CMARK_NODE_SOFTBREAK || type == CMARK_NODE_LINEBREAK) {
      out += ' ';
    } else {
      out += plain_text(c);
    }
  }
  return out;
}

std::string literal_of(cmark_node* node) {
  const char* literal = cmark_node_get_literal(node);
  return literal != nullptr ? literal : "";
}

std::string url_of(cmark_node* node) {
  const char* url = cmark_node_get_url(node);
  return url != nullptr ? url : "";
}

/// The type of a node of a syntax extension ("table", "table_row", "table_header", "table_cell").
std::string_view extension_type(cmark_node* node) {
  const char* type = cmark_node_get_type_string(node);
  return type != nullptr ? std::string_view(type) : std::string_view();
}

bool picture_file(std::string_view path) { return ends_with(path, ".png") || ends_with(path, ".svg"); }

/// "dir/name.png" -> "dir/name": a picture and its vector twin are one picture.
std::string picture_stem(std::string_view path) {
  return std::string(picture_file(path) ? path.substr(0, path.size() - 4) : path);
}

/// What a product's picture shows, from its folder and name (the files the products write, see
/// docs/tour.md); "" for a name this table does not know (the caption is then the file's name).
std::string describe_picture(std::string_view path) {
  const std::string stem = picture_stem(path);
  const std::size_t slash = stem.rfind('/');
  const std::string name = slash == std::string::npos ? stem : stem.substr(slash + 1);
  const std::string dir = slash == std::string::npos ? "" : stem.substr(0, slash);
  const std::string folder = dir.substr(dir.rfind('/') == std::string::npos ? 0 : dir.rfind('/') + 1);
  const bool optimised = dir.find("-optimized") != std::string::npos;
  const std::string of = optimised ? " of the optimised design" : "";
  const auto after = [&](std::string_view prefix) { return name.substr(prefix.size()); };
  const auto ends = [&](std::string_view suffix) {
    return name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  const auto station_of = [&](std::string_view suffix) { return name.substr(0, name.size() - suffix.size()); };
  if (folder == "workspace" && ends("-workspace")) {
    return "Station " + station_of("-workspace") + ": the lower (red) and upper (blue) mechanisms' reachable regions, "
           "their shared region, the target ellipse, the linkages at its centre and the LCI where both reach";
  }
  if (folder == "patterns") return "Station " + name + of + ": each skin-deformation pattern's tactor paths, the links at its start and end";
  if (folder == "collision") return "Station " + name + of + ": which pairs of tactor targets make the two linkages collide";
  if (folder == "control" && ends("-stability")) {
    return "Station " + station_of("-stability") + ": spectral radius of the sampled PID loop over the reachable region, the target and its worst pose";
  }
  if (folder == "tolerance" && ends("-tolerance")) {
    return "Station " + station_of("-tolerance") + ": 3-sigma tactor error and the joints' clearance play over the target, per mechanism";
  }
  if (folder == "simulate") {
    const std::size_t dash = name.find('-');
    if (dash != std::string::npos) {
      return "Station " + name.substr(0, dash) + ", " + name.substr(dash + 1) + ": the simulated tactors against their references over time";
    }
  }
  if (folder == "optimize") {
    if (name == "front") return "The optimisation's front: the objectives of its non-dominated designs";
    if (name == "hypervolume") return "Hypervolume of the front (normalised) against the evaluations spent";
    if (name.rfind("atlas-", 0) == 0) return "Station " + after("atlas-") + " in the performance atlas of the symmetric five-bars";
  }
  if (folder == "sweep") {
    if (name == "sweep_scatter") return "The swept designs' objectives against each other, and how many cover the target";
    if (name == "sweep_heatmap") return "The sweep's first objective over its grid of the two swept dimensions";
  }
  if (folder == "report" && name.rfind("accuracy_", 0) == 0) {
    static const std::vector<std::pair<std::string, std::string>> quantities = {
        {"_area", "workspace area"}, {"_margin", "coverage margin"}, {"_min_lci", "minimum LCI over the target"},
        {"_restricted", "assembly- and LCI-restricted areas"}, {"_tolerance", "3-sigma tactor error"}};
    const std::string what = after("accuracy_");
    if (what == "fk" || what == "ik") return (what == "fk" ? "FK" : "IK") + std::string(": error against a __float128 reference by distance to singularity, per arithmetic");
    if (what == "dynamics") return "Dynamics: each integrator's tracking error against its run time (BDF against explicit Runge-Kutta)";
    if (what == "dynamics_stiffness") return "Dynamics: integrator steps per simulated second as the motor inductance shrinks";
    for (const auto& [suffix, quantity] : quantities) {
      if (what.size() > suffix.size() && what.compare(what.size() - suffix.size(), suffix.size(), suffix) == 0) {
        return "Station " + what.substr(0, what.size() - suffix.size()) + ", " + quantity + ": error against run time of each method";
      }
    }
  }
  return "";
}

/// The parsed Markdown (GitHub-flavoured: CommonMark and pipe tables), freed on scope exit.
class Document {
 public:
  explicit Document(std::string_view markdown) {
    cmark_gfm_core_extensions_ensure_registered();
    parser_ = cmark_parser_new(CMARK_OPT_DEFAULT);
    if (cmark_syntax_extension* table = cmark_find_syntax_extension("table")) {
      cmark_parser_attach_syntax_extension(parser_, table);
    }
    cmark_parser_feed(parser_, markdown.data(), markdown.size());
    root_ = cmark_parser_finish(parser_);
  }
  ~Document() {
    if (root_ != nullptr) cmark_node_free(root_);
    if (parser_ != nullptr) cmark_parser_free(parser_);
  }
  Document(const Document&) = delete;
  Document& operator=(const Document&) = delete;
  cmark_node* root() const { return root_; }

 private:
  cmark_parser* parser_ = nullptr;
  cmark_node* root_ = nullptr;
};

class Renderer {
 public:
  explicit Renderer(const HtmlFiles& files) : files_(files) {}

  /// The picture to show for `src`: the SVG beside a PNG when there is one.
  std::string picture_source(std::string_view src) const {
    std::string s(src);
    if (ends_with(s, ".png") && local_file(s) && files_.exists) {
      const std::string svg = s.substr(0, s.size() - 4) + ".svg";
      if (files_.exists(svg)) return svg;
    }
    return s;
  }

  /// An SVG with a script, to be placed inline; nothing otherwise.
  std::optional<std::string> inline_svg(std::string_view src) const {
    if (!ends_with(src, ".svg") || !local_file(src) || !files_.read) return std::nullopt;
    auto text = files_.read(std::string(src));
    if (!text || text->find("<script") == std::string::npos) return std::nullopt;
    std::size_t start = text->find("<svg");
    if (start == std::string::npos) return std::nullopt;
    return text->substr(start);
  }

  std::string image(std::string_view alt, std::string_view src) const {
    if (!safe_href(src)) return html_escape(alt);
    const std::string pic = picture_source(src);
    return "<a href=\"" + html_escape(pic) + "\"><img src=\"" + html_escape(pic) + "\" alt=\"" + html_escape(alt) + "\"></a>";
  }

  /// A picture as a figure with its caption (inline when it is an animation).
  std::string figure(std::string_view given, std::string_view src) {
    shown_.push_back(picture_stem(src));
    // A caption that is only a word (a station's name, a file's stem) says what is shown instead.
    std::string caption(given);
    if (caption.find(' ') == std::string::npos) {
      if (const std::string shows = describe_picture(src); !shows.empty()) caption = shows;
    }
    std::string body;
    if (auto svg = inline_svg(src)) {
      body = *svg;
      if (!body.empty() && body.back() == '\n') body.pop_back();
      body += "\n";
    } else {
      body = image(caption, src);
    }
    return "<figure>" + body + "<figcaption>" + html_escape(caption) + "</figcaption></figure>\n";
  }

  /// Notes a picture of the scene the current section names (a link or a file in code).
  void named(std::string_view path, std::string_view caption) {
    if (section_product_.empty() || !picture_file(path) || !local_file(path) || !files_.exists ||
        !files_.exists(std::string(path))) {
      return;
    }
    named_.emplace_back(std::string(path), std::string(caption));
  }

  std::string inlines(cmark_node* node) {
    std::string out;
    for (cmark_node* c = cmark_node_first_child(node); c != nullptr; c = cmark_node_next(c)) out += inline_node(c);
    return out;
  }

  std::string inline_node(cmark_node* node) {
    const cmark_node_type type = cmark_node_get_type(node);
    switch (type) {
      case CMARK_NODE_TEXT:
      case CMARK_NODE_HTML_INLINE:  // raw HTML is text here: every text is escaped
        return html_escape(literal_of(node));
      case CMARK_NODE_SOFTBREAK:
        return "\n";
      case CMARK_NODE_LINEBREAK:
        return "<br>\n";
      case CMARK_NODE_CODE: {
        const std::string code = literal_of(node);
        // A file of the scene named in code (the products' file lists) links to it.
        const bool file = code.find('.') != std::string::npos && local_file(code) && files_.exists && files_.exists(code);
        const std::string html = "<code>" + html_escape(code) + "</code>";
        // Inside a link's text it is that link's (no anchor inside an anchor).
        if (!file || in_link_ > 0) return html;
        named(code, code);
        return "<a href=\"" + html_escape(code) + "\">" + html + "</a>";
      }
      case CMARK_NODE_EMPH:
        return "<em>" + inlines(node) + "</em>";
      case CMARK_NODE_STRONG:
        return "<strong>" + inlines(node) + "</strong>";
      case CMARK_NODE_LINK: {
        const std::string target = url_of(node);
        ++in_link_;
        const std::string text = inlines(node);
        --in_link_;
        if (!safe_href(target)) return text;
        named(target, plain_text(node));
        return "<a href=\"" + html_escape(target) + "\">" + text + "</a>";
      }
      case CMARK_NODE_IMAGE: {
        const std::string src = url_of(node);
        if (local_file(src)) shown_.push_back(picture_stem(src));
        return image(plain_text(node), src);
      }
      default:
        break;
    }
    // Anything else inline (an extension's node): its children.
    return inlines(node);
  }

  std::string table(cmark_node* node) {
    const std::uint16_t columns = cmark_gfm_extensions_get_table_columns(node);
    const std::uint8_t* alignments = cmark_gfm_extensions_get_table_alignments(node);
    const auto cls = [&](std::size_t k) -> std::string {
      if (alignments == nullptr || k >= columns) return "";
      if (alignments[k] == 'r') return " class=\"r\"";
      if (alignments[k] == 'c') return " class=\"c\"";
      return "";
    };
    std::string out = "<div class=\"table\"><table>\n";
    bool body = false;
    for (cmark_node* row = cmark_node_first_child(node); row != nullptr; row = cmark_node_next(row)) {
      const bool header = cmark_gfm_extensions_get_table_row_is_header(row) != 0;
      if (header) out += "<thead>";
      if (!header && !body) {
        out += "<tbody>\n";
        body = true;
      }
      out += "<tr>";
      std::size_t k = 0;
      for (cmark_node* cell = cmark_node_first_child(row); cell != nullptr; cell = cmark_node_next(cell), ++k) {
        const char* tag = header ? "th" : "td";
        out += std::string("<") + tag + cls(k) + ">" + inlines(cell) + "</" + tag + ">";
      }
      out += "</tr>";
      out += header ? "</thead>\n" : "\n";
    }
    if (!body) out += "<tbody>\n";
    return out + "</tbody></table></div>\n";
  }

  /// The pictures the section named but did not show, each as a figure (the end of a section).
  std::string gallery() {
    std::vector<std::pair<std::string, std::string>> pictures = named_;
    if (auto row = product_files_.find(section_product_); row != product_files_.end()) {
      for (const std::string& f : row->second) pictures.emplace_back(f, f);
    }
    std::string figures;
    for (const auto& [path, caption] : pictures) {
      const std::string stem = picture_stem(path);
      if (std::find(shown_.begin(), shown_.end(), stem) != shown_.end()) continue;
      if (inline_svg(path)) continue;  // an animation: its own section shows it
      // The PNG when there is one (the SVG beside it is what is shown, the PNG what is linked).
      std::string src = path;
      if (ends_with(path, ".svg") && files_.exists(stem + ".png")) src = stem + ".png";
      const std::string name = src.substr(src.rfind('/') + 1);
      // A caption that is only a name (the file's, a station's) says what the picture shows instead.
      std::string text = caption + " (" + name + ")";
      const bool only_a_name = caption == path || caption.find(' ') == std::string::npos;
      if (const std::string shows = describe_picture(path); only_a_name && !shows.empty()) {
        text = shows + " (" + name + ")";
      } else if (caption == path) {
        text = section_product_ + ": " + name;
      }
      figures += figure(text, src);
    }
    named_.clear();
    if (figures.empty()) return "";
    return "<div class=\"gallery\">\n" + figures + "</div>\n";
  }

  /// The products table's files of each product: its pictures, for the product's section.
  void read_products_table(cmark_node* root) {
    for (cmark_node* n = cmark_node_first_child(root); n != nullptr; n = cmark_node_next(n)) {
      if (extension_type(n) != "table") continue;
      cmark_node* header = cmark_node_first_child(n);
      if (header == nullptr || trim(plain_text(cmark_node_first_child(header))) != "product") continue;
      for (cmark_node* row = cmark_node_next(header); row != nullptr; row = cmark_node_next(row)) {
        cmark_node* first = cmark_node_first_child(row);
        if (first == nullptr) continue;
        const std::string product(trim(plain_text(first)));
        std::vector<std::string>& files = product_files_[product];
        for (cmark_node* cell = cmark_node_next(first); cell != nullptr; cell = cmark_node_next(cell)) {
          for (cmark_node* c = cmark_node_first_child(cell); c != nullptr; c = cmark_node_next(c)) {
            const std::string code = literal_of(c);
            if (cmark_node_get_type(c) == CMARK_NODE_CODE && picture_file(code) && local_file(code) &&
                files_.exists && files_.exists(code)) {
              files.push_back(code);
            }
          }
        }
      }
    }
  }

  /// The product a heading names: "... (`simulate`)" -> "simulate".
  static std::string heading_product(cmark_node* heading) {
    std::string product;
    for (cmark_node* c = cmark_node_first_child(heading); c != nullptr; c = cmark_node_next(c)) {
      if (cmark_node_get_type(c) == CMARK_NODE_CODE) product = literal_of(c);
    }
    return product;
  }

  std::string block(cmark_node* node, bool tight, std::string& toc) {
    const cmark_node_type type = cmark_node_get_type(node);
    switch (type) {
      case CMARK_NODE_HEADING: {
        const int level = cmark_node_get_heading_level(node);
        std::string out;
        if (level <= 2) {
          out += gallery();  // the end of the previous section
          section_product_ = level == 2 ? heading_product(node) : std::string();
        }
        const std::string text = inlines(node);
        std::string id = slug(plain_text(node));
        std::string unique = id;
        for (int k = 2; std::find(ids_.begin(), ids_.end(), unique) != ids_.end(); ++k) unique = id + "-" + std::to_string(k);
        ids_.push_back(unique);
        const std::string h = std::to_string(level);
        out += "<h" + h + " id=\"" + unique + "\">" + text + "</h" + h + ">\n";
        if (level == 2) toc += "<li><a href=\"#" + unique + "\">" + text + "</a></li>";
        return out;
      }
      case CMARK_NODE_PARAGRAPH: {
        cmark_node* only = cmark_node_first_child(node);
        if (only != nullptr && cmark_node_next(only) == nullptr && cmark_node_get_type(only) == CMARK_NODE_IMAGE &&
            !tight) {
          return figure(plain_text(only), url_of(only));
        }
        const std::string text = inlines(node);
        return tight ? text : "<p>" + text + "</p>\n";
      }
      case CMARK_NODE_LIST: {
        const bool ordered = cmark_node_get_list_type(node) == CMARK_ORDERED_LIST;
        const bool list_tight = cmark_node_get_list_tight(node) != 0;
        std::string out;
        if (ordered) {
          const int start = cmark_node_get_list_start(node);
          out += start != 1 ? "<ol start=\"" + std::to_string(start) + "\">\n" : "<ol>\n";
        } else {
          out += "<ul>\n";
        }
        for (cmark_node* item = cmark_node_first_child(node); item != nullptr; item = cmark_node_next(item)) {
          std::string inner;
          for (cmark_node* c = cmark_node_first_child(item); c != nullptr; c = cmark_node_next(c)) {
            inner += block(c, list_tight, toc);
          }
          out += "<li>" + inner + "</li>\n";
        }
        return out + (ordered ? "</ol>\n" : "</ul>\n");
      }
      case CMARK_NODE_CODE_BLOCK:
      case CMARK_NODE_HTML_BLOCK:  // raw HTML is shown as text
        return "<pre><code>" + html_escape(literal_of(node)) + "</code></pre>\n";
      case CMARK_NODE_THEMATIC_BREAK:
        return "<hr>\n";
      case CMARK_NODE_BLOCK_QUOTE: {
        std::string out = "<blockquote>\n";
        for (cmark_node* c = cmark_node_first_child(node); c != nullptr; c = cmark_node_next(c)) out += block(c, false, toc);
        return out + "</blockquote>\n";
      }
      default:
        break;
    }
    if (extension_type(node) == "table") return table(node);
    std::string out;
    for (cmark_node* c = cmark_node_first_child(node); c != nullptr; c = cmark_node_next(c)) out += block(c, tight, toc);
    return out;
  }

  std::string render(std::string_view markdown, std::string& toc) {
    const Document document(markdown);
    if (document.root() == nullptr) return "<p>" + html_escape(markdown) + "</p>\n";
    read_products_table(document.root());
    std::string out;
    for (cmark_node* c = cmark_node_first_child(document.root()); c != nullptr; c = cmark_node_next(c)) {
      out += block(c, false, toc);
    }
    return out + gallery();
  }

 private:
  const HtmlFiles& files_;
  std::vector<std::string> ids_;
  std::vector<std::string> shown_;                               ///< stems of the pictures shown
  std::vector<std::pair<std::string, std::string>> named_;       ///< pictures the section named (path, caption)
  std::string section_product_;                                  ///< the product of the current section
  std::map<std::string, std::vector<std::string>> product_files_;  ///< pictures of each product's row
  int in_link_ = 0;  ///< depth of the links whose text is being rendered
};

}  // namespace

std::string html_escape(std::string_view text) { return format::xml_escape(text); }

std::string to_html_page(std::string_view markdown, std::string_view title, const HtmlFiles& files) {
  Renderer renderer(files);
  std::string toc;
  const std::string body = renderer.render(markdown, toc);
  std::string page = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  page += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  page += "<title>" + html_escape(title) + "</title>\n<link rel=\"icon\" href=\"data:,\">\n";
  page += "<style>" + std::string(kStyle) + "</style>\n</head>\n<body>\n<main>\n";
  // The contents after the page's first heading and its opening paragraphs.
  const std::size_t second = body.find("<h2");
  if (!toc.empty() && second != std::string::npos) {
    page += body.substr(0, second) + "<nav class=\"toc\"><strong>Contents</strong><ol>" + toc + "</ol></nav>\n" +
            body.substr(second);
  } else {
    page += body;
  }
  page += "<footer>This page and summary.md beside it hold the same tables; pictures are the files beside them. "
          "Animations: play/pause, drag the slider, or add <code>#t=SECONDS</code> to the address.</footer>\n";
  page += "</main>\n</body>\n</html>\n";
  return page;
}

}  // namespace fivebar::md
