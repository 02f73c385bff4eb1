// coal::collide on a solver kept between queries (the contact detection of detect.cpp).
//
// coal::collide (coal 3.0.3, src/collision.cpp) makes a GJKSolver for every query.  Making one resets its GJK, whose
// assertion builds a std::invalid_argument (its message on the heap) even in a release build, and its EPA, whose
// stores are allocated again at the first penetrating query.  This does what coal::collide does, in the same order,
// with a look-up table built by coal's own constructor (equal to the one coal::collide consults), on one solver.
// Before each query the solver gets a new one's cached guesses, then set(request) (settings, distance bound, statuses).
// The rest of it keeps the last query's contents, and equality rests on coal rewriting them before it reads them:
// every GJK run calls minkowski_difference.set and gjk.reset, every EPA run epa.reset (its stores resized, its hull and
// free list rebuilt) and EPA writes every field of a face it makes.  That holds for coal 3.0.3, the version this was
// checked against; with any other coal, `kept` starts false (coal::collide itself) until it is checked again.  Results
// equal coal::collide's bit for bit: tests/test_narrowphase.py steps scenes with `kept` on and off.
#pragma once

#include <cstddef>

#include <coal/collision_data.h>
#include <coal/collision_func_matrix.h>
#include <coal/config.hh>
#include <coal/narrowphase/narrowphase.h>

namespace bhgrasp {

class Narrowphase {
 public:
  // What coal::collide(a, placement_a, b, placement_b, request, result) returns and leaves in result and request.
  std::size_t collide(const coal::CollisionGeometry* a, const coal::Transform3s& placement_a,
                      const coal::CollisionGeometry* b, const coal::Transform3s& placement_b,
                      const coal::CollisionRequest& request, coal::CollisionResult& result);

  // false: coal::collide, a new solver per query (the reference; any coal but the one checked)
  bool kept = COAL_MAJOR_VERSION == 3 && COAL_MINOR_VERSION == 0 && COAL_PATCH_VERSION == 3;

 private:
  coal::GJKSolver solver_;
  coal::CollisionFunctionMatrix table_;  // built by coal's constructor, equal to the table coal::collide consults
};

}  // namespace bhgrasp
