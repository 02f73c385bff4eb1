// Small helpers shared by the compiled step's source files (engine.cpp, detect.cpp, contact_law.cpp, implicit.cpp,
// integrators.cpp); not part of the module's interface.
#pragma once

#include "engine.hpp"

namespace bhgrasp {

using ConstRef = Eigen::Ref<const Vector>;

// Row i of an (m, 3) array as a vector.
inline Vector3 row(const Points& points, Eigen::Index i) { return points.row(i).transpose(); }

// The tangential part of a vector at normal n.
inline Vector3 tangential(const Vector3& x, const Vector3& n) { return x - x.dot(n) * n; }

// Solve (T^T A T) w = T^T b and return T w (A symmetric positive definite, T of full column rank); in engine.cpp.
Vector reduced_solve(const Matrix& transmission, const Matrix& matrix, const Vector& rhs);

}  // namespace bhgrasp
