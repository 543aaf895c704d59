// Building a die's body (hull, labels, exact mass properties): the part of `dicesim info` and of
// compiling a scene that depends on the shape. Target (issue #11): `info` on a 2000-vertex mesh
// under 0.5 s overall, so the body of such a mesh must build in well under that.
#include <benchmark/benchmark.h>

#include <cmath>
#include <sstream>
#include <string>

#include "sim/body/body.hpp"

namespace dicesim {
namespace {

// A UV sphere of radius 1 with `rings` - 1 latitude circles of `segments` vertices (quads between
// circles, triangles at the poles), counter-clockwise from outside.
std::string uv_sphere_obj(int rings, int segments) {
  std::ostringstream o;
  o.precision(12);
  o << "v 0 0 1\n";
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double t = kPi * i / rings, p = 2.0 * kPi * j / segments;
      o << "v " << std::sin(t) * std::cos(p) << ' ' << std::sin(t) * std::sin(p) << ' ' << std::cos(t) << '\n';
    }
  o << "v 0 0 -1\n";
  const int south = 1 + (rings - 1) * segments + 1;
  auto id = [&](int i, int j) { return 2 + (i - 1) * segments + (j % segments); };
  for (int j = 0; j < segments; ++j) o << "f 1 " << id(1, j) << ' ' << id(1, j + 1) << '\n';
  for (int i = 1; i + 1 < rings; ++i)
    for (int j = 0; j < segments; ++j)
      o << "f " << id(i, j) << ' ' << id(i + 1, j) << ' ' << id(i + 1, j + 1) << ' ' << id(i, j + 1) << '\n';
  for (int j = 0; j < segments; ++j) o << "f " << id(rings - 1, j) << ' ' << south << ' ' << id(rings - 1, j + 1) << '\n';
  return o.str();
}

SceneDef scene_with(ShapeKind shape) {
  SceneDef s = default_scene_def();
  s.materials["plastic"] = MaterialDef{1200.0, 0.5, 0.3};
  s.die.base_material = "plastic";
  s.die.shape = shape;
  s.die.size = Vec3::Constant(0.02);
  return s;
}

void BM_BuildBodyMesh2000(benchmark::State& state) {
  SceneDef s = scene_with(ShapeKind::Mesh);
  s.die.mesh_text = uv_sphere_obj(41, 50);  // 2002 vertices
  s.die.mesh_path = "sphere.obj";
  s.die.scale = 0.01;
  for (auto _ : state) benchmark::DoNotOptimize(build_body(s, "bench"));
}
BENCHMARK(BM_BuildBodyMesh2000)->Unit(benchmark::kMillisecond);

void BM_BuildBodyD20(benchmark::State& state) {
  const SceneDef s = scene_with(ShapeKind::D20);
  for (auto _ : state) benchmark::DoNotOptimize(build_body(s, "bench"));
}
BENCHMARK(BM_BuildBodyD20)->Unit(benchmark::kMicrosecond);

void BM_BuildBodyRoundedD20(benchmark::State& state) {
  SceneDef s = scene_with(ShapeKind::D20);
  s.die.rounding = 0.001;
  for (auto _ : state) benchmark::DoNotOptimize(build_body(s, "bench"));
}
BENCHMARK(BM_BuildBodyRoundedD20)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace dicesim
