// dicesim info: what the scene compiles to: mass properties, principal frame, faces, corners.
#include <cmath>
#include <algorithm>
#include <cstdio>
#include <thread>
#include <vector>

#include "apps/commands.hpp"
#include "apps/info_json.hpp"
#include "apps/report.hpp"
#include "sim/body/die_model.hpp"
#include "sim/body/material_parts.hpp"
#include "sim/body/outcome.hpp"
#include "sim/body/world.hpp"
#include "sim/models/compile.hpp"
#include "sim/models/fidelity_models.hpp"
#include "sim/study/auto_pilot.hpp"

namespace dicesim {
namespace {

Vec3 geometric_normal(const DieModel& m, std::size_t f) { return m.geo_to_body.transpose() * m.face_normals[f]; }

// Which outcome each resting face gives, and which outcomes the die's symmetry makes alike.
void print_outcome_map(const DieModel& m) {
  std::printf("\nresting on face -> outcome read%s\n", m.read_down ? " (the face on the floor)" : "");
  std::string row;
  for (int f = 0; f < m.face_count(); ++f) {
    row += (row.empty() ? "  " : "   ") + std::to_string(f) + " -> " + std::to_string(resting_outcome_label(m, f));
    if (row.size() > 90 || f + 1 == m.face_count()) {
      std::printf("%s\n", row.c_str());
      row.clear();
    }
  }
  for (const int f : m.own_read_faces)
    std::printf("  face %d reads its own label %d: resting on it, no single face is up (several tie)\n", f,
                m.face_labels[static_cast<std::size_t>(f)]);
  const auto groups = alike_groups(m);
  std::string text;
  for (const auto& g : groups) {
    text += text.empty() ? "" : " | ";
    for (std::size_t k = 0; k < g.size(); ++k) text += (k ? ", " : "") + std::to_string(g[k]);
  }
  std::printf("alike by design    %s\n  (%s)\n", groups.empty() ? "none: no outcome is tested against another" : text.c_str(),
              m.alike_note.c_str());
}

// One format per kind of number, as in `toss`: SI quantities with 6 significant digits (%.6g),
// unit directions with 4 decimals, probabilities with 5.
void print_info(const std::string& path, const DieModel& m, const FloorDef& floor, const std::vector<MaterialPart>& parts) {
  const MassProperties& mp = m.mass_geometric;
  double volume = 0.0;
  for (const MaterialPart& p : parts) volume += p.volume;
  std::printf("%s%s%s\n\n", path.c_str(), m.name.empty() ? "" : ": ", m.name.c_str());
  if (m.world)
    std::printf("world              %d dice, %zu obstacle pieces; %d outcomes (%s), labels %d to %d; below: the first die\n",
                m.world->size(), m.world->pieces.size(), m.outcomes(),
                m.world->kind == OutcomeKind::Sum ? "sums" : "tuples", m.outcome_labels.front(), m.outcome_labels.back());
  std::printf("shape              %s: %d corners, %d faces, %d outcomes, read %s%s\n", m.kind.c_str(), m.vertex_count(),
              m.face_count(), m.outcomes(), m.read_down ? "down (the face on the floor)" : "up",
              m.convex ? "" : "  (not convex: contact uses its hull)");
  if (m.curved())
    std::printf("cylinder           radius %.6g m, height %.6g m; faces: 0 heads (+z), 1 tails (-z), 2 the curved side (edge)\n",
                m.rims.radius + m.rounding, 2.0 * (m.rims.half + m.rounding));
  if (m.rounding > 0.0) std::printf("rounding           %.6g m (%s)\n", m.rounding, m.curved() ? "rims" : "edges and corners");
  std::printf("volume             %.6g m^3 (%.6g cm^3)\n", volume, 1e6 * volume);
  std::printf("mass               %.6g kg (%.6g g)\n", mp.mass, 1e3 * mp.mass);
  std::printf("centre of mass     (%+.6g, %+.6g, %+.6g) m from the geometric centre (%.6g mm off)\n", mp.com.x(), mp.com.y(),
              mp.com.z(), 1e3 * mp.com.norm());
  std::printf("inertia about COM  [%+13.6g %+13.6g %+13.6g]\n", mp.inertia(0, 0), mp.inertia(0, 1), mp.inertia(0, 2));
  std::printf("  (kg m^2,         [%+13.6g %+13.6g %+13.6g]\n", mp.inertia(1, 0), mp.inertia(1, 1), mp.inertia(1, 2));
  std::printf("   geometric axes) [%+13.6g %+13.6g %+13.6g]\n", mp.inertia(2, 0), mp.inertia(2, 1), mp.inertia(2, 2));
  std::printf("principal moments  %.6g  %.6g  %.6g kg m^2%s\n", mp.principal_moments[0], mp.principal_moments[1],
              mp.principal_moments[2], m.symmetric_top ? "  (symmetric top: closed-form flight)" : "");
  for (int k = 0; k < 3; ++k)
    std::printf("  axis %d           (%+.4f, %+.4f, %+.4f)\n", k + 1, mp.principal_axes(0, k), mp.principal_axes(1, k),
                mp.principal_axes(2, k));
  std::printf("bounding radius    %.6g m (COM to farthest point)\n\n", m.bounding_radius);
  // What the die is made of: a maker checks an insert's volume and mass here.
  std::printf("parts (the base material is all that no region covers; regions: intersections of half-spaces)\n");
  std::printf("  part       material          density (kg/m^3)  volume (cm^3)  mass (g)      share of mass\n");
  for (const MaterialPart& p : parts)
    std::printf("  %-10s %-17s %-17.6g %-14.6g %-13.6g %.4f\n", p.what.c_str(), p.material.c_str(), p.density,
                1e6 * p.volume, 1e3 * p.mass, mp.mass > 0 ? p.mass / mp.mass : 0.0);
  std::printf("\n");
  const std::vector<double> p_static = static_face_probabilities(m, kInfoStaticDirections);
  std::printf("faces (outward normal in the geometric frame; area of the flat face; can it hold the die;\n"
              "p_static: probability of reading it in `static` with a uniform orientation; COM height resting on it;\n"
              "lowest COM height out of its basin)\n");
  std::printf("  face  label  normal                     area (m^2)    stable  p_static  height (m)    escape (m)\n");
  for (std::size_t f = 0; f < m.face_normals.size(); ++f) {
    const Vec3 n = geometric_normal(m, f);
    char normal[64];
    // A coin's side (edge) has no single normal and no flat area: say what it is instead.
    const bool side = m.curved() && f == 2;
    if (side)
      std::snprintf(normal, sizeof normal, "%s", "any, perpendicular to axis");
    else
      std::snprintf(normal, sizeof normal, "(%+.4f, %+.4f, %+.4f)", n.x(), n.y(), n.z());
    char area[32];
    if (side)
      std::snprintf(area, sizeof area, "%s", "- (curved)");
    else
      std::snprintf(area, sizeof area, "%.6g", m.face_area[f]);
    std::printf("  %4zu  %5d  %-26s %-13s %-7s %.5f   %-13.6g", f, m.face_labels[f], normal, area,
                m.face_hold[f] >= 0.0 ? "yes" : "no", p_static[f], m.face_height[f]);
    if (std::isfinite(m.face_escape[f]))
      std::printf(" %.6g\n", m.face_escape[f]);
    else
      std::printf(" %s\n", m.face_hold[f] >= 0.0 ? "none (the only basin)" : "-");
  }
  // Where a neighbouring basin reads the same, the outcome settles below a higher pass (rest.hpp).
  for (std::size_t f = 0; f < m.face_normals.size(); ++f)
    if (m.outcome_escape[f] != m.face_escape[f])
      std::printf("face %zu: a neighbouring basin also reads %d; the lowest pass to another outcome is %.6g m "
                  "(a toss settles below it)\n",
                  f, resting_outcome_label(m, static_cast<int>(f)),
                  m.outcome_escape[f]);
  print_outcome_map(m);
  // Where the two numbers come from: the materials at the corner, or the scene's [floor] values.
  auto source = [](const char* what, bool from_floor) {
    return std::string(what) + (from_floor ? ": [floor] " + std::string(what) + " for every contact" : ": volume mix of the materials at the corner");
  };
  if (!m.vertices.empty()) {
    std::printf("\ncorners (%s; %s)\n", source("restitution", floor.restitution.has_value()).c_str(),
                source("friction", floor.friction.has_value()).c_str());
    for (std::size_t c = 0; c < m.vertices.size(); ++c) {
      const Vec3 geo = m.geo_to_body.transpose() * m.vertices[c] + mp.com;
      std::printf("  %4zu  (%+.6g, %+.6g, %+.6g) m  e = %.4f  mu = %.4f\n", c, geo.x(), geo.y(), geo.z(),
                  m.vertex_restitution[c], m.vertex_friction[c]);
    }
  }
  if (m.curved()) {
    // A cylinder has no corners: it touches the floor with its rims (heads' and tails'), whose
    // points the contact follows; a landing on the edge is a rest on the curved side between them.
    std::printf("\nrims (no corners: contact is on these two core circles, swept by the rounding; the edge outcome\n"
                "is the curved side between them; restitution, friction, rolling and pivoting resistance)\n");
    for (int k = 0; k < 2 && 3 * k < static_cast<int>(m.vertex_rolling.size()); ++k) {
      const double sgn = k == 0 ? 1.0 : -1.0;
      const Vec3 c = m.geo_to_body.transpose() * (m.rims.centre + sgn * m.rims.half * m.rims.axis) + mp.com;
      const std::size_t v = static_cast<std::size_t>(3 * k);
      std::printf("  %-5s centre (%+.6g, %+.6g, %+.6g) m  radius %.6g m  e = %.4f  mu = %.4f  rolling %.6g m  pivoting %.6g m\n",
                  kCylinderOutcomeNames[static_cast<std::size_t>(k)], c.x(), c.y(), c.z(), m.rims.radius,
                  m.vertex_restitution[v], m.vertex_friction[v], m.vertex_rolling[v],
                  m.vertex_pivoting[v]);
    }
  }
  std::printf("\nfidelity           %s", to_string(m.fidelity));
  if (m.fidelity_requested == Fidelity::Auto) std::printf(" (chosen by auto)");
  std::printf("\n  why              %s\n", m.fidelity_reason.c_str());
}

void print_pilot(const FidelityPilot& p) {
  if (!p.ran) return;
  // Its cost in tosses, not seconds: info prints the same for the same inputs (toss reports the time).
  std::printf("  pilot            %llu tosses (seed %llu; full size %llu pairs, cap %llu)\n",
              static_cast<unsigned long long>(p.tosses), static_cast<unsigned long long>(p.seed),
              static_cast<unsigned long long>(p.max_pairs), static_cast<unsigned long long>(p.cap));
  for (const PilotCandidate& c : p.candidates)
    std::printf("    %-8s       differs from impulse in %llu of %llu pairs: bias <= %.3g (upper 95%%), %s\n",
                to_string(c.model), static_cast<unsigned long long>(c.differing), static_cast<unsigned long long>(c.pairs),
                c.bound, c.adequate ? "adequate" : "not adequate");
  std::printf("    adequate when  bias < %.3g = %.2g x the half-width %.3g of %s\n", p.threshold, p.fraction,
              p.halfwidth, p.precision.c_str());
}

}  // namespace

void register_info(CLI::App& app, int& exit_code) {
  struct Args {
    SceneArgs scene;
    bool json = false;
    std::uint64_t tosses = 100000;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "info",
      "Compile a scene and print the die's exact mass, centre of mass, inertia tensor about the\n"
      "COM (products of inertia included), principal moments and axes, and per face its label,\n"
      "outward normal, area, whether the die can rest on it and its `static` probability.\n\n"
      "Example:  dicesim info scenes/paper/die3.toml --json");
  args->scene.add_to(cmd);
  cmd->add_flag("--json", args->json, "One JSON object: shape, vertex_count, face_count, faces [{label, normal, area, stable,\n"
                "p_static}], mass, com, inertia (3x3), principal_moments, ...");
  cmd->add_option("-n,--tosses", args->tosses,
                  "The run size a scene that names no fidelity (auto) is judged for: its pilot decides as\n"
                  "`dicesim toss -n N` would")
      ->capture_default_str()
      ->check(CLI::Range(1ULL, 1ULL << 40));
  cmd->callback([args, &exit_code] {
    const SceneDef def = args->scene.load();
    DieModel m = compile(def, args->scene.path);
    const std::vector<MaterialPart> parts = material_parts(def, args->scene.path);
    const FidelityPilot pilot =
        resolve_auto(m, precision_of_run(m, args->tosses), static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
    if (args->json) {
      nlohmann::json j = info_json(args->scene.path, m, parts);
      j["pilot"] = pilot_json(pilot);
      if (j["pilot"].is_object()) j["pilot"].erase("seconds");  // the same output for the same inputs
      std::printf("%s\n", j.dump(2).c_str());
    } else {
      print_info(args->scene.path, m, def.floor, parts);
      print_pilot(pilot);
    }
    exit_code = kExitOk;
  });
}

}  // namespace dicesim
