// Integrator pieces: see engine.hpp.  Each function mirrors the Python function of the same name in
// bhgrasp/sim/integrators.py or bhgrasp/sim/python_engine.py (PythonEngine); the comments there explain the mechanics.
#include <algorithm>
#include <cmath>

#include <pinocchio/algorithm/joint-configuration.hpp>

#include "engine.hpp"

namespace bhgrasp {
namespace {

// w x I w in the principal axes, I = diag(moments) (sim/integrators.py: gyroscopic_torque).
Vector3 gyroscopic(const Vector3& moments, const Vector3& w) {
  const double a = moments[0], b = moments[1], c = moments[2];
  return Vector3((c - b) * w[1] * w[2], (a - c) * w[2] * w[0], (b - a) * w[0] * w[1]);
}

// The midpoint m of an implicit-midpoint step of torque-free spin, I m + h m x I m = I w
// (sim/integrators.py: spin_midpoint).
Vector3 spin_midpoint(const Vector3& moments, const Vector3& w, double h) {
  const double a = moments[0], b = moments[1], c = moments[2];
  const double w0 = w[0], w1 = w[1], w2 = w[2];
  double m0 = w0, m1 = w1, m2 = w2;
  const double p = h * (c - b), q = h * (a - c), r = h * (b - a);
  for (int iteration = 0; iteration < 30; ++iteration) {
    const double f0 = a * (m0 - w0) + p * m1 * m2;
    const double f1 = b * (m1 - w1) + q * m2 * m0;
    const double f2 = c * (m2 - w2) + r * m0 * m1;
    const double j01 = p * m2, j02 = p * m1, j10 = q * m2, j12 = q * m0, j20 = r * m1, j21 = r * m0;
    const double c0 = b * c - j12 * j21, c1 = j12 * j20 - j10 * c, c2 = j10 * j21 - b * j20;
    const double det = a * c0 + j01 * c1 + j02 * c2;
    const double d0 = (f0 * c0 + j01 * (j12 * f2 - f1 * c) + j02 * (f1 * j21 - b * f2)) / det;
    const double d1 = (a * (f1 * c - j12 * f2) + f0 * c1 + j02 * (j10 * f2 - f1 * j20)) / det;
    const double d2 = (a * (b * f2 - f1 * j21) + j01 * (f1 * j20 - j10 * f2) + f0 * c2) / det;
    m0 -= d0;
    m1 -= d1;
    m2 -= d2;
    if (std::max({std::abs(d0), std::abs(d1), std::abs(d2)}) <=
        1e-16 * (1.0 + std::max({std::abs(m0), std::abs(m1), std::abs(m2)})))
      break;
  }
  return Vector3(m0, m1, m2);
}

}  // namespace

void Engine::implicit_gyroscopic(const Vector& v, Vector& bias) const {
  for (const Spinning& body : settings_.spinning) {
    const Vector3 w = body.axes.transpose() * v.segment<3>(body.angular);
    if ((body.moments[0] == body.moments[1] && body.moments[1] == body.moments[2]) || (w.array() == 0.0).all())
      continue;
    const Vector3 explicit_torque = gyroscopic(body.moments, w);
    const Vector3 middle = spin_midpoint(body.moments, w, 0.5 * settings_.dt);
    bias.segment<3>(body.angular) += body.axes * (gyroscopic(body.moments, middle) - explicit_torque);
  }
}

Vector Engine::increment_rate(const Vector& increment, const Vector& v) const {
  Vector rate = v;
  for (const Spinning& body : settings_.spinning) {
    const Vector3 theta = increment.segment<3>(body.angular), w = v.segment<3>(body.angular);
    const Vector3 half = theta.cross(w);
    rate.segment<3>(body.angular) = w + 0.5 * half + theta.cross(half) / 12.0;
  }
  return rate;
}

Vector Engine::integrate(const Vector& q, const Vector& v) const {
  Vector result(model_.nq);
  pinocchio::integrate(model_, q, v, result);
  return result;
}

}  // namespace bhgrasp
