#include "sim/body/mesh.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <sstream>
#include <utility>

#include "sim/scene/scene_error.hpp"

namespace dicesim {
namespace {

std::string line_key(int line) { return "line " + std::to_string(line); }

bool parse_double(const std::string& token, double& out) {
  if (token.empty()) return false;
  errno = 0;
  char* end = nullptr;
  out = std::strtod(token.c_str(), &end);
  return errno == 0 && end == token.c_str() + token.size() && std::isfinite(out);
}

bool parse_index(const std::string& token, long long& out) {
  const std::string head = token.substr(0, token.find('/'));
  if (head.empty()) return false;
  errno = 0;
  char* end = nullptr;
  out = std::strtoll(head.c_str(), &end, 10);
  return errno == 0 && end == head.c_str() + head.size();
}

}  // namespace

ObjMesh parse_obj(const std::string& text, const std::string& file) {
  ObjMesh mesh;
  std::istringstream in(text);
  std::string raw;
  int line = 0;
  while (std::getline(in, raw)) {
    ++line;
    std::string content = raw.substr(0, raw.find('#'));
    if (!content.empty() && content.back() == '\r') content.pop_back();
    std::istringstream words(content);
    std::string keyword;
    if (!(words >> keyword)) continue;
    std::vector<std::string> args;
    for (std::string w; words >> w;) args.push_back(w);
    auto fail = [&](const std::string& why) { throw SceneError(file, line_key(line), content, why); };
    if (keyword == "v") {
      if (args.size() != 3 && args.size() != 4) fail("a vertex is 'v x y z' (optionally w): 3 finite numbers");
      Vec3 v;
      for (int k = 0; k < 3; ++k)
        if (!parse_double(args[k], v[k])) fail("a vertex is 'v x y z': '" + args[k] + "' is not a finite number");
      mesh.vertices.push_back(v);
    } else if (keyword == "f") {
      if (args.size() < 3) fail("a face needs at least 3 corners: 'f i j k ...'");
      std::vector<int> face;
      const long long n = static_cast<long long>(mesh.vertices.size());
      for (const std::string& a : args) {
        long long i = 0;
        if (!parse_index(a, i) || i == 0)
          fail("a face corner is a vertex index (1-based, or negative counting back), optionally /t or /t/n or //n: got '" +
               a + "'");
        const long long idx = i > 0 ? i - 1 : n + i;
        if (idx < 0 || idx >= n)
          fail("vertex index " + std::to_string(i) + " is out of range: " + std::to_string(n) +
               " vertices are defined above this line");
        for (int prev : face)
          if (prev == idx) fail("vertex " + std::to_string(idx + 1) + " appears twice in one face");
        face.push_back(static_cast<int>(idx));
      }
      mesh.faces.push_back(std::move(face));
      mesh.face_line.push_back(line);
    } else if (keyword == "vt" || keyword == "vn" || keyword == "vp" || keyword == "o" || keyword == "g" ||
               keyword == "s" || keyword == "usemtl" || keyword == "mtllib" || keyword == "l" || keyword == "p") {
      continue;
    } else {
      fail("unknown OBJ statement '" + keyword + "'; allowed: v, f (and vt, vn, vp, o, g, s, usemtl, mtllib, l, p, ignored)");
    }
  }
  if (mesh.faces.size() < 4)
    throw SceneError(file, "", "", "a mesh needs at least 4 faces ('f' lines) enclosing a solid; found " +
                                       std::to_string(mesh.faces.size()));
  return mesh;
}

void check_closed(const ObjMesh& mesh, const std::string& file) {
  std::map<std::pair<int, int>, std::size_t> edge_face;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& loop = mesh.faces[f];
    for (std::size_t k = 0; k < loop.size(); ++k) {
      const std::pair<int, int> e{loop[k], loop[(k + 1) % loop.size()]};
      const auto [it, fresh] = edge_face.emplace(e, f);
      if (!fresh)
        throw SceneError(file, line_key(mesh.face_line[f]), "",
                         "edge " + std::to_string(e.first + 1) + "-" + std::to_string(e.second + 1) +
                             " is used in the same direction by the face on line " +
                             std::to_string(mesh.face_line[it->second]) +
                             ": faces must be consistently oriented (counter-clockwise seen from outside) and each "
                             "edge shared by exactly two faces");
    }
  }
  for (const auto& [e, f] : edge_face)
    if (!edge_face.count({e.second, e.first}))
      throw SceneError(file, line_key(mesh.face_line[f]), "",
                       "edge " + std::to_string(e.first + 1) + "-" + std::to_string(e.second + 1) +
                           " has no face on its other side: the mesh must be closed (watertight)");
  // Closed and consistent: the signed volume says whether the faces point out.
  double volume = 0.0;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& t : mesh_triangles(mesh, 1.0)) {
    volume += t[0].dot(t[1].cross(t[2])) / 6.0;
    for (const Vec3& p : t) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  if (std::abs(volume) <= 1e-12 * std::pow((hi - lo).norm(), 3))
    throw SceneError(file, "", "", "the faces enclose no volume (a flat mesh): a die must be a solid");
  if (!(volume > 0.0))
    throw SceneError(file, "", "", "the faces enclose a negative volume: they are oriented inward; OBJ faces must be "
                                   "counter-clockwise seen from outside (reverse every face)");
}

Triangles mesh_triangles(const ObjMesh& mesh, double scale) {
  Triangles t;
  for (const auto& loop : mesh.faces)
    for (std::size_t k = 1; k + 1 < loop.size(); ++k)
      t.push_back({scale * mesh.vertices[loop[0]], scale * mesh.vertices[loop[k]], scale * mesh.vertices[loop[k + 1]]});
  return t;
}

std::vector<Vec3> used_vertices(const ObjMesh& mesh, double scale) {
  std::vector<bool> used(mesh.vertices.size(), false);
  for (const auto& loop : mesh.faces)
    for (int v : loop) used[v] = true;
  std::vector<Vec3> out;
  for (std::size_t v = 0; v < used.size(); ++v)
    if (used[v]) out.push_back(scale * mesh.vertices[v]);
  return out;
}

}  // namespace dicesim
