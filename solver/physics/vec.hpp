#pragma once
#include "host_device.hpp"

namespace spate {

// A small fixed-size vector for 2D or 3D physics. Components are float32 like the particle fields.
template <int Dim>
struct Vec {
  float c[Dim];
  SPATE_HD float& operator[](int k) { return c[k]; }
  SPATE_HD float operator[](int k) const { return c[k]; }
};

template <int Dim>
SPATE_HD Vec<Dim> operator-(const Vec<Dim>& a, const Vec<Dim>& b) {
  Vec<Dim> r;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) r[k] = a[k] - b[k];
  return r;
}
template <int Dim>
SPATE_HD Vec<Dim> operator+(const Vec<Dim>& a, const Vec<Dim>& b) {
  Vec<Dim> r;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) r[k] = a[k] + b[k];
  return r;
}
template <int Dim>
SPATE_HD Vec<Dim> operator*(float s, const Vec<Dim>& a) {
  Vec<Dim> r;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) r[k] = s * a[k];
  return r;
}
template <int Dim>
SPATE_HD Vec<Dim>& operator+=(Vec<Dim>& a, const Vec<Dim>& b) {
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) a[k] += b[k];
  return a;
}
template <int Dim>
SPATE_HD float dot(const Vec<Dim>& a, const Vec<Dim>& b) {
  float s = 0.0f;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) s += a[k] * b[k];
  return s;
}
template <int Dim>
SPATE_HD Vec<Dim> zero_vec() {
  Vec<Dim> r;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) r[k] = 0.0f;
  return r;
}

}  // namespace spate
