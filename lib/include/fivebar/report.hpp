#pragma once
/// How accurate is each answer, what does the accuracy cost, and does the tool stay sound where
/// mechanisms are hard: `fivebar report accuracy` (work-precision) and `fivebar report stability`
/// (a catalogue of extreme cases).
///
/// References. Kinematics, closed-form areas and ellipse margins are recomputed in IEEE binary128
/// (__float128, lib/src/report/quad.hpp) by formulas written independently of the library's; the
/// reachable area's reference is the exact CGAL region; sampled (assembly- and LCI-restricted)
/// regions are measured against the same method on a 16x finer grid; the sampled coverage
/// quantities against coverage().
///
/// Work-precision. Every approximate method is run at increasing resolution; each point is the
/// median wall time of repeated runs after a warm-up and the error against the reference. The
/// convergence order is the least-squares slope of log(error) against log(resolution).
///
/// Stability. Each case states the library's status, its error against the quad reference, and
/// the error the problem's conditioning allows (the bound; derivations in lib/src/report/stability.cpp).
/// It passes when every number is finite, the status is one the reference allows and the error is
/// within the bound. A case whose bound is large (few correct digits are possible in double
/// precision) is flagged ill_conditioned with the reason; it can still pass.

#include "fivebar/report/accuracy.hpp"
#include "fivebar/report/stability.hpp"
