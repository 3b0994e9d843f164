#pragma once
/// The `contact:` section of a design file: the fingertip skin under each tactor, as a shear
/// spring-damper anchored where the tactor first touches, sliding (Coulomb) when the spring force
/// exceeds mu times the normal preload (the model is in fivebar/dynamics.hpp). One module of the
/// design (docs/architecture.md "Design sections"): loader and writer in
/// lib/src/sections/contact.cpp; `design.get<ContactSettings>()`.
///
/// The paper gives no skin data: every default is an ASSUMPTION to replace with measurements of
/// the fingertips and tactors in use.

#include <string_view>

#include "fivebar/design.hpp"

namespace fivebar {

struct ContactSettings {
  static constexpr std::string_view kKey = "contact";
  double shear_stiffness_N_per_mm = 1.0;     ///< k, tangential stiffness of the skin (assumption)
  double damping_N_s_per_mm = 0.005;         ///< c, tangential damping (assumption)
  double friction_coefficient = 1.0;         ///< mu, tactor on skin (assumption)
  double normal_preload_N = 0.5;             ///< N, force pressing the finger on the tactor (assumption)
  /// Throws ValidationError naming the key.
  void validate() const;
};

}  // namespace fivebar
