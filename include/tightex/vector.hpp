// Small fixed-size vectors of doubles: the mesh's positions, texture coordinates, normals and tangents.
// tightex's own type, so that a public header names no third-party one. It converts implicitly from any
// vector expression that has size() and operator()(i) (an Eigen vector, for one) and its sums are
// computed in the order Eigen computes them, so code that moves between the two gets the same bits.
#pragma once
#include <cassert>
#include <cmath>
#include <cstddef>
#include <ostream>
#include <type_traits>
#include <utility>

namespace tightex {

namespace detail {
/// The number of coefficients a vector type holds, known at compile time: tightex's kSize, Eigen's
/// SizeAtCompileTime; -1 where it is not known (a dynamic vector).
template <class V>
constexpr int compile_time_size() {
  if constexpr (requires { V::kSize; })
    return int(V::kSize);
  else if constexpr (requires { V::SizeAtCompileTime; })
    return int(V::SizeAtCompileTime);
  else
    return -1;
}
}  // namespace detail

template <int N>
class Vector {
  static_assert(N >= 2 && N <= 4, "tightex::Vector holds 2, 3 or 4 doubles");

 public:
  static constexpr int kSize = N;

  Vector() = default;
  Vector(double x, double y) requires(N == 2) : c_{x, y} {}
  Vector(double x, double y, double z) requires(N == 3) : c_{x, y, z} {}
  Vector(double x, double y, double z, double w) requires(N == 4) : c_{x, y, z, w} {}
  /// A direction and a fourth coefficient (a tangent and its handedness).
  Vector(const Vector<3>& xyz, double w) requires(N == 4) : c_{xyz[0], xyz[1], xyz[2], w} {}
  /// From any other vector expression of N coefficients (read through size() and operator()(i)); one
  /// whose size is known at compile time must be N, a dynamic one must hold N at run time.
  template <class Other>
  requires(!std::is_same_v<std::remove_cvref_t<Other>, Vector> &&
           requires(const Other& o) {
             o.size();
             double(o(0));
           } &&
           (detail::compile_time_size<std::remove_cvref_t<Other>>() == N || detail::compile_time_size<std::remove_cvref_t<Other>>() < 0))
      Vector(const Other& other) {  // NOLINT(google-explicit-constructor): interchangeable with Eigen's
    assert(other.size() == N);
    for (int i = 0; i < N; ++i) c_[i] = other(i);
  }

  static Vector Zero() { return Constant(0.0); }
  static Vector Constant(double value) {
    Vector v;
    for (int i = 0; i < N; ++i) v.c_[i] = value;
    return v;
  }
  static Vector Unit(int axis) {
    Vector v = Zero();
    v.c_[axis] = 1.0;
    return v;
  }
  static Vector UnitX() { return Unit(0); }
  static Vector UnitY() { return Unit(1); }
  static Vector UnitZ() requires(N >= 3) { return Unit(2); }

  static constexpr int size() { return N; }
  double* data() { return c_; }
  const double* data() const { return c_; }
  double& operator[](int i) { return c_[i]; }
  double operator[](int i) const { return c_[i]; }
  double& operator()(int i) { return c_[i]; }
  double operator()(int i) const { return c_[i]; }
  double& x() { return c_[0]; }
  double& y() { return c_[1]; }
  double& z() requires(N >= 3) { return c_[2]; }
  double& w() requires(N == 4) { return c_[3]; }
  double x() const { return c_[0]; }
  double y() const { return c_[1]; }
  double z() const requires(N >= 3) { return c_[2]; }
  double w() const requires(N == 4) { return c_[3]; }
  /// The first M coefficients (a tangent's direction: head<3>()).
  template <int M>
  Vector<M> head() const requires(M >= 2 && M <= N) {
    Vector<M> v;
    for (int i = 0; i < M; ++i) v[i] = c_[i];
    return v;
  }

