#pragma once
// The studio's page, script and style sheet (cli/studio/), compiled into the binary at build time
// by cli/studio/embed.cmake (cli/CMakeLists.txt).
#include <string_view>

namespace fivebar::cli::studio_assets {
extern const std::string_view index_html;
extern const std::string_view studio_js;
extern const std::string_view studio_css;
}  // namespace fivebar::cli::studio_assets
