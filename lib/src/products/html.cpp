// summary.md as an offline HTML page (products/html.hpp).

#include "products/html.hpp"

#include "fivebar/format.hpp"

#include <algorithm>
#include <cctype>
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

/// "[text](target)" starting at s[i] == '['; the end index past ')' and the parts, or npos.
std::size_t bracket_link(std::string_view s, std::size_t i, std::string_view& text, std::string_view& target) {
  int depth = 0;
  std::size_t j = i;
  for (; j < s.size(); ++j) {
    if (s[j] == '[') ++depth;
    if (s[j] == ']' && --depth == 0) break;
  }
  if (j >= s.size() || j + 1 >= s.size() || s[j + 1] != '(') return std::string_view::npos;
  const std::size_t close = s.find(')', j + 2);
  if (close == std::string_view::npos) return std::string_view::npos;
  text = s.substr(i + 1, j - i - 1);
  target = s.substr(j + 2, close - j - 2);
  return close + 1;
}

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

  std::string inline_text(std::string_view s) const {
    std::string out;
    std::size_t i = 0;
    while (i < s.size()) {
      const char c = s[i];
      if (c == '\\' && i + 1 < s.size() && std::ispunct(static_cast<unsigned char>(s[i + 1]))) {
        out += html_escape(s.substr(i + 1, 1));
        i += 2;
      } else if (c == '`') {
        const std::size_t end = s.find('`', i + 1);
        if (end == std::string_view::npos) {
          out += "`";
          ++i;
          continue;
        }
        const std::string_view code = s.substr(i + 1, end - i - 1);
        // A file of the scene named in code (the products' file lists) links to it.
        const bool file = code.find('.') != std::string_view::npos && local_file(code) && files_.exists &&
                          files_.exists(std::string(code));
        const std::string html = "<code>" + html_escape(code) + "</code>";
        out += file ? "<a href=\"" + html_escape(code) + "\">" + html + "</a>" : html;
        i = end + 1;
      } else if (c == '*' && i + 1 < s.size() && s[i + 1] == '*') {
        const std::size_t end = s.find("**", i + 2);
        if (end == std::string_view::npos) {
          out += "**";
          i += 2;
          continue;
        }
        out += "<strong>" + inline_text(s.substr(i + 2, end - i - 2)) + "</strong>";
        i = end + 2;
      } else if (c == '!' && i + 1 < s.size() && s[i + 1] == '[') {
        std::string_view text, target;
        const std::size_t end = bracket_link(s, i + 1, text, target);
        if (end == std::string_view::npos) {
          out += "!";
          ++i;
          continue;
        }
        out += image(text, target);
        i = end;
      } else if (c == '[') {
        std::string_view text, target;
        const std::size_t end = bracket_link(s, i, text, target);
        if (end == std::string_view::npos) {
          out += "[";
          ++i;
          continue;
        }
        out += safe_href(target) ? "<a href=\"" + html_escape(target) + "\">" + inline_text(text) + "</a>" : inline_text(text);
        i = end;
      } else {
        out += html_escape(s.substr(i, 1));
        ++i;
      }
    }
    return out;
  }

  /// Cells of a table row: split at '|' not escaped by '\'.
  static std::vector<std::string> cells(std::string_view line) {
    line = trim(line);
    if (starts_with(line, "|")) line.remove_prefix(1);
    if (ends_with(line, "|") && !ends_with(line, "\\|")) line.remove_suffix(1);
    std::vector<std::string> out;
    std::string cell;
    for (std::size_t i = 0; i < line.size(); ++i) {
      if (line[i] == '\\' && i + 1 < line.size() && line[i + 1] == '|') {
        cell += '|';  // an escaped pipe is text, also inside code
        ++i;
      } else if (line[i] == '|') {
        out.emplace_back(trim(cell));
        cell.clear();
      } else {
        cell += line[i];
      }
    }
    out.emplace_back(trim(cell));
    return out;
  }

  std::string table(const std::vector<std::string_view>& rows) const {
    const std::vector<std::string> head = cells(rows[0]);
    std::vector<std::string> align;
    if (rows.size() > 1) {
      for (const std::string& a : cells(rows[1])) {
        const bool left = starts_with(a, ":"), right = ends_with(a, ":");
        align.push_back(left && right ? " class=\"c\"" : (right ? " class=\"r\"" : ""));
      }
    }
    const auto cls = [&](std::size_t k) { return k < align.size() ? align[k] : std::string(); };
    std::string out = "<div class=\"table\"><table>\n<thead><tr>";
    for (std::size_t k = 0; k < head.size(); ++k) out += "<th" + cls(k) + ">" + inline_text(head[k]) + "</th>";
    out += "</tr></thead>\n<tbody>\n";
    for (std::size_t r = 2; r < rows.size(); ++r) {
      const std::vector<std::string> row = cells(rows[r]);
      out += "<tr>";
      for (std::size_t k = 0; k < head.size(); ++k) {
        out += "<td" + cls(k) + ">" + (k < row.size() ? inline_text(row[k]) : std::string()) + "</td>";
      }
      out += "</tr>\n";
    }
    return out + "</tbody></table></div>\n";
  }

  /// A line that is one image: a figure (inline when it is an animation).
  std::optional<std::string> figure(std::string_view line) const {
    if (!starts_with(line, "![")) return std::nullopt;
    std::string_view alt, src;
    const std::size_t end = bracket_link(line, 1, alt, src);
    if (end != line.size()) return std::nullopt;
    std::string body;
    if (auto svg = inline_svg(src)) {
      body = *svg;
      if (!body.empty() && body.back() == '\n') body.pop_back();
      body += "\n";
    } else {
      body = image(alt, src);
    }
    return "<figure>" + body + "<figcaption>" + html_escape(alt) + "</figcaption></figure>\n";
  }

  std::string render(std::string_view markdown, std::string& toc) const {
    std::vector<std::string_view> lines;
    std::size_t pos = 0;
    while (pos <= markdown.size()) {
      const std::size_t nl = markdown.find('\n', pos);
      if (nl == std::string_view::npos) {
        if (pos < markdown.size()) lines.push_back(markdown.substr(pos));
        break;
      }
      lines.push_back(markdown.substr(pos, nl - pos));
      pos = nl + 1;
    }
    std::string out;
    std::string paragraph;
    bool in_list = false;
    std::vector<std::string> ids;
    const auto flush = [&]() {
      if (!paragraph.empty()) out += "<p>" + paragraph + "</p>\n";
      paragraph.clear();
      if (in_list) out += "</ul>\n";
      in_list = false;
    };
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const std::string_view line = trim(lines[i]);
      if (line.empty()) {
        flush();
        continue;
      }
      std::size_t level = 0;
      while (level < line.size() && line[level] == '#') ++level;
      if (level >= 1 && level <= 6 && level < line.size() && line[level] == ' ') {
        flush();
        const std::string_view text = trim(line.substr(level + 1));
        std::string id = slug(text);
        std::string unique = id;
        for (int k = 2; std::find(ids.begin(), ids.end(), unique) != ids.end(); ++k) unique = id + "-" + std::to_string(k);
        ids.push_back(unique);
        const std::string h = std::to_string(level);
        out += "<h" + h + " id=\"" + unique + "\">" + inline_text(text) + "</h" + h + ">\n";
        if (level == 2) toc += "<li><a href=\"#" + unique + "\">" + inline_text(text) + "</a></li>";
        continue;
      }
      if (starts_with(line, "|")) {
        flush();
        std::vector<std::string_view> rows;
        while (i < lines.size() && starts_with(trim(lines[i]), "|")) rows.push_back(trim(lines[i++]));
        --i;
        out += table(rows);
        continue;
      }
      if (auto fig = figure(line)) {
        flush();
        out += *fig;
        continue;
      }
      if (starts_with(line, "- ") || starts_with(line, "* ")) {
        if (!paragraph.empty()) {
          out += "<p>" + paragraph + "</p>\n";
          paragraph.clear();
        }
        if (!in_list) out += "<ul>\n";
        in_list = true;
        out += "<li>" + inline_text(trim(line.substr(2))) + "</li>\n";
        continue;
      }
      if (in_list) flush();
      paragraph += (paragraph.empty() ? "" : "\n") + inline_text(line);
    }
    flush();
    return out;
  }

 private:
  const HtmlFiles& files_;
};

}  // namespace

std::string html_escape(std::string_view text) { return format::xml_escape(text); }

std::string to_html_page(std::string_view markdown, std::string_view title, const HtmlFiles& files) {
  const Renderer renderer(files);
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
