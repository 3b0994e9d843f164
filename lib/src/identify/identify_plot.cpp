// Measured against fitted (fivebar/identify/identify.hpp identify_plot): the logged position with
// the open-loop simulations of the IDIM-LS and output-error models above, the logged drive with the
// inverse model's prediction below. Drawn on the house canvas (lib/src/plot/tactor_canvas.hpp).

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "fivebar/format.hpp"
#include "fivebar/identify/identify.hpp"
#include "plot/chart.hpp"
#include "plot/tactor_canvas.hpp"

namespace fivebar::identify {

namespace {

using namespace tactor_plot;
using plot::Line;
using plot::decimated_line;

constexpr double kWidth = 1200.0, kHeight = 760.0;

using format::fixed;
using format::general;





}  // namespace

RenderedPlot identify_plot(const JointIdentification& r, bool validation) {
  const Series& s = validation ? r.validation_series : r.series;
  const Fit& fi = validation ? *r.validation_idim : r.estimation_idim;
  const Fit* fo = validation ? (r.validation_oe ? &*r.validation_oe : nullptr) : (r.output_error ? &r.estimation_oe : nullptr);
  Canvas canvas(kWidth, kHeight);
  cairo_t* cr = canvas.cr();
  const std::string pos_unit = r.linear ? "position (m)" : "angle (rad)";
  const std::string drive_unit = r.drive_column;
  text(cr, 20.0, 28.0, "identify — " + r.joint + (validation ? ", validation log" : ", estimation log"), 18.0, kInk, 0.0, true);
  std::string line1 = "position fit (open-loop simulation): IDIM-LS " +
                      (fi.simulated ? (fixed(fi.position_fit_percent, 1) + " %") : std::string("diverged"));
  if (fo) line1 += ", output error " + (fo->simulated ? (fixed(fo->position_fit_percent, 1) + " %") : std::string("diverged"));
  line1 += ";  drive fit (inverse model) " + (fixed(fi.drive_fit_percent, 1) + " %") + ", relative error " +
           (fixed(fi.drive_relative_error_percent, 2) + " %");
  text(cr, 20.0, 50.0, line1, 11.5, kInk);
  const double t_end = s.time.empty() ? 1.0 : s.time.back() - s.time.front();
  plot::time_chart(cr, {90.0, 90.0, kWidth - 120.0, 270.0, "position: measured and simulated", pos_unit, t_end, false, 52.0},
                   {decimated_line(s.time, s.position, kInk, 1.2, false, "measured"),
                    decimated_line(s.time, s.position_idim, kLower, 1.0, false, "IDIM-LS model"),
                    decimated_line(s.time, s.position_oe, kUpper, 1.0, true, "output-error model")});
  plot::time_chart(cr,
                   {90.0, 430.0, kWidth - 120.0, 270.0, "drive: measured (decimated) and predicted by the inverse model",
                    drive_unit, t_end, false, 52.0},
                   {decimated_line(s.drive_time, s.drive, kInk, 1.2, false, "measured"),
                    decimated_line(s.drive_time, s.drive_idim, kLower, 1.0, false, "IDIM-LS prediction")});
  return canvas.render();
}

}  // namespace fivebar::identify
