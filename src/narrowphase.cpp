// coal::collide on a kept solver: see narrowphase.hpp.
#include "narrowphase.hpp"

#include <coal/collision.h>

#include <limits>
#include <stdexcept>

namespace bhgrasp {

std::size_t Narrowphase::collide(const coal::CollisionGeometry* a, const coal::Transform3s& placement_a,
                                 const coal::CollisionGeometry* b, const coal::Transform3s& placement_b,
                                 const coal::CollisionRequest& request, coal::CollisionResult& result) {
  if (!kept) return coal::collide(a, placement_a, b, placement_b, request, result);
  if (request.security_margin == -std::numeric_limits<coal::CoalScalar>::infinity()) {
    result.clear();
    return 0;
  }
  if (request.num_max_contacts == 0) throw std::invalid_argument("a collision request needs num_max_contacts > 0");
  // the state of a GJKSolver(request): its constructor's guesses, then set(request)
  solver_.cached_guess = coal::Vec3s(1, 0, 0);
  solver_.support_func_cached_guess = coal::support_func_guess_t::Zero();
  solver_.set(request);
  const coal::NODE_TYPE type_a = a->getNodeType(), type_b = b->getNodeType();
  std::size_t found = 0;
  if (a->getObjectType() == coal::OT_GEOM &&
      (b->getObjectType() == coal::OT_BVH || b->getObjectType() == coal::OT_HFIELD)) {  // coal's order: b first
    const auto query = table_.collision_matrix[type_b][type_a];
    if (!query) throw std::invalid_argument("coal has no collision query between these geometry types");
    found = query(b, placement_b, a, placement_a, &solver_, request, result);
    result.swapObjects();
    result.nearest_points[0].swap(result.nearest_points[1]);
    result.normal *= -1;
  } else {
    const auto query = table_.collision_matrix[type_a][type_b];
    if (!query) throw std::invalid_argument("coal has no collision query between these geometry types");
    found = query(a, placement_a, b, placement_b, &solver_, request, result);
  }
  result.cached_gjk_guess = solver_.cached_guess;
  result.cached_support_func_guess = solver_.support_func_cached_guess;
  request.updateGuess(result);
  return found;
}

}  // namespace bhgrasp
