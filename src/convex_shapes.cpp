// Convex shapes written ahead of a GeometryModel's text: see convex_shapes.hpp and bhgrasp/sim/geometry_text.py
// (the format: a header line "bhgrasp-convex-shapes 1 <count>", then per shape "<geometry> <points> <triangles>",
// its points' coordinates as hexadecimal floats (exact) and its triangles' vertex indexes; then the model's text).
// Every record is checked: a malformed or truncated text, a shape of fewer than 4 points or triangles, a coordinate
// that is not finite, an index out of range or geometries not in increasing order is refused with
// std::invalid_argument, before anything is allocated beyond what the text can hold.
#include "convex_shapes.hpp"

#include <charconv>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <system_error>

namespace bhgrasp {
namespace {

constexpr const char* kHeader = "bhgrasp-convex-shapes";

[[noreturn]] void refuse(const std::string& what) { throw std::invalid_argument("convex shapes: " + what); }

long read_count(std::istringstream& in, const char* what, long most) {
  long value = -1;
  if (!(in >> value) || value < 0 || value > most) refuse(std::string("a malformed or impossible ") + what);
  return value;
}

// A coordinate as Python's float.hex() writes it ("-0x1.8p+3"), read with std::from_chars: exact, and independent of
// the process's locale (strtod reads "1.5" as 1 where the decimal point is a comma).
double read_real(std::istringstream& in) {
  std::string token;
  if (!(in >> token)) refuse("the text ends inside a point");
  const char* first = token.data();
  const char* last = first + token.size();
  const bool negative = first != last && *first == '-';
  if (negative) ++first;
  if (last - first < 2 || first[0] != '0' || (first[1] != 'x' && first[1] != 'X')) refuse("a malformed coordinate");
  first += 2;
  double value = 0.0;
  const auto [end, error] = std::from_chars(first, last, value, std::chars_format::hex);
  if (error != std::errc() || end != last || !std::isfinite(value)) refuse("a malformed or non-finite coordinate");
  return negative ? -value : value;
}

}  // namespace

std::vector<ConvexShape> read_convex_shapes(const std::string& text, std::string& rest) {
  std::vector<ConvexShape> shapes;
  std::istringstream in(text);
  std::string header;
  if (!(in >> header) || header != kHeader) {
    rest = text;  // Pinocchio's own text, no convex shape ahead of it
    return shapes;
  }
  // No count can exceed what the text could hold: a point takes at least 6 characters ("0x0p+0" and a separator),
  // a triangle 6 ("0 1 2 "), a record 6.
  const long most = static_cast<long>(text.size() / 6) + 1;
  if (read_count(in, "format version", most) != 1) refuse("unknown format version");
  const long count = read_count(in, "shape count", most);
  long previous = -1;
  for (long k = 0; k < count; ++k) {
    const long geometry = read_count(in, "geometry index", most);
    if (geometry <= previous) refuse("geometry indexes must increase");
    previous = geometry;
    const long n_points = read_count(in, "point count", most / 3);
    const long n_triangles = read_count(in, "triangle count", most / 3);
    if (n_points < 4 || n_triangles < 4) refuse("a shape needs at least 4 points and 4 triangles");
    auto points = std::make_shared<std::vector<coal::Vec3s>>(static_cast<std::size_t>(n_points));
    for (auto& point : *points)
      for (int axis = 0; axis < 3; ++axis) point[axis] = read_real(in);
    auto triangles = std::make_shared<std::vector<coal::Triangle>>(static_cast<std::size_t>(n_triangles));
    for (auto& triangle : *triangles) {
      const long a = read_count(in, "vertex index", n_points - 1), b = read_count(in, "vertex index", n_points - 1);
      const long c = read_count(in, "vertex index", n_points - 1);
      triangle.set(static_cast<coal::Triangle::index_type>(a), static_cast<coal::Triangle::index_type>(b),
                   static_cast<coal::Triangle::index_type>(c));
    }
    auto shape = std::make_shared<coal::Convex<coal::Triangle>>(points, static_cast<unsigned int>(n_points), triangles,
                                                                static_cast<unsigned int>(n_triangles));
    shapes.push_back({static_cast<std::size_t>(geometry), shape});
  }
  std::string line;
  std::getline(in, line);  // the end of the last record's line: nothing else on it
  if (line.find_first_not_of(" \t\r") != std::string::npos) refuse("unexpected text after the last record");
  const std::streamoff start = in.tellg();
  if (start < 0 || text.find_first_not_of(" \t\r\n", static_cast<std::size_t>(start)) == std::string::npos)
    refuse("no geometry model follows them");
  rest = text.substr(static_cast<std::size_t>(start));
  return shapes;
}

}  // namespace bhgrasp
