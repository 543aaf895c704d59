// dicesim info: what the scene compiles to: mass properties, principal frame, faces, corners.
#include <cstdio>

#include "apps/commands.hpp"
#include "apps/info_json.hpp"
#include "sim/body/die_model.hpp"
#include "sim/models/compile.hpp"

namespace dicesim {
namespace {

void print_info(const std::string& path, const DieModel& m) {
  const MassProperties& mp = m.mass_geometric;
  std::printf("%s%s%s\n\n", path.c_str(), m.name.empty() ? "" : ": ", m.name.c_str());
  std::printf("mass               %.9g kg\n", mp.mass);
  std::printf("centre of mass     (%+.6e, %+.6e, %+.6e) m from the box centre (%.4f mm off)\n", mp.com.x(), mp.com.y(),
              mp.com.z(), 1e3 * mp.com.norm());
  std::printf("inertia about COM  [%+.6e %+.6e %+.6e]\n", mp.inertia(0, 0), mp.inertia(0, 1), mp.inertia(0, 2));
  std::printf("  (kg m^2,         [%+.6e %+.6e %+.6e]\n", mp.inertia(1, 0), mp.inertia(1, 1), mp.inertia(1, 2));
  std::printf("   geometric axes) [%+.6e %+.6e %+.6e]\n", mp.inertia(2, 0), mp.inertia(2, 1), mp.inertia(2, 2));
  std::printf("principal moments  %.6e  %.6e  %.6e kg m^2%s\n", mp.principal_moments[0], mp.principal_moments[1],
              mp.principal_moments[2], m.symmetric_top ? "  (symmetric top: closed-form flight)" : "");
  for (int k = 0; k < 3; ++k)
    std::printf("  axis %d           (%+.4f, %+.4f, %+.4f)\n", k + 1, mp.principal_axes(0, k), mp.principal_axes(1, k),
                mp.principal_axes(2, k));
  std::printf("bounding radius    %.6g m (COM to farthest corner)\n\nfaces (label: outward normal)\n", m.bounding_radius);
  for (int f = 0; f < 6; ++f) std::printf("  %d: %s\n", m.face_labels[f], kFaceDirNames[f]);
  std::printf("\ncorners (restitution, friction: volume mix of the materials at the corner)\n");
  for (int c = 0; c < 8; ++c)
    std::printf("  (%c,%c,%c)  e = %.4f  mu = %.3f\n", (c & 1) ? '+' : '-', (c & 2) ? '+' : '-', (c & 4) ? '+' : '-',
                m.vertex_restitution[c], m.vertex_friction[c]);
  std::printf("\nresting (COM height on the face; lowest COM height over its edges)\n");
  for (int f = 0; f < 6; ++f)
    std::printf("  %d: %.6g m, escape %.6g m\n", m.face_labels[f], m.face_height[f], m.face_escape[f]);
  std::printf("\nfidelity           %s", to_string(m.fidelity));
  if (m.fidelity_requested == Fidelity::Auto) std::printf(" (chosen by auto)");
  std::printf("\n  why              %s\n", m.fidelity_reason.c_str());
}

}  // namespace

void register_info(CLI::App& app, int& exit_code) {
  struct Args {
    SceneArgs scene;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "info",
      "Compile a scene and print the die's exact mass, centre of mass, inertia tensor about the\n"
      "COM (products of inertia included), principal moments and axes, and the face map.\n\n"
      "Example:  dicesim info scenes/paper/die3.toml --json");
  args->scene.add_to(cmd);
  cmd->add_flag("--json", args->json, "One JSON object: mass, com, inertia (3x3), principal_moments, ...");
  cmd->callback([args, &exit_code] {
    const DieModel m = compile(args->scene.load(), args->scene.path);
    if (args->json)
      std::printf("%s\n", info_json(args->scene.path, m).dump(2).c_str());
    else
      print_info(args->scene.path, m);
    exit_code = kExitOk;
  });
}

}  // namespace dicesim
