// coal::collide on a solver kept between queries (the contact detection of detect.cpp).
//
// coal::collide (coal 3.0, src/collision.cpp) makes a GJKSolver for every query.  Making one resets its GJK, whose
// assertion builds a std::invalid_argument (its message on the heap) even in a release build, and its EPA, whose
// stores are allocated again at the first penetrating query.  This does what coal::collide does, with the same
// look-up table, the same steps and the same arithmetic, on one solver set back before every query to the state a new
// one starts in (cached guesses, settings and statuses from the request).  Results equal coal::collide's bit for bit:
// with `kept` false it calls coal::collide itself, the reference tests/test_narrowphase.py holds it to.
#pragma once

#include <cstddef>

#include <coal/collision_data.h>
#include <coal/collision_func_matrix.h>
#include <coal/narrowphase/narrowphase.h>

namespace bhgrasp {

class Narrowphase {
 public:
  // What coal::collide(a, placement_a, b, placement_b, request, result) returns and leaves in result and request.
  std::size_t collide(const coal::CollisionGeometry* a, const coal::Transform3s& placement_a,
                      const coal::CollisionGeometry* b, const coal::Transform3s& placement_b,
                      const coal::CollisionRequest& request, coal::CollisionResult& result);

  bool kept = true;  // false: coal::collide, a new solver per query

 private:
  coal::GJKSolver solver_;
  coal::CollisionFunctionMatrix table_;  // coal's own look-up table (the one coal::collide consults), built once
};

}  // namespace bhgrasp
