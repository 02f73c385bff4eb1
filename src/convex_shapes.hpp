// Convex shapes across the Python/C++ boundary.  Pinocchio 4.1's serialisation of a GeometryModel has no coal::Convex
// (Python's saveToString fails: "unregistered class"), so bhgrasp/sim/geometry_text.py writes each convex shape's
// points and triangles ahead of the model's text, a placeholder in its place, and geometry_from_text puts them back.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <coal/shape/convex.h>

namespace bhgrasp {

// The radius [m] of the sphere geometry_text.py writes in each convex shape's place (checked when it is replaced).
constexpr double kConvexPlaceholderRadius = 1e-3;

struct ConvexShape {
  std::size_t geometry;                                     // its index in the GeometryModel
  std::shared_ptr<coal::Convex<coal::Triangle>> shape;      // its points and triangles, as written
};

// The convex shapes written ahead of `text` (none if it does not start with the header) and, in `rest`, the
// GeometryModel's own text that follows them.  Throws std::invalid_argument on a malformed header or record.
std::vector<ConvexShape> read_convex_shapes(const std::string& text, std::string& rest);

}  // namespace bhgrasp
