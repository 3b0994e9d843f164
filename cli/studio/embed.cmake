# Writes the studio's page, script and style sheet (cli/studio/) into a C++ source of string
# constants, at build time, so that the binary serves them with nothing read from disk.
# cmake -DOUT_DIR=... -DSRC_DIR=... -P embed.cmake
set(names index_html studio_js studio_css)
set(files index.html studio.js studio.css)
set(body "// Generated from cli/studio/ by cli/studio/embed.cmake: do not edit.\n#include \"studio_assets.hpp\"\nnamespace fivebar::cli::studio_assets {\n")
foreach(i RANGE 2)
  list(GET names ${i} name)
  list(GET files ${i} file)
  file(READ "${SRC_DIR}/${file}" hex HEX)
  string(LENGTH "${hex}" n)
  math(EXPR n "${n} / 2")
  string(REGEX REPLACE "([0-9a-f][0-9a-f])" "'\\\\x\\1'," hex "${hex}")
  string(APPEND body "static const char ${name}_bytes[] = {${hex} 0};\nconst std::string_view ${name}(${name}_bytes, ${n});\n")
endforeach()
string(APPEND body "}  // namespace fivebar::cli::studio_assets\n")
file(WRITE "${OUT_DIR}/studio_assets.cpp.tmp" "${body}")
file(COPY_FILE "${OUT_DIR}/studio_assets.cpp.tmp" "${OUT_DIR}/studio_assets.cpp" ONLY_IF_DIFFERENT)
