#pragma once
/// The scene's index.html: summary.md rendered as one HTML page that opens offline (no network, no
/// script or style from elsewhere), in the house style. The Markdown is parsed by cmark-gfm
/// (CommonMark with GitHub's pipe tables: emphasis, code, links, lists, tables with their
/// alignment); the page's HTML is rendered here from its tree, every text HTML-escaped (raw HTML
/// in the Markdown is shown as text). An image alone in its paragraph is a figure with its caption;
/// a picture with an SVG beside it (same stem) is shown from the SVG, linking to it; an SVG that
/// carries a script (an animation, fivebar/animation.hpp) is placed inline, since a browser runs no
/// script of an SVG shown through <img>. At the end of each product's section (a level-2 heading
/// naming the product in code, "... (`simulate`)") every picture the product wrote (its row of the
/// products table) or the section names (a link, a file in code) and did not show yet is shown as a
/// figure with a caption, so that no result is only a link.

#include <functional>
#include <optional>
#include <string>
#include <string_view>

namespace fivebar::md {

/// How the page reaches the files beside it (paths relative to the page, '/'-separated).
struct HtmlFiles {
  /// True when the file exists.
  std::function<bool(const std::string&)> exists;
  /// The file's text, or nothing when it cannot be read.
  std::function<std::optional<std::string>(const std::string&)> read;
};

/// Text with &, <, >, " and ' escaped.
std::string html_escape(std::string_view text);

/// The whole page: `<!DOCTYPE html>` ... with `title` in <title> and the rendered `markdown`.
std::string to_html_page(std::string_view markdown, std::string_view title, const HtmlFiles& files);

}  // namespace fivebar::md
