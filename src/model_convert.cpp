// The model and geometry conversions of model_io.hpp that write or read more than a Model: the mimic-free copy of a
// model (its Model written back as text) and the geometry read from text.  Apart from model_from_text
// (model_io.cpp) so that neither file compiles all of Boost's serialisation at once: 1.78 GB of the compiler's memory
// together, 1.56 GB and 1.32 GB apart.
#include "model_io.hpp"

#include "convex_shapes.hpp"

#include <cmath>
#include <stdexcept>

#include <boost/variant/get.hpp>
#include <coal/shape/geometric_shapes.h>
#include <pinocchio/multibody/geometry.hpp>
#include <pinocchio/multibody/model.hpp>
#include <pinocchio/serialization.hpp>

namespace bhgrasp {

std::string independent_model_text(const std::string& text) {
  using Mimic = pinocchio::JointModelMimic;
  const pinocchio::Model model = model_from_text(text);
  pinocchio::Model out;
  out.name = model.name;
  out.gravity = model.gravity;
  out.inertias[0] = model.inertias[0];
  for (pinocchio::JointIndex i = 1; i < static_cast<pinocchio::JointIndex>(model.njoints); ++i) {
    const Mimic* mimic = boost::get<Mimic>(&model.joints[i].toVariant());
    const pinocchio::JointModel joint = mimic != nullptr ? pinocchio::JointModel(mimic->jmodel()) : model.joints[i];
    const pinocchio::JointIndex id = out.addJoint(model.parents[i], joint, model.jointPlacements[i], model.names[i]);
    out.inertias[id] = model.inertias[i];  // as read (appendBodyToJoint would add it to zero: round-off)
  }
  // Per coordinate: a joint's own values copied (limits, armature, rotor, friction, damping); a mimic joint's limits
  // are its mimicked joint's mapped through q = scaling q_mimicked + offset (its idx_q and idx_v in `model` point at
  // the mimicked joint's coordinates), its speed limits scaled by |scaling|, its effort limits the mimicked joint's,
  // its other values zero.
  for (pinocchio::JointIndex i = 1; i < static_cast<pinocchio::JointIndex>(model.njoints); ++i) {
    const Mimic* mimic = boost::get<Mimic>(&model.joints[i].toVariant());
    const auto& from = model.joints[i];
    const auto& to = out.joints[i];
    const int nq = to.nq(), nv = to.nv();
    const auto mapped = [&](const Eigen::VectorXd& low, const Eigen::VectorXd& high, int source, int target, int n,
                            double scaling, double offset, Eigen::VectorXd& out_low, Eigen::VectorXd& out_high) {
      const Eigen::VectorXd a = (scaling * low.segment(source, n).array() + offset).matrix();
      const Eigen::VectorXd b = (scaling * high.segment(source, n).array() + offset).matrix();
      out_low.segment(target, n) = a.cwiseMin(b);
      out_high.segment(target, n) = a.cwiseMax(b);
    };
    if (mimic == nullptr) {
      out.lowerPositionLimit.segment(to.idx_q(), nq) = model.lowerPositionLimit.segment(from.idx_q(), nq);
      out.upperPositionLimit.segment(to.idx_q(), nq) = model.upperPositionLimit.segment(from.idx_q(), nq);
      for (auto member : {&pinocchio::Model::lowerVelocityLimit, &pinocchio::Model::upperVelocityLimit,
                          &pinocchio::Model::lowerEffortLimit, &pinocchio::Model::upperEffortLimit,
                          &pinocchio::Model::rotorInertia, &pinocchio::Model::rotorGearRatio,
                          &pinocchio::Model::lowerDryFrictionLimit, &pinocchio::Model::upperDryFrictionLimit,
                          &pinocchio::Model::damping})
        (out.*member).segment(to.idx_v(), nv) = (model.*member).segment(from.idx_v(), nv);
      out.armature.segment(to.idx_v(), nv) = model.armature.segment(from.idx_v(), nv);
      continue;
    }
    const double scaling = mimic->scaling(), offset = mimic->offset();
    mapped(model.lowerPositionLimit, model.upperPositionLimit, from.idx_q(), to.idx_q(), nq, scaling, offset,
           out.lowerPositionLimit, out.upperPositionLimit);
    // Pinocchio keeps both velocity limits as magnitudes (lowerVelocityLimit = max_velocity): scaled, not mapped.
    const double speed = std::abs(scaling);
    out.lowerVelocityLimit.segment(to.idx_v(), nv) = speed * model.lowerVelocityLimit.segment(from.idx_v(), nv);
    out.upperVelocityLimit.segment(to.idx_v(), nv) = speed * model.upperVelocityLimit.segment(from.idx_v(), nv);
    out.lowerEffortLimit.segment(to.idx_v(), nv) = model.lowerEffortLimit.segment(from.idx_v(), nv);
    out.upperEffortLimit.segment(to.idx_v(), nv) = model.upperEffortLimit.segment(from.idx_v(), nv);
  }
  for (std::size_t k = 1; k < model.frames.size(); ++k) out.addFrame(model.frames[k], false);
  return out.saveToString();
}

pinocchio::GeometryModel geometry_from_text(const std::string& text) {
  std::string rest;
  const std::vector<ConvexShape> shapes = read_convex_shapes(text, rest);
  pinocchio::GeometryModel geometry;
  geometry.loadFromString(rest);
  for (const ConvexShape& convex : shapes) {
    if (convex.geometry >= geometry.geometryObjects.size())
      throw std::invalid_argument("convex shapes: a shape names a geometry the geometry model lacks");
    auto& target = geometry.geometryObjects[convex.geometry].geometry;
    const auto* placeholder = dynamic_cast<const coal::Sphere*>(target.get());
    if (placeholder == nullptr || placeholder->radius != kConvexPlaceholderRadius)
      throw std::invalid_argument("convex shapes: a shape names a geometry that is not its placeholder");
    target = convex.shape;
  }
  return geometry;
}

}  // namespace bhgrasp
