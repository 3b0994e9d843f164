#pragma once
/// The `identify` study (docs/identify.md): logs, the motor-rig model, IDIM-LS and output-error
/// fits, excitation planning.
#include "fivebar/identify/identify.hpp"
#include "fivebar/identify/log.hpp"
#include "fivebar/identify/model.hpp"
#include "fivebar/identify/filter.hpp"
#include "fivebar/identify/plan.hpp"
#include "fivebar/identify/json.hpp"
#include "fivebar/identify/patch.hpp"
#include "fivebar/identify/mechanism.hpp"
