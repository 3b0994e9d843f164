#pragma once
/// A runtime Config from the C++ header `fivebar export --format header` writes, for firmware that
/// compiles its configuration in (fivebar/export/export.hpp). The header holds every value twice
/// in one file: as `inline constexpr` constants in namespaces (for code that uses a value at
/// compile time) and as `runtime_json`, the JSON export's text, which the runtime reads here with
/// the reader it uses for the JSON file, through the one key list
/// (fivebar/runtime/config_layout.hpp). `fivebar export --check` refuses a header whose two copies
/// differ.
///
///   #include "iros2022_controller.hpp"
///   #include "fivebar/runtime/header_config.hpp"
///   fivebar::runtime::Config config = FIVEBAR_RUNTIME_CONFIG(fivebar_controller);
///
/// Initialisation only (it allocates); throws ConfigError naming the key as parse_config_json() does.

#include "fivebar/runtime/config.hpp"
#include "fivebar/runtime/json_config.hpp"

/// The Config of the exported header whose node namespace is NS.
#define FIVEBAR_RUNTIME_CONFIG(NS) ::fivebar::runtime::parse_config_json(NS::runtime_json, #NS "::runtime_json (exported header)")
