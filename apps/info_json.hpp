// What `dicesim info --json` prints: the compiled die as one JSON object. Shared by the CLI and the
// Python module (python/), so it lives in dicesim_report, which needs nothing of the CLI.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sim/body/die_model.hpp"
#include "sim/body/material_parts.hpp"

namespace dicesim {

// {"scene", "name", "shape", "convex", "rounding", "read", "vertex_count", "face_count", "outcomes",
//  "mass", "volume", "parts": [{"part" ("base", "region k"), "material", "density", "volume", "mass"}], "com", "inertia", "principal_moments", "principal_axes", "symmetric_top", "bounding_radius",
//  "faces": [{"label", "normal", "area", "stable", "p_static"}], "corners", "fidelity",
//  "fidelity_requested", "fidelity_reason", "rest"}; a cylinder adds "cylinder": {"radius", "height",
//  "rounding", "axis", "labels": {"heads", "tails", "edge"}, "rims": [{"face", "centre", "normal",
//  "radius" (the core rim's), "restitution", "friction", "rolling_resistance",
//  "pivoting_resistance"}]} and per face
//  "direction" (heads, tails, edge) and "curved" (the edge: its "normal" and "area" are null). p_static: the probability of reading the face in
//  `static` with a uniform orientation (its Gauss-map basin; a Fibonacci lattice of
//  kInfoStaticDirections down directions, error ~1e-5).
inline constexpr int kInfoStaticDirections = 200000;
// `parts`: material_parts of the scene (sim/body/material_parts.hpp); "volume" is their sum.
nlohmann::json info_json(const std::string& path, const DieModel& m, const std::vector<MaterialPart>& parts);

}  // namespace dicesim
