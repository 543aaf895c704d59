// Face labels: each shape's standard labelling, then the scene's [[die.labels]] by nearest normal.
#pragma once

#include <string>
#include <vector>

#include "sim/body/shape.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

// The face whose outward normal is nearest `direction` (largest cosine; ties to the lower index).
int nearest_face(const ConvexShape& s, const Vec3& direction);

// Standard labels, per face of `s` as built for `die.shape`:
//   box, d6: die.face_labels ([die.faces]);
//   d8, d12, d20: opposite faces sum to N + 1: walking the faces in order, each face not yet
//     labelled gets the next of 1, 2, ... and the face opposite it N + 1 minus that;
//   d10: the same with 0, 1, ... and opposite faces summing to 9;
//   d4: 1..4 in face order (a d4 is read from the face it rests on);
//   prism: the side whose outward normal is at azimuth 360 j / n deg gets j + 1; the +z end n + 1,
//     the -z end n + 2;
//   hull, mesh: 1, 2, ... in face order.
// Then each [[die.labels]] entry relabels its nearest face. On a hull or mesh the faces it does
// not name are numbered 1, 2, ... in face order, skipping the labels the entries use. Several
// faces may share a label (a grouped outcome); two entries naming one face is a SceneError.
std::vector<int> face_labels(const ConvexShape& s, const DieDef& die, const std::string& origin);

}  // namespace dicesim
