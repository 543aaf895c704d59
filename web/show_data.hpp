// What `dicesim show` draws, as JSON for the page (web/show.js): the die's geometry, labels,
// material regions and centre of mass, and one toss's poses over time with its impacts.
#pragma once

#include <cstdint>

#include <nlohmann/json.hpp>

#include "sim/body/die_model.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim::web {

// The die in its body frame (principal axes, origin at the centre of mass), metres:
// {"kind": "polytope"|"cylinder", "name", "rounding", "bounding_radius", "read_down",
//  "vertices": [[x,y,z]...] (core corners), "faces": [{"label", "text", "loop": [corner...],
//  "normal"}], "cylinder": {"centre", "axis", "radius", "half"} (curved dice),
//  "geometric_centre": [x,y,z], "regions": [{"material", "polygons": [[[x,y,z]...]...]}]}.
nlohmann::json die_json(const DieModel& m, const SceneDef& def);

// Toss `index` of a run with `seed`: the very toss `dicesim toss`/`toss_one` makes.
// {"seed", "index", "fidelity", "status", "face", "face_index", "outcome", "t_end", "bounces",
//  "frames": [[t, px, py, pz, qx, qy, qz, qw]...] (body -> world), "impacts": [{"t", "kind"
//  (corner, edge, face, rim), "corners", "impulse", "energy_before", "energy_after"}],
//  "steps_recorded", "interpolated": [[t0, t1]...]}.
// Between impacts flight is exact and torque-free, so poses there are sampled from it every
// `frame_dt` seconds. Sustained contact (`impulse`'s fixed steps between impacts, `stepped`'s
// whole toss) is recorded from the stepper (TossProbe::steps_observer): its states as simulated,
// at most one per `frame_dt` of toss time plus each phase's last (the cap: the frames number about
// t_end / frame_dt, whatever the step), "steps_recorded" of them. `stepped`'s coasts (closed-form
// steps high above the floor) are drawn as the exact flight they are. A stretch that could only
// be interpolated (a flight that does not land on the next recorded state: none is expected) is
// listed in "interpolated".
nlohmann::json toss_json(const DieModel& m, std::uint64_t seed, std::uint64_t index, double frame_dt = 1e-3);

}  // namespace dicesim::web
