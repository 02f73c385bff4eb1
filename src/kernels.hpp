// Small helpers shared by the compiled step's source files (engine.cpp, detect.cpp, contact_law.cpp, implicit.cpp);
// not part of the module's interface.
#pragma once

#include "engine.hpp"

namespace bhgrasp {

using ConstRef = Eigen::Ref<const Vector>;

// Row i of an (m, 3) array as a vector.
inline Vector3 row(const Points& points, Eigen::Index i) { return points.row(i).transpose(); }

// The tangential part of a vector at normal n.
inline Vector3 tangential(const Vector3& x, const Vector3& n) { return x - x.dot(n) * n; }

// Grow a work array to at least `rows` rows, never shrinking it: a scene allocates it again only when it reaches more
// contacts than ever before.  Its values are not kept.
template <typename Array>
void reserve_rows(Array& array, Eigen::Index rows) {
  if (array.rows() < rows) array.resize(rows, array.cols());
}

}  // namespace bhgrasp
