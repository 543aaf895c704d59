// A die given as a Wavefront OBJ mesh: parsing, the closed-and-oriented check, its triangles.
#pragma once

#include <string>
#include <vector>

#include "sim/body/shape.hpp"

namespace dicesim {

struct ObjMesh {
  std::vector<Vec3> vertices;            // `v` lines, in order
  std::vector<std::vector<int>> faces;   // `f` lines: 0-based vertex indices, as written
  std::vector<int> face_line;            // the OBJ line of each face (1-based)
};

// Reads `v` and `f` statements (f accepts i, i/t, i//n, i/t/n, negative = relative indices);
// ignores vt, vn, vp, o, g, s, usemtl, mtllib, l, p and comments. Anything else, a malformed
// number or index, a face with fewer than 3 corners or a repeated corner is a SceneError naming
// `file`, "line N", the line and what is expected.
ObjMesh parse_obj(const std::string& text, const std::string& file);

// A closed, consistently and outward oriented surface: every edge is used once in each direction
// by the faces, and the enclosed volume is positive. Otherwise a SceneError naming the OBJ line
// of an offending face.
void check_closed(const ObjMesh& mesh, const std::string& file);

// The faces fanned into triangles, coordinates times `scale`.
Triangles mesh_triangles(const ObjMesh& mesh, double scale);

// The vertices some face uses, times `scale` (what can touch the floor: their hull).
std::vector<Vec3> used_vertices(const ObjMesh& mesh, double scale);

}  // namespace dicesim
