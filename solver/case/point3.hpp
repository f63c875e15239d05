#pragma once
// Double-precision points and vectors of the geometry code (meshes, their triangle tree, the
// surface layers): the few operations they share, in one place.
#include <array>
#include <cmath>

namespace spate::point3 {

using P3 = std::array<double, 3>;
inline P3 sub(const P3& a, const P3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline P3 cross(const P3& a, const P3& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
inline double dot(const P3& a, const P3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline double norm(const P3& a) { return std::sqrt(dot(a, a)); }
inline double distance2(const P3& a, const P3& b) { return dot(sub(a, b), sub(a, b)); }

}  // namespace spate::point3
