#pragma once
/// The scene's index.html: summary.md rendered as one HTML page that opens offline (no network, no
/// script or style from elsewhere), in the house style. The Markdown is the subset the products
/// write (products/markdown.hpp): headings, paragraphs, "- " lists, pipe tables with their
/// alignment row, images on a line of their own, and inline code, **bold** and [links](...).
/// Every text is HTML-escaped. A picture with an SVG beside it (same stem) is shown from the SVG;
/// an SVG that carries a script (an animation, fivebar/animation.hpp) is placed inline, since a
/// browser runs no script of an SVG shown through <img>.

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