  /// The sum of the coefficients' products. Four are summed pairwise ((x + z) + (y + w)), as Eigen's
  /// two-double packets do; two and three left to right.
  double dot(const Vector& o) const {
    if constexpr (N == 4) return (c_[0] * o.c_[0] + c_[2] * o.c_[2]) + (c_[1] * o.c_[1] + c_[3] * o.c_[3]);
    double sum = c_[0] * o.c_[0];
    for (int i = 1; i < N; ++i) sum += c_[i] * o.c_[i];
    return sum;
  }
  double squaredNorm() const { return dot(*this); }
  double norm() const { return std::sqrt(squaredNorm()); }
  /// This vector divided by its length; a zero vector stays zero.
  Vector normalized() const {
    const double squared = squaredNorm();
    return squared > 0.0 ? *this / std::sqrt(squared) : *this;
  }
  void normalize() { *this = normalized(); }
  Vector cross(const Vector& o) const requires(N == 3) {
    return {c_[1] * o.c_[2] - c_[2] * o.c_[1], c_[2] * o.c_[0] - c_[0] * o.c_[2], c_[0] * o.c_[1] - c_[1] * o.c_[0]};
  }
  bool allFinite() const {
    for (int i = 0; i < N; ++i)
      if (!std::isfinite(c_[i])) return false;
    return true;
  }
  double minCoeff() const {
    double m = c_[0];
    for (int i = 1; i < N; ++i) m = c_[i] < m ? c_[i] : m;
    return m;
  }
  double maxCoeff() const {
    double m = c_[0];
    for (int i = 1; i < N; ++i) m = c_[i] > m ? c_[i] : m;
    return m;
  }
  Vector cwiseMin(const Vector& o) const {
    return combine(o, [](double a, double b) { return b < a ? b : a; });
  }
  Vector cwiseMax(const Vector& o) const {
    return combine(o, [](double a, double b) { return b > a ? b : a; });
  }
  Vector cwiseProduct(const Vector& o) const {
    return combine(o, [](double a, double b) { return a * b; });
  }
  Vector cwiseQuotient(const Vector& o) const {
    return combine(o, [](double a, double b) { return a / b; });
  }
  Vector cwiseAbs() const {
    return combine(*this, [](double a, double) { return std::abs(a); });
  }
  void setZero() { *this = Zero(); }

  Vector& operator+=(const Vector& o) { return *this = *this + o; }
  Vector& operator-=(const Vector& o) { return *this = *this - o; }
  Vector& operator*=(double s) { return *this = *this * s; }
  Vector& operator/=(double s) { return *this = *this / s; }
  friend Vector operator+(const Vector& a, const Vector& b) {
    return a.combine(b, [](double p, double q) { return p + q; });
  }
  friend Vector operator-(const Vector& a, const Vector& b) {
    return a.combine(b, [](double p, double q) { return p - q; });
  }
  friend Vector operator-(const Vector& a) {
    return a.combine(a, [](double p, double) { return -p; });
  }
  friend Vector operator*(const Vector& a, double s) {
    return a.combine(a, [s](double p, double) { return p * s; });
  }
  friend Vector operator*(double s, const Vector& a) {
    return a.combine(a, [s](double p, double) { return s * p; });
  }
  friend Vector operator/(const Vector& a, double s) {
    return a.combine(a, [s](double p, double) { return p / s; });
  }
  friend bool operator==(const Vector& a, const Vector& b) {
    for (int i = 0; i < N; ++i)
      if (!(a.c_[i] == b.c_[i])) return false;
    return true;
  }

 private:
  template <class Op>
  Vector combine(const Vector& o, Op op) const {
    Vector v;
    for (int i = 0; i < N; ++i) v.c_[i] = op(c_[i], o.c_[i]);
    return v;
  }

  double c_[N];
};

/// The coefficients separated by spaces ("1 2 3"), for messages.
template <int N>
std::ostream& operator<<(std::ostream& out, const Vector<N>& v) {
  for (int i = 0; i < N; ++i) out << (i ? " " : "") << v[i];
  return out;
}

using Vec2 = Vector<2>;
using Vec3 = Vector<3>;
using Vec4 = Vector<4>;
// An array of vectors is an array of doubles, N per vector (the Python module copies numpy's (n, N)
// arrays in and out whole).
static_assert(sizeof(Vec2) == 2 * sizeof(double) && sizeof(Vec3) == 3 * sizeof(double) && sizeof(Vec4) == 4 * sizeof(double));
static_assert(std::is_trivially_copyable_v<Vec3>);

}  // namespace tightex
