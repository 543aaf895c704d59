// `static`: random orientation, then the quasi-static roll to the resting face.
#include "sim/models/fidelity_models.hpp"
#include "sim/dynamics/rest.hpp"

namespace dicesim {

TossResult run_static(const DieModel& m, const RigidState& s, double tiebreak) {
  TossResult r;
  r.face_index = opposite_face(quasi_static_down_face(m, s.R, tiebreak));
  r.face = m.face_labels[r.face_index];
  r.status = TossStatus::Settled;
  return r;
}

}  // namespace dicesim
