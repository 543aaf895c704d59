// The contact search's corner pass (two corners per SSE2 instruction) must give exactly the
// numbers of the plain one-corner-at-a-time search it replaced: the pinned counts depend on every
// bit of the contact times. The reference below is that search, written against the public API.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "sim/dynamics/flight.hpp"
#include "sim/models/compile.hpp"
#include "sim/models/toss.hpp"
#include "sim/scene/scene.hpp"

namespace {

using namespace dicesim;

ContactSearch reference_search(const DieModel& m, const RigidState& s, double t_limit) {
  const TorqueFreeRotation rot(m.principal_moments, s.R, world_angular_momentum(m, s.R, s.omega));
  const double g = m.gravity, r = m.bounding_radius;
  const double w_max = rot.max_omega();
  const double A = g + r * (w_max * w_max + rot.max_alpha());
  const double tol = 1e-9 * r;
  ContactSearch out;
  const double clear = s.position.z() - r;
  const double disc = s.velocity.z() * s.velocity.z() + 2.0 * g * clear;
  const double sphere_time = disc >= 0.0 ? (s.velocity.z() + std::sqrt(disc)) / g : 0.0;
  double t = clear > 0.0 ? sphere_time : 0.0;
  for (int it = 0; it < 100000; ++it) {
    out.iterations = it + 1;
    if (t > t_limit) {
      out.outcome = ContactSearch::Outcome::TimeLimit;
      out.t = t_limit;
      return out;
    }
    Mat3 R;
    Vec3 w;
    rot.state(t, R, w);
    const double zc = s.position.z() + s.velocity.z() * t - 0.5 * g * t * t;
    const double vz = s.velocity.z() - g * t;
    if (zc > r && sphere_time > t) {
      t = sphere_time;
      continue;
    }
    double step = std::numeric_limits<double>::infinity();
    int touching = -1;
    double touching_z = std::numeric_limits<double>::infinity();
    for (int i = 0; i < m.vertex_count(); ++i) {
      const Vec3 p = R * m.vertices[static_cast<std::size_t>(i)];
      const double z = zc + p.z() - m.rounding;
      const double zdot = vz + (w.x() * p.y() - w.y() * p.x());
      if (z <= tol && zdot < 0.0) {
        if (z < touching_z) touching = i, touching_z = z;
        continue;
      }
      step = std::min(step, (zdot + std::sqrt(zdot * zdot + 2.0 * A * std::max(z, 0.0))) / A);
    }
    if (touching >= 0) {
      out.outcome = ContactSearch::Outcome::Contact;
      out.t = t;
      out.vertex = touching;
      return out;
    }
    t += std::max(step, 1e-15 * (1.0 + t));
  }
  out.outcome = ContactSearch::Outcome::IterationLimit;
  return out;
}

TEST(FlightSearch, CornerPassIsBitIdenticalToThePlainSearch) {
  // A box (8 corners), a d20 (12), a d4 (4), a prism (6) and a rounded die: even and odd lanes.
  for (const char* scene : {"scenes/paper/die1.toml", "scenes/dice/d20.toml", "scenes/dice/d4.toml",
                            "scenes/dice/prism3.toml", "scenes/dice/loaded-d20.toml"}) {
    const DieModel m = compile(load_scene(std::string(DICESIM_SOURCE_DIR) + "/" + scene));
    int contacts = 0;
    for (std::uint64_t i = 0; i < 300; ++i) {
      RigidState s = to_body_state(m, draw_initial_state(m.throw_, 11, i));
      // The first flight, then one bounce later (a start on the floor, rising).
      for (int leg = 0; leg < 2; ++leg) {
        const Flight f(m, s);
        const ContactSearch got = f.next_contact(m.max_time);
        const ContactSearch want = reference_search(m, s, m.max_time);
        ASSERT_EQ(got.outcome, want.outcome) << scene << " toss " << i << " leg " << leg;
        ASSERT_EQ(got.t, want.t) << scene << " toss " << i << " leg " << leg;  // exact, not near
        ASSERT_EQ(got.vertex, want.vertex) << scene << " toss " << i << " leg " << leg;
        ASSERT_EQ(got.iterations, want.iterations) << scene << " toss " << i << " leg " << leg;
        if (got.outcome != ContactSearch::Outcome::Contact) break;
        ++contacts;
        const RigidState at = f.state(got.t);
        EXPECT_EQ(got.at.R, at.R) << "the state returned is Flight::state at the contact";
        EXPECT_EQ(got.at.omega, at.omega);
        EXPECT_EQ(got.at.position, at.position);
        EXPECT_EQ(got.at.velocity, at.velocity);
        s = at;
        s.velocity.z() = std::abs(s.velocity.z()) * 0.5;  // leave the floor
        s.omega *= 0.7;
      }
    }
    EXPECT_GT(contacts, 400) << scene;
  }
}

}  // namespace
