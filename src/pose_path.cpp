#include "pose_path.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <pinocchio/spatial/explog.hpp>

namespace bhgrasp {

PosePath::PosePath(std::vector<PoseMove> moves) : moves_(std::move(moves)) {
  if (moves_.empty()) throw std::invalid_argument("a pose path needs at least one move");
  for (const PoseMove& move : moves_)
    if (!(move.duration > 0.0) || !std::isfinite(move.delay))
      throw std::invalid_argument("a move needs duration > 0 and a finite delay");
}

void PosePath::at(double t, Eigen::Matrix3d& rotation, Eigen::Vector3d& position, Vector6& twist,
                  Vector6& derivative) const {
  const PoseMove* move = &moves_.back();  // PosePath: the move whose end is still ahead, else the last
  for (const PoseMove& candidate : moves_)
    if (t < candidate.delay + candidate.duration) {
      move = &candidate;
      break;
    }
  // PoseMotion's blend and minimum_jerk, operation for operation (the same bits)
  const double s = std::min(std::max((t - move->delay) / move->duration, 0.0), 1.0);
  const double square = s * s, rest = 1.0 - s;
  const double blend = square * s * (10.0 + s * (-15.0 + 6.0 * s));
  const double rate = 30.0 * square * rest * rest / move->duration;
  const double curvature = 60.0 * s * rest * (1.0 - 2.0 * s) / (move->duration * move->duration);
  const Eigen::Vector3d turn = blend * move->offset.tail<3>();
  rotation = pinocchio::exp3(turn) * move->start_rotation;
  position = move->start_translation + blend * move->offset.head<3>();
  twist = rate * move->offset;
  derivative = curvature * move->offset;
}

}  // namespace bhgrasp
