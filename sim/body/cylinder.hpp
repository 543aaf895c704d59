// A right circular cylinder (a coin, a rod), axis z, centred at the origin of its geometric frame,
// optionally with both rims rounded: the core cylinder (radius - rounding, height - 2 rounding)
// swept by a ball of radius `rounding`, exactly as a rounded polytope is its core swept by a ball.
// Its volume moments, also cut by half-spaces (density regions), to ~1e-12 relative.
#pragma once

#include <vector>

#include "sim/body/mass_properties.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

struct CylinderShape {
  double radius = 0.0;    // outer radius (m), > 0
  double height = 0.0;    // outer height along z (m), > 0
  double rounding = 0.0;  // radius of the rounded rims (m), in [0, min(radius, height / 2))
  double core_radius() const { return radius - rounding; }
  double core_half() const { return 0.5 * height - rounding; }
};

// Volume moments of the cylinder intersected with every cut (n.x <= d). Each cross-section z =
// const is a disc (radius a, or a - r + sqrt(r^2 - u^2) in a rounded rim) clipped by half-planes,
// whose area moments are exact boundary integrals (Green's theorem over its segments and arcs);
// the integral over z is adaptive Gauss-Kronrod (7/15) between the rims' breakpoints.
VolumeMoments cylinder_moments(const CylinderShape& c, const std::vector<HalfSpace>& cuts);

}  // namespace dicesim
