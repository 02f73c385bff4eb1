// A pose path of back-to-back minimum-jerk moves by world offsets (bhgrasp/motion/pose_references.py: PoseMotion
// and PosePath, the readable twins): its pose, world twist and the twist's derivative at a time.  The wrist servo
// (wrist_servo.cpp) and the grasp laws' object reference (the Python binding `PosePath`) share it.  Units SI, radians.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace bhgrasp {

using Vector6 = Eigen::Matrix<double, 6, 1>;

// One move of a pose path: from (start_rotation, start_translation) (world <- body) by the world offset
// (dx [m], dtheta [rad]) over `duration` [s] from `delay` [s] (PoseMotion).
struct PoseMove {
  Eigen::Matrix3d start_rotation;
  Eigen::Vector3d start_translation;
  Vector6 offset;
  double duration;
  double delay;
};

class PosePath {
 public:
  // `moves` in time order, each starting where the last ended (PosePath); std::invalid_argument if there is none, a
  // duration is not > 0 or a delay is not finite.
  explicit PosePath(std::vector<PoseMove> moves);

  // At t [s], of the move whose end is still ahead (else the last): with the blend b of its minimum-jerk profile,
  // rotation = exp3(b dtheta) R_0, position = x_0 + b dx, twist = b' (dx, dtheta), derivative = b'' (dx, dtheta).
  // The operations of PoseMotion.__call__ but the rotation's product (Eigen's sums, not NumPy's matmul).
  void at(double t, Eigen::Matrix3d& rotation, Eigen::Vector3d& position, Vector6& twist, Vector6& derivative) const;

 private:
  std::vector<PoseMove> moves_;
};

}  // namespace bhgrasp
