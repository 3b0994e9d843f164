// fivebar::core from an install prefix: forward kinematics of the paper's index mechanism checked
// against the loop's own constraints (|P - A1| = L3, |P - A2| = L4), and the installed showcase
// design read back. Exit 0 when both hold.
#include <cmath>
#include <cstdio>

#include "fivebar/design.hpp"
#include "fivebar/kinematics.hpp"

int main() {
  fivebar::Mechanism m;
  m.name = "lower";
  m.O1 = {0.0, 0.0};
  m.O2 = {12.5, 0.0};  // the paper's Table 1, index station
  m.L = {9.0, 9.0, 15.0, 15.0};
  m.working_mode = {-1, +1};
  m.assembly_mode = fivebar::AssemblyMode::Plus;
  m.validate();
  const double t1 = 100.0 * M_PI / 180.0, t2 = 80.0 * M_PI / 180.0;
  const fivebar::Pose p = fivebar::fk(m, t1, t2);
  const double a1x = 9.0 * std::cos(t1), a1y = 9.0 * std::sin(t1);
  const double a2x = 12.5 + 9.0 * std::cos(t2), a2y = 9.0 * std::sin(t2);
  const double r3 = std::hypot(p.P.x() - a1x, p.P.y() - a1y), r4 = std::hypot(p.P.x() - a2x, p.P.y() - a2y);
  if (p.status != fivebar::Status::ok || std::fabs(r3 - 15.0) > 1e-9 || std::fabs(r4 - 15.0) > 1e-9 || p.P.y() < a1y) {
    std::fprintf(stderr, "fk: P = (%g, %g), |P-A1| = %.12g, |P-A2| = %.12g\n", p.P.x(), p.P.y(), r3, r4);
    return 1;
  }
  const fivebar::Design d = fivebar::load_design(SHARE_DIR "/designs/iros2022.yaml");
  if (d.stations.size() != 2) {
    std::fprintf(stderr, "designs/iros2022.yaml: %zu stations\n", d.stations.size());
    return 1;
  }
  std::printf("core: P = (%.6f, %.6f) mm, %zu stations\n", p.P.x(), p.P.y(), d.stations.size());
  return 0;
}
