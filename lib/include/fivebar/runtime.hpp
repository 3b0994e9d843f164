#pragma once
/// The device's control loop as a library (docs/runtime.md): fivebar::runtime, C++17 and the
/// standard library only, configured by the exported JSON. C: fivebar/runtime/c_api.h.
#include "fivebar/runtime/config.hpp"
#include "fivebar/runtime/controller.hpp"
#include "fivebar/runtime/json_config.hpp"
