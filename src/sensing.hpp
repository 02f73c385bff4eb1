// What a grasp controller reads from sensed contacts, per finger (bhgrasp/grasp/sensing.py: ContactSensing.fingers):
// the contacts of each finger summed, with the force-weighted normal and point of the pressing ones.
// The Python twin is ContactSensing._fingers_python; tests/test_sensing_kernels.py holds both to round-off.
// Units SI, world frame; rows of (m, 3) arrays are contacts, as NumPy's.
#pragma once

#include <Eigen/Core>

#include "engine.hpp"

namespace bhgrasp {

struct FingerSums {
  Points force;         // (F, 3) total force the finger exerts on the object [N]
  Vector normal_force;  // (F,) sum of n . f [N]
  Points normal;        // (F, 3) force-weighted mean unit normal of the pressing contacts (all contacts' sum
                        // normalised when none presses; zeros without contacts)
  Indices count;        // (F,) number of contacts
  Points point;         // (F, 3) force-weighted mean point of the pressing contacts [m] (zeros when none presses)
  Indices strongest;    // (F,) row of the contact that presses hardest (the first of equals); -1 when none presses
};

// Work arrays of finger_contacts, (F,) and (F, 3); kept by a caller that sums every control cycle.
struct FingerWork {
  Vector weight_sum, best;
  Points pressing_normal, plain_normal;
};

using ConstIndices = Eigen::Ref<const Indices>;
using ConstPoints = Eigen::Ref<const Points>;

// `finger[k]`: the finger (0 .. fingers - 1) of contact k, or -1 for a contact of no finger; `points`, `normals`
// (unit, finger -> object) and `forces` (on the object) (m, 3).  Sizes are checked (std::invalid_argument).
FingerSums finger_contacts(const ConstIndices& finger, Eigen::Index fingers, const ConstPoints& points,
                           const ConstPoints& normals, const ConstPoints& forces);
// The same sums into `sums`, with `work` (both allocated only when the number of fingers changes).
void finger_contacts_into(const ConstIndices& finger, Eigen::Index fingers, const ConstPoints& points,
                          const ConstPoints& normals, const ConstPoints& forces, FingerSums& sums, FingerWork& work);

// Y_o (6, 7) of bhgrasp.controllers.adaptive_grasp.object_regressor: Y_o sigma_o = M_o a_r + C_o(omega) v_r + N_o
// at the COM, world, for sigma_o = (m, I_xx, I_xy, I_xz, I_yy, I_yz, I_zz) (body-frame inertia about the COM).
Eigen::Matrix<double, 6, 7, Eigen::RowMajor> object_regressor(const Eigen::Matrix3d& rotation,
                                                               const Eigen::Vector3d& omega,
                                                               const Eigen::Matrix<double, 6, 1>& v_r,
                                                               const Eigen::Matrix<double, 6, 1>& a_r,
                                                               const Eigen::Vector3d& gravity);

// Contact frames [t1, t2, n] of bhgrasp.grasp.frames.contact_frames for normals (m, 3) (any length): rows 3i..3i+2
// of the result (3m, 3) are frame i (columns t1, t2, n, world).  t1 is the world x-axis (the y-axis when
// |n_x| > switch_x) projected on the tangent plane, t2 = n x t1.  `zero` is set to the first normal shorter than
// `zero_length` (-1: none; its frame is then not finite).
Points contact_frames(const Points& normals, double zero_length, double switch_x, Eigen::Index& zero);
// The frame (columns t1, t2, n) of one normal, as a block of contact_frames (not finite for a zero normal).
Eigen::Matrix3d contact_frame(const Eigen::RowVector3d& normal, double switch_x);

}  // namespace bhgrasp
