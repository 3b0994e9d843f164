#pragma once
/// JSON of an identification (docs/schemas/identify.schema.json, one element of "joints").

#include "fivebar/identify/identify.hpp"
#include "fivebar/json.hpp"

namespace fivebar::identify {

/// Parameters (the records), base-parameter estimates with covariance and correlation, the
/// output-error refinement and the fit figures.
Json to_json(const JointIdentification& r);

}  // namespace fivebar::identify
