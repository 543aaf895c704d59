// Coefficient of restitution from drop measurements (the seed's sec. 5.1): from pairs of
// speeds just before and after impacts, or from a height-against-time track of a bouncing die,
// where a parabola is fitted to each flight and the two parabolas around an impact give the
// speeds at the impact instant. Estimate: the mean of the per-impact ratios |v_out| / |v_in|,
// with a 95% Student-t interval (n >= 2). Pure computation: nothing here prints.
#pragma once

#include <cstddef>
#include <vector>

#include "sim/study/statistics.hpp"

namespace dicesim {

struct RestitutionEstimate {
  double restitution = 0.0;   // mean ratio
  Interval ci95;              // mean +- t(0.975, n-1) sd / sqrt(n)
  std::size_t n = 0;          // impacts used
  double sd = 0.0;            // sample standard deviation of the ratios
  std::vector<double> ratios;
};

// Speeds before (v_in) and after (v_out) each impact; signs are ignored (speeds). Throws
// std::invalid_argument for fewer than 2 pairs, a zero or non-finite speed.
RestitutionEstimate restitution_from_pairs(const std::vector<double>& v_in, const std::vector<double>& v_out);

// One impact found in a track.
struct TrackImpact {
  double t = 0.0;       // impact instant (s): where the two flight parabolas meet
  double v_in = 0.0;    // vertical velocity just before (m/s, < 0)
  double v_out = 0.0;   // just after (> 0)
  double ratio = 0.0;   // -v_out / v_in
  double g_before = 0.0, g_after = 0.0;  // -2 x the fitted quadratic coefficients (m/s^2), a check
};

struct TrackFit {
  std::vector<TrackImpact> impacts;
  RestitutionEstimate estimate;
};

// Height z (m) against time t (s), strictly increasing t. Impacts are the local minima of z
// near the floor (within 5% of the height range of the lowest sample) where the sampled
// velocity (from two samples before to one after) jumps upward by more than free flight and 4
// standard deviations of sampling noise (estimated robustly from all slope changes). Each flight between impacts (at least 3 samples, the minimum
// samples left out) gets a least-squares parabola; an impact whose flights do not fit a parabola
// to within 5x the noise is left out. Throws std::invalid_argument when fewer than 2 usable
// impacts are found.
TrackFit restitution_from_track(const std::vector<double>& t, const std::vector<double>& z);

}  // namespace dicesim
