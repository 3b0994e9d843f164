// libFuzzer target: the design loader on arbitrary bytes (README "Hardening").
//
// Property: load_design_from_string either returns a design that passes validate() again, or
// throws InputError whose message starts with the origin. Any other exception, a crash, a
// sanitizer report, a hang (-timeout) or a memory blow-up (-rss_limit_mb) is a finding.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>

#include "fivebar/design.hpp"
#include "fivebar/error.hpp"

namespace {

[[noreturn]] void finding(const std::string& what) {
  std::fprintf(stderr, "fuzz_design_loader: %s\n", what.c_str());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::string origin = "fuzz.yaml";
  try {
    const fivebar::Design design = fivebar::load_design_from_string(text, origin);
    try {
      design.validate();
    } catch (const std::exception& e) {
      finding(std::string("a loaded design fails validate(): ") + e.what());
    }
  } catch (const fivebar::InputError& e) {
    const std::string_view message = e.what();
    if (!message.starts_with(origin + ":")) finding("InputError without the file name: " + std::string(message));
    if (message.size() > 4096) finding("InputError message of " + std::to_string(message.size()) + " bytes");
  } catch (const std::exception& e) {
    finding(std::string("unexpected exception (not InputError): ") + e.what());
  } catch (...) {
    finding("unexpected non-standard exception");
  }
  return 0;
}
