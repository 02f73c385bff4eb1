#include "touch_search.hpp"
#include "model_io.hpp"

#include <stdexcept>

#include <coal/distance.h>
#include <pinocchio/algorithm/geometry.hpp>
#include <pinocchio/collision/collision.hpp>

namespace bhgrasp {

TouchSearch::TouchSearch(const std::string& model, const std::string& geometry, int object,
                         std::vector<std::vector<int>> links, const Eigen::VectorXd& configuration,
                         std::vector<int> proximal, std::vector<int> distal, const Eigen::Matrix3d& axes)
    : model_(model_from_text(model)),
      geometry_(geometry_from_text(geometry)),
      object_(object),
      links_(std::move(links)),
      q_(configuration),
      proximal_(std::move(proximal)),
      distal_(std::move(distal)),
      axes_(axes) {
  const auto shapes = static_cast<int>(geometry_.ngeoms);
  if (object_ < 0 || object_ >= shapes) throw std::invalid_argument("the object is not a shape of the geometry");
  for (const auto& finger : links_)
    for (const int link : finger)
      if (link < 0 || link >= shapes) throw std::invalid_argument("a finger's link is not a shape of the geometry");
  if (q_.size() != model_.nq) throw std::invalid_argument("the configuration needs one value per coordinate");
  for (const auto* joints : {&proximal_, &distal_})
    for (const int joint : *joints)
      if (joint < 0 || joint >= model_.nq) throw std::invalid_argument("a finger's coordinate is out of range");
  data_ = std::make_unique<pinocchio::Data>(model_);
  placed_ = std::make_unique<pinocchio::GeometryData>(geometry_);
}

bool TouchSearch::apart(int finger, double angle, const Eigen::Vector3d& centre) {
  if (finger < 0 || finger >= static_cast<int>(links_.size())) throw std::invalid_argument("no such finger");
  for (const int joint : proximal_) q_[joint] = angle;
  for (const int joint : distal_) q_[joint] = angle / 3;
  pinocchio::updateGeometryPlacements(model_, *data_, geometry_, *placed_, q_);
  const coal::Transform3s placement(axes_, centre);
  const coal::CollisionGeometry* shape = geometry_.geometryObjects[static_cast<std::size_t>(object_)].geometry.get();
  for (const int link : links_[static_cast<std::size_t>(finger)]) {
    const auto index = static_cast<std::size_t>(link);
    const pinocchio::SE3& frame = placed_->oMg[index];
    coal::DistanceResult result;
    const double gap = coal::distance(geometry_.geometryObjects[index].geometry.get(),
                                      coal::Transform3s(frame.rotation(), frame.translation()), shape, placement,
                                      request_, result);
    if (gap <= 0.0) return false;
  }
  return true;
}

double TouchSearch::touch(int finger, const Eigen::Vector3d& centre, double opening, double closed) {
  double low = opening, high = closed;
  if (!apart(finger, low, centre)) return low;
  if (apart(finger, high, centre)) return high;
  for (int step = 0; step < 30; ++step) {
    const double middle = 0.5 * (low + high);
    if (apart(finger, middle, centre))
      low = middle;
    else
      high = middle;
  }
  return high;
}

}  // namespace bhgrasp
