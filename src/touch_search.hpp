// Where a closing finger first touches an object (bhgrasp/bench/reach.py: Reach._touch, the readable twin): every
// finger at proximal angle a, its distal at a / 3, the hand's collision shapes placed by Pinocchio and measured by
// coal against the object at a centre (axes fixed, the hand frame); the first touching angle by 30 bisections
// between the open and the closed angle.  The same Pinocchio and coal calls as the twin's, in the same order, so the
// same angle to the bit (tests/test_touch_search.py).  Units SI, radians.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <coal/collision_data.h>
#include <pinocchio/multibody/geometry.hpp>
#include <pinocchio/multibody/model.hpp>

namespace bhgrasp {

class TouchSearch {
 public:
  // `model`, `geometry`: the hand and its collision shapes with the object's as shape `object` (on the universe at
  // identity; text of bhgrasp/sim/geometry_text.py); `links[f]`: finger f's shapes; `configuration`: the hand's
  // coordinates but the fingers' (the spreads set); `proximal`, `distal`: the fingers' coordinates; `axes`: hand <-
  // object.  std::invalid_argument on bad indices or sizes.
  TouchSearch(const std::string& model, const std::string& geometry, int object, std::vector<std::vector<int>> links,
              const Eigen::VectorXd& configuration, std::vector<int> proximal, std::vector<int> distal,
              const Eigen::Matrix3d& axes);

  // Whether every shape of finger f is apart from the object at `centre` (coal's distance > 0) with every finger at
  // proximal `angle` [rad]: the twin's `distance(f, angle, centre) > 0`, stopping at the first shape that touches.
  bool apart(int finger, double angle, const Eigen::Vector3d& centre);

  // The first proximal angle [rad] at which finger f touches the object at `centre`, between `opening` and `closed`
  // (`opening` if it touches there, `closed` if it never does).
  double touch(int finger, const Eigen::Vector3d& centre, double opening, double closed);

 private:
  pinocchio::Model model_;
  std::unique_ptr<pinocchio::Data> data_;
  pinocchio::GeometryModel geometry_;
  std::unique_ptr<pinocchio::GeometryData> placed_;
  int object_;
  std::vector<std::vector<int>> links_;
  Eigen::VectorXd q_;
  std::vector<int> proximal_, distal_;
  Eigen::Matrix3d axes_;
  coal::DistanceRequest request_;
};

}  // namespace bhgrasp
