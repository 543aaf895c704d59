// dicesim.toss_one: one toss of a run, its initial state, result and every impact, as numpy arrays.
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "python/bindings.hpp"
#include "sim/dynamics/flight.hpp"
#include "sim/models/initial_state.hpp"
#include "sim/models/toss.hpp"

namespace dicesim::py {
namespace {

pb::array_t<double> vec(const Vec3& v) { return pb::array_t<double>(3, v.data()); }
pb::array_t<double> mat(const Mat3& m) {
  pb::array_t<double> out({3, 3});
  auto o = out.mutable_unchecked<2>();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) o(i, j) = m(i, j);
  return out;
}

// Translational + rotational kinetic energy and potential energy above the floor (J).
double energy(const DieModel& m, const RigidState& s) {
  const double rot = 0.5 * s.omega.dot(world_inertia(m, s.R) * s.omega);
  return 0.5 * m.mass * s.velocity.squaredNorm() + rot + m.mass * m.gravity * s.position.z();
}

pb::dict state_dict(const DieModel& m, const RigidState& s) {
  pb::dict d;
  d["position"] = vec(s.position);
  d["velocity"] = vec(s.velocity);
  d["R"] = mat(s.R);
  d["omega"] = vec(s.omega);
  d["energy"] = energy(m, s);
  return d;
}

// Per-impact columns of one side (before or after) of the impacts: arrays with the impact first.
pb::dict impact_columns(const DieModel& m, const std::vector<BounceRecord>& trace, bool after) {
  const auto k = static_cast<pb::ssize_t>(trace.size());
  pb::array_t<double> pos({k, pb::ssize_t{3}}), vel({k, pb::ssize_t{3}}), omega({k, pb::ssize_t{3}}),
      R({k, pb::ssize_t{3}, pb::ssize_t{3}}), e(k);
  auto p = pos.mutable_unchecked<2>();
  auto v = vel.mutable_unchecked<2>();
  auto w = omega.mutable_unchecked<2>();
  auto r = R.mutable_unchecked<3>();
  auto en = e.mutable_unchecked<1>();
  for (pb::ssize_t i = 0; i < k; ++i) {
    const RigidState& s = after ? trace[static_cast<std::size_t>(i)].after : trace[static_cast<std::size_t>(i)].before;
    for (int c = 0; c < 3; ++c) {
      p(i, c) = s.position[c];
      v(i, c) = s.velocity[c];
      w(i, c) = s.omega[c];
      for (int d = 0; d < 3; ++d) r(i, c, d) = s.R(c, d);
    }
    en(i) = energy(m, s);
  }
  pb::dict d;
  d["position"] = pos;
  d["velocity"] = vel;
  d["R"] = R;
  d["omega"] = omega;
  d["energy"] = e;
  return d;
}

pb::dict toss_one(Scene& scene, std::uint64_t index, std::uint64_t seed, std::optional<std::string> fidelity, bool trace) {
  const std::shared_ptr<const DieModel> model = scene.model(fidelity);
  if (trace && model->world)
    throw pb::value_error("trace=True follows one die alone: a toss of several dice or among obstacles has no trace yet (docs/world.md)");
  const InitialState init = draw_initial_state(model->throw_, seed, index);
  std::vector<BounceRecord> records;
  TossProbe probe;
  probe.trace = trace ? &records : nullptr;
  TossResult r;
  {
    pb::gil_scoped_release nogil;
    r = toss(*model, seed, index, &probe);  // the very toss number `index` of a run with `seed`
  }
  pb::dict out;
  out["index"] = index;
  out["seed"] = seed;
  out["fidelity"] = to_string(model->fidelity);
  out["face"] = r.face;
  out["face_index"] = r.face_index;
  out["status"] = to_string(r.status);
  out["bounces"] = r.bounces;
  out["t_end"] = r.t_end;
  out["mass"] = model->mass;
  out["gravity"] = model->gravity;

  pb::dict initial;
  initial["com_position"] = vec(init.com_position);
  initial["velocity"] = vec(init.velocity);
  initial["orientation"] = mat(init.orientation);
  initial["omega"] = vec(init.omega);
  out["initial"] = initial;
  out["initial_state"] = state_dict(*model, to_body_state(*model, init));

  if (trace) {
    const auto k = static_cast<pb::ssize_t>(records.size());
    pb::array_t<std::int64_t> bounce(k), vertex(k);
    pb::array_t<double> t(k), impulse(k);
    for (pb::ssize_t i = 0; i < k; ++i) {
      const BounceRecord& b = records[static_cast<std::size_t>(i)];
      bounce.mutable_at(i) = b.bounce;
      vertex.mutable_at(i) = b.vertex;
      t.mutable_at(i) = b.t;
      impulse.mutable_at(i) = b.impulse;
    }
    pb::dict impacts;
    impacts["bounce"] = bounce;
    impacts["t"] = t;
    impacts["vertex"] = vertex;
    impacts["impulse"] = impulse;
    impacts["before"] = impact_columns(*model, records, false);
    impacts["after"] = impact_columns(*model, records, true);
    out["impacts"] = impacts;
  } else {
    out["impacts"] = pb::none();
  }
  return out;
}

}  // namespace

void register_trace(pb::module_& m) {
  m.def("toss_one", &toss_one, pb::arg("scene"), pb::arg("index"), pb::arg("seed") = 1, pb::arg("fidelity") = pb::none(),
        pb::arg("trace") = true,
        "Toss number `index` of a run with `seed` (the same toss that run makes), with its impacts:\n"
        "  face, face_index, status ('settled'/'unresolved'/'invalid'), bounces, t_end (s),\n"
        "  mass (kg), gravity (m/s^2), fidelity, index, seed;\n"
        "  initial: the drawn throw {com_position, velocity, orientation (geometric frame -> world),\n"
        "           omega} (world frame, SI units);\n"
        "  initial_state: the die at release {position, velocity, R (body -> world), omega, energy};\n"
        "  impacts (None unless trace): one entry per impact, as numpy arrays: bounce, t (s since\n"
        "           release), vertex, impulse (N s), and before/after: {position (k,3), velocity (k,3),\n"
        "           R (k,3,3), omega (k,3), energy (k,)} at the instant of contact / right after it.\n"
        "Energy is kinetic (translation and rotation) plus m g z, in J. With fidelity 'paper' the\n"
        "centre of mass flies ballistically between impacts: z(t) = z_i + vz_i (t - t_i) - g (t - t_i)^2 / 2\n"
        "(the other fidelities also roll and slide in sustained contact between recorded impacts).");
}

}  // namespace dicesim::py
