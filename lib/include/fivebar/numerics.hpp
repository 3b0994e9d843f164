#pragma once
/// Named numerical tolerances. Every tolerance is relative: multiply by a length scale
/// (Mechanism::length_scale(), mm) or compare a dimensionless quantity (a sine, a ratio).
/// No algorithm file holds a bare epsilon.

#include <limits>

namespace fivebar::tol {

/// Machine epsilon of double.
inline constexpr double kEps = std::numeric_limits<double>::epsilon();

/// Circles (c1, r1), (c2, r2) meet iff (r1 - r2)^2 <= d^2 <= (r1 + r2)^2, d = |c2 - c1|; the
/// squared distance carries a relative rounding error of a few eps. A d^2 beyond a tangency value
/// by more than kReachRel of it means the circles do not meet (unreachable); within that they are
/// tangent within rounding and the chord height is clamped to 0.
inline constexpr double kReachRel = 16.0 * kEps;

/// |sin| of a joint angle (type I: between a proximal and its distal link; type II: between the
/// two distal links) below which the configuration is reported singular. At |sin| = s the branch
/// position is known to about eps/s of the length scale, and the branch sign itself is
/// undecidable once s approaches sqrt(eps) ~ 1.5e-8; 1e-7 leaves a factor ~7 of guard.
inline constexpr double kSingularSin = 1e-7;

/// Loop closure: an IK branch is accepted when FK of its angles puts each distal link end within
/// kClosureRel * length_scale of its nominal length. Regular poses close to a few eps; near a
/// singularity the angles are only known to ~eps/s, so the bound follows the conditioning.
inline constexpr double kClosureRel = 256.0 * kEps;

/// Two base joints closer than this (relative to the length scale) count as coincident.
inline constexpr double kCoincidentRel = 4.0 * kEps;

// --- Printed parts (fivebar/parts.hpp) ---------------------------------------------------------

/// Design intent of a printed part, measured on its mesh: pin-centre distances, hole diameters and
/// heights must equal the design within this many mm. A manufacturing specification (resin
/// printers hold ~0.05 mm), not a rounding epsilon: binary STL stores float32 coordinates, so a
/// correct part measures within ~1e-5 mm at device sizes.
inline constexpr double kPartDimensionMm = 0.01;

/// Circle fit of a hole wall: a wall vertex further than this fraction of the radius from the
/// fitted circle is not on the circle (a corner where a D-bore's flat cuts the arc) and is dropped
/// before the final fit. Float32 vertices of a true polygon sit within ~1e-6 of the radius.
inline constexpr double kCircleFitRejectRel = 1e-4;

// --- Dynamics (fivebar/dynamics.hpp) ------------------------------------------------------------

/// A duration times a rate within this of a whole number of controller periods counts as that
/// number (0.29 s at 100 Hz is 28.999999999999996 periods in doubles): in periods.
inline constexpr double kSamplePeriodsRel = 1e-9;

}  // namespace fivebar::tol
