// pinocchio::computeFrameJacobian is an inline template: a file that sees its definition (frames.hpp) compiles it
// again for every joint type even where an extern template declaration names Pinocchio's precompiled copy, because
// GCC instantiates inline functions to inline them.  In finger_terms.cpp that one call cost 0.9 GB of the compiler's
// memory and 13 s (1.96 -> 1.08 GB).  This file declares the template without its definition (no frames.hpp, no
// precompiled header: CMakeLists.txt), so the call below can only link to libpinocchio_default's explicit instantiation for these exact
// argument types (VectorXd, Data::Matrix6x): the same code, the same bits, nothing compiled here.  Strictly, a
// function declared inline in one file (frames.hpp, through the precompiled header) and not here is ill-formed, no
// diagnostic required; GCC and Clang on ELF link it as intended.  A signature change in another Pinocchio would show
// as an undefined symbol when bhgrasp._core is imported, not at build time: `pin` is pinned (pyproject.toml).
#include "frame_jacobian.hpp"

#include <type_traits>

#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

namespace pinocchio {

// pinocchio/algorithm/frames.hpp's declaration, without `inline` (its definition is not in this file).
template <typename Scalar, int Options, template <typename, int> class JointCollectionTpl, typename ConfigVectorType,
          typename Matrix6xLike>
void computeFrameJacobian(const ModelTpl<Scalar, Options, JointCollectionTpl>& model,
                          DataTpl<Scalar, Options, JointCollectionTpl>& data,
                          const Eigen::MatrixBase<ConfigVectorType>& q, const FrameIndex frame_id,
                          const ReferenceFrame reference_frame, const Eigen::MatrixBase<Matrix6xLike>& J);

}  // namespace pinocchio

namespace bhgrasp {

void compute_frame_jacobian(const pinocchio::Model& model, pinocchio::Data& data, const Eigen::VectorXd& q,
                            pinocchio::FrameIndex frame, pinocchio::ReferenceFrame reference,
                            pinocchio::Data::Matrix6x& jacobian) {
  static_assert(std::is_same_v<pinocchio::Data::Matrix6x, Eigen::Matrix<double, 6, Eigen::Dynamic>>);
  pinocchio::computeFrameJacobian(model, data, q, frame, reference, jacobian);
}

}  // namespace bhgrasp
