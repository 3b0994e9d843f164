#pragma once
/// Kinematic calibration (docs/calibrate.md): measurements, the model, the fit with its
/// identifiability, the pose planner and the outputs.
#include "fivebar/calibrate/fit.hpp"
#include "fivebar/calibrate/measurements.hpp"
#include "fivebar/calibrate/model.hpp"
#include "fivebar/calibrate/plan.hpp"
#include "fivebar/calibrate/report.hpp"
#include "fivebar/calibrate/hard_stops.hpp"
