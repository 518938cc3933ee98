#pragma once
// The small 3-vector the builder (float, aliasing xyz position arrays) and the attribute term
// (double) compute with.

#include <cmath>

namespace tom::detail {

template <class T>
struct Vec3T {
    T x, y, z;
};
template <class T>
inline Vec3T<T> sub(Vec3T<T> a, Vec3T<T> b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <class T>
inline Vec3T<T> cross(Vec3T<T> a, Vec3T<T> b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
template <class T>
inline T dot(Vec3T<T> a, Vec3T<T> b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <class T>
inline T length(Vec3T<T> a) { return std::sqrt(dot(a, a)); }

} // namespace tom::detail
