// A world toss's window bound (sim/models/world_windows.hpp, window_for): the first time points
// approaching at `closing` + accel t close `gap`. Moving apart (closing < 0), the gap first grows
// and only gravity's accel brings them back: the window is the later root, finite whenever accel
// is, and never beyond where the gap is really closed.
#include "sim/models/world_windows.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace dicesim::world_detail {
namespace {

// What is left of the gap after t.
double left(double gap, double closing, double accel, double t) { return gap - closing * t - 0.5 * accel * t * t; }

TEST(WorldWindows, TheWindowIsTheFirstTimeTheGapCloses) {
  struct Case {
    double gap, closing, accel;
  };
  const Case cases[] = {{1e-3, 2.0, 9.81}, {1e-3, 0.0, 9.81}, {1e-3, -0.5, 9.81}, {2e-2, -3.0, 4.0},
                        {1e-6, 1e-3, 0.0}, {5e-3, 0.7, 0.0},  {1e-3, -1e-3, 1e-3}};
  for (const Case& c : cases) {
    const double t = window_for(c.gap, c.closing, c.accel);
    ASSERT_TRUE(std::isfinite(t)) << c.gap << " " << c.closing << " " << c.accel;
    // Open up to the window (sampled), closed at it to rounding.
    for (int k = 0; k < 100; ++k) EXPECT_GT(left(c.gap, c.closing, c.accel, t * k / 100.0), 0.0);
    const double scale = c.gap + std::abs(c.closing) * t + 0.5 * c.accel * t * t;
    EXPECT_NEAR(left(c.gap, c.closing, c.accel, t), 0.0, 1e-12 * scale);
  }
}

TEST(WorldWindows, MovingApartWithoutAccelerationNeverCloses) {
  EXPECT_EQ(window_for(1e-3, 0.0, 0.0), std::numeric_limits<double>::infinity());
  EXPECT_EQ(window_for(1e-3, -2.0, 0.0), std::numeric_limits<double>::infinity());
}

// Moving apart fast under a feeble accel, gap + |closing| t and accel t^2 / 2 balance only after a
// long time; a form of the root that subtracts |closing| from sqrt(closing^2 + 2 accel gap) loses
// every digit here (its denominator rounds to 0: an infinite window).
TEST(WorldWindows, MovingApartUnderAFeebleAccelStillMeetsAgain) {
  const double gap = 1e-3, closing = -1.0, accel = 1e-14;
  const double t = window_for(gap, closing, accel);
  ASSERT_TRUE(std::isfinite(t));
  EXPECT_NEAR(t, 2.0 / accel, 1e-6 * (2.0 / accel));
}

}  // namespace
}  // namespace dicesim::world_detail
