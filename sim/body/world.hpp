// Several dice and static obstacles in one toss (issue 41): what a world toss reads besides each
// die's own model. Compiled once with the scene (sim/models/world_compile.cpp); the toss's model
// (the first die's, its outcomes replaced by the toss's) points to it.
#pragma once

#include <vector>

#include "sim/body/die_model.hpp"
#include "sim/body/obstacles.hpp"
#include "sim/body/piece_tree.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

struct World {
  std::vector<DieModel> dice;          // each die compiled on its own (the floor's law, its throw)
  std::vector<Vec3> offsets;           // per die: added to the release position (m)
  HandKind hand = HandKind::Each;
  OutcomeKind kind = OutcomeKind::Tuple;
  std::vector<std::vector<Vec3>> die_edges;  // per die: unit edge directions, body frame (the narrow phase's overlap axes)
  std::vector<double> die_restitution, die_friction;  // per die: mean over its corners; die against die: the two means' mean
  std::vector<double> die_width;       // per die: its least width (twice its lowest resting COM height, m)

  std::vector<ObstaclePiece> pieces;   // the obstacles, convex pieces
  std::vector<Vec3> piece_lo, piece_hi;  // per piece: its axis-aligned bounding box (polyhedra; planes: unused)
  PieceTree piece_tree;                // the polyhedra's boxes, for the pieces near a die (planes: not in it)
  std::vector<int> plane_pieces;       // the half-space pieces (not in the tree)
  std::vector<double> piece_width;     // per piece: its least width across its faces (planes: +inf)
  std::vector<int> piece_material;     // per piece: index into die_against's second level
  // [die][material]: the die with that obstacle material's restitution and friction at every corner
  // (the floor law, turned to the obstacle's face, reads its materials from the model).
  std::vector<std::vector<DieModel>> die_against;
  // [die i][die j]: die_against's material for i struck against j held at rest (the two dice's means).
  std::vector<std::vector<int>> die_pair_material;

  // The toss's outcome from the dice's: tuple index = sum_k outcome_k * stride[k] (mixed radix, the
  // first die most significant: ascending tuple labels), then tuple_outcome[tuple index].
  std::vector<int> stride;
  std::vector<int> tuple_outcome;
  // Per outcome of the toss: how many of the dice's face tuples read it (a fair set of dice's
  // expectation, as faces per label is a die's).
  std::vector<int> faces_per_outcome;

  int size() const { return static_cast<int>(dice.size()); }
};

}  // namespace dicesim
