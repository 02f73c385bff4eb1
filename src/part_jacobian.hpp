// A contact's Jacobian by parts, for the implicit step's velocity system by parts (part_system.hpp).  Apart from it so
// that the engine's header needs no sparse algebra.
#pragma once

#include <array>

#include <Eigen/Core>

#include "options.hpp"

namespace bhgrasp {

// A contact's relative point Jacobian J_b(p) - J_a(p) by parts: at most two blocks (3, the part's nv), each with its
// part's first velocity in the scene (the Jacobian's other columns are zero).  A contact between two bodies of one part
// has one block.
struct PartJacobian {
  using Block = Eigen::Matrix<double, 3, Eigen::Dynamic>;
  int count = 0;
  std::array<Eigen::Index, 2> first{};
  std::array<Block, 2> block;

  // Add `sign` times a part's rows (the part's first velocity `at`), merged into a block of the same part.
  template <class Rows>
  void add(Eigen::Index at, const Rows& rows, double sign) {
    for (int k = 0; k < count; ++k) {
      if (first[static_cast<std::size_t>(k)] != at) continue;
      block[static_cast<std::size_t>(k)] += sign * rows;
      return;
    }
    first[static_cast<std::size_t>(count)] = at;
    block[static_cast<std::size_t>(count)] = sign * rows;
    ++count;
  }
  Vector3 times(const Vector& v) const;                           // J v
  void add_transpose_times(const Vector3& f, Vector& out) const;  // out += J^T f
};

inline Vector3 PartJacobian::times(const Vector& v) const {
  Vector3 result = Vector3::Zero();
  for (int k = 0; k < count; ++k) {
    const Block& rows = block[static_cast<std::size_t>(k)];
    result.noalias() += rows * v.segment(first[static_cast<std::size_t>(k)], rows.cols());
  }
  return result;
}

inline void PartJacobian::add_transpose_times(const Vector3& f, Vector& out) const {
  for (int k = 0; k < count; ++k) {
    const Block& rows = block[static_cast<std::size_t>(k)];
    out.segment(first[static_cast<std::size_t>(k)], rows.cols()).noalias() += rows.transpose() * f;
  }
}

}  // namespace bhgrasp
