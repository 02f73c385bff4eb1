// Convex shapes written ahead of a GeometryModel's text: see convex_shapes.hpp and bhgrasp/sim/geometry_text.py
// (the format: a header line "bhgrasp-convex-shapes 1 <count>", then per shape "<geometry> <points> <triangles>",
// its points' coordinates as hexadecimal floats (exact) and its triangles' vertex indexes; then the model's text).
#include "convex_shapes.hpp"

#include <cstdlib>
#include <sstream>
#include <stdexcept>

namespace bhgrasp {
namespace {

constexpr const char* kHeader = "bhgrasp-convex-shapes";
constexpr long kMaxCount = 100000000;  // a sanity bound on each count read: a corrupt text fails, not allocates

long read_count(std::istringstream& in, const char* what) {
  long value = -1;
  if (!(in >> value) || value < 0 || value > kMaxCount)
    throw std::invalid_argument(std::string("convex shapes: a malformed ") + what);
  return value;
}

double read_real(std::istringstream& in) {
  std::string token;
  if (!(in >> token)) throw std::invalid_argument("convex shapes: the text ends inside a point");
  char* end = nullptr;
  const double value = std::strtod(token.c_str(), &end);  // reads C99 hexadecimal floats exactly
  if (end != token.c_str() + token.size()) throw std::invalid_argument("convex shapes: a malformed coordinate");
  return value;
}

}  // namespace

std::vector<ConvexShape> read_convex_shapes(const std::string& text, std::string& rest) {
  std::vector<ConvexShape> shapes;
  if (text.rfind(kHeader, 0) != 0) {
    rest = text;
    return shapes;
  }
  std::istringstream in(text);
  std::string header;
  in >> header;
  if (read_count(in, "format version") != 1) throw std::invalid_argument("convex shapes: unknown format version");
  const long count = read_count(in, "shape count");
  for (long k = 0; k < count; ++k) {
    const long geometry = read_count(in, "geometry index");
    const long n_points = read_count(in, "point count");
    const long n_triangles = read_count(in, "triangle count");
    auto points = std::make_shared<std::vector<coal::Vec3s>>(static_cast<std::size_t>(n_points));
    for (auto& point : *points)
      for (int axis = 0; axis < 3; ++axis) point[axis] = read_real(in);
    auto triangles = std::make_shared<std::vector<coal::Triangle>>(static_cast<std::size_t>(n_triangles));
    for (auto& triangle : *triangles) {
      const long a = read_count(in, "vertex index"), b = read_count(in, "vertex index");
      const long c = read_count(in, "vertex index");
      if (a >= n_points || b >= n_points || c >= n_points)
        throw std::invalid_argument("convex shapes: a triangle names a point the shape lacks");
      triangle.set(static_cast<coal::Triangle::index_type>(a), static_cast<coal::Triangle::index_type>(b),
                   static_cast<coal::Triangle::index_type>(c));
    }
    auto shape = std::make_shared<coal::Convex<coal::Triangle>>(points, static_cast<unsigned int>(n_points), triangles,
                                                                static_cast<unsigned int>(n_triangles));
    shapes.push_back({static_cast<std::size_t>(geometry), shape});
  }
  std::string line;
  std::getline(in, line);  // the end of the last record's line
  const std::streamoff start = in.tellg();
  if (start < 0) throw std::invalid_argument("convex shapes: no geometry model follows them");
  rest = text.substr(static_cast<std::size_t>(start));
  return shapes;
}

}  // namespace bhgrasp
