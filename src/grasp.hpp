// The grasp law's kinematics kernel: P = J_h^+ G^T, its rate P_dot, G, J_h and J_h^+ for contacts fixed on the
// object and on hand links, on Pinocchio's C++ API.
//
// The Python twin is bhgrasp.grasp.kinematics.contact_kinematics_python (its module docstring derives the maths);
// compute() mirrors it line for line, named alike, but for J^+, which it takes block by block (pinv_by_blocks: the same
// pseudo-inverse, to round-off), and tests/test_grasp_kernels.py checks both agree to round-off.
// Units SI, world frame; arrays of points are (n, 3) row-major, as NumPy's.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include <pinocchio/multibody.hpp>

#include "decompositions.hpp"

namespace bhgrasp {

using Rows = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;  // as batch.hpp's
using Vector6 = Eigen::Matrix<double, 6, 1>;

// The maps of a grasp at one instant (bhgrasp.grasp.kinematics.GraspKinematics), n contacts, nv joint velocities.
struct GraspMaps {
  Rows joint_map;           // P = J_h^+ G^T (nv, 6)
  Rows joint_map_rate;      // P_dot (nv, 6) along q_dot = P x_dot and the object twist x_dot [1/s]
  Rows grasp_map;           // G (6, 3n) at the centre of mass, contact coordinates
  Rows hand_jacobian;       // J_h (3n, nv), contact coordinates
  Rows hand_jacobian_pinv;  // J_h^+ (nv, 3n)
};

class GraspKinematics {
 public:
  using ConstVector = Eigen::Ref<const Eigen::VectorXd>;
  using ConstRows = Eigen::Ref<const Rows>;

  // `model`: Pinocchio's text serialisation of the hand (Model.saveToString); the model is not modified afterwards.
  explicit GraspKinematics(const std::string& model);

  // The maps at configuration q (nq) of a hand whose model frame sits at (base_rotation, base_translation) in the
  // world (world <- model), for an object with COM `com` [m] and twist (v [m/s], omega [rad/s]), world, and n
  // contacts: `points` (n, 3) [m] world, `frames` (3n, 3) the contact frames stacked (rows 3i..3i+2: columns t1,
  // t2, n of contact i, world) and `joints` the Pinocchio ids of the joints whose bodies carry them.  The result
  // lives in this object until the next call.  Sizes are checked (std::invalid_argument); values are not.
  const GraspMaps& compute(const Eigen::Matrix3d& base_rotation, const Eigen::Vector3d& base_translation,
                           const ConstVector& q, const Eigen::Vector3d& com, const Vector6& twist,
                           const ConstRows& points, const ConstRows& frames, const std::vector<int>& joints);

  int nq() const { return model_.nq; }
  int nv() const { return model_.nv; }

 private:
  void resize(Eigen::Index count);
  // J^+ of jacobian_world_ into pinv_world_, block by block (grasp.cpp): singular values <= 1e-15 of the largest
  // dropped, as np.linalg.pinv of the whole J
  void pinv_by_blocks(const std::vector<int>& joints);

  pinocchio::Model model_;
  pinocchio::Data data_;
  Eigen::MatrixXd masks_;  // (njoints, nv): 1 in the columns that move joint j's body

  // work buffers, sized for the last contact count (resized only when it changes)
  Eigen::Index count_ = -1;
  Eigen::MatrixXd spatial_, rate_;             // J^W, J^W_dot (6, nv), world
  Eigen::MatrixXd at_com_, rate_at_com_;       // their linear rows moved to the COM (3, nv)
  Eigen::MatrixXd jacobian_world_;             // J (3n, nv)
  Eigen::MatrixXd jacobian_rate_;              // J_dot (3n, nv)
  Eigen::MatrixXd pinv_world_;                 // J^+ (nv, 3n)
  Eigen::MatrixXd grasp_t_, grasp_t_rate_;     // G_w^T and its rate (3n, 6)
  Eigen::MatrixXd p_map_, p_dot_;              // P, P_dot (nv, 6)
  Eigen::MatrixXd residual_, lifted_;          // (3n, 6), (nv, 6) terms of P_dot
  Eigen::MatrixXd gram_, rate_t_, projected_;  // J^+ J^+T (nv, nv), J_dot^T (nv, 3n), J J_dot^T (3n, 3n)
  Eigen::VectorXd q_dot_;
  // pinv_by_blocks' work, kept between calls (a block keeps its size while the grasp keeps its contacts)
  std::vector<int> block_of_;                          // per contact: its block
  std::vector<std::vector<Eigen::Index>> block_rows_, block_columns_;
  std::vector<Eigen::MatrixXd> block_, block_pinv_;    // J's block and its pseudo-inverse
  std::vector<Eigen::JacobiSVD<Eigen::MatrixXd>> block_svd_;
  std::vector<Eigen::VectorXd> block_inverse_;
  std::vector<Eigen::MatrixXd> block_scaled_;          // V diag(1/s) of a block
  std::vector<Eigen::MatrixXd> block_u_, block_v_;     // a block's SVD: U, V (thin; full for 3x3) and singular values
  std::vector<Eigen::VectorXd> block_singular_;
  Eigen::JacobiSVD<Eigen::Matrix3d> square_svd_;       // the SVD of a 3x3 block (fixed size: no allocation)
  Eigen::RowVectorXd block_mask_;                      // the columns of the block being gathered
  GraspMaps maps_;
};

}  // namespace bhgrasp
