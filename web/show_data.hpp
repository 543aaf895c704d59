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
//  (corner, edge, face, rim), "corners", "impulse", "energy_before", "energy_after"}]}.
// Between impacts flight is exact and torque-free, so poses there are sampled from it every
// `frame_dt` seconds. Sustained contact (`impulse`'s fixed steps between impacts, `stepped`'s
// whole toss) records no states: those stretches are interpolated between the last flight's
// touchdown and the next recorded state, and listed in "interpolated": [[t0, t1]...].
nlohmann::json toss_json(const DieModel& m, std::uint64_t seed, std::uint64_t index, double frame_dt = 1e-3);

}  // namespace dicesim::web
