// tightex::Vector (tightex/vector.hpp), the mesh's own vector type: its arithmetic gives the same bits
// as Eigen's fixed-size vectors, which the stages mix it with, so outputs do not depend on which of
// the two a stage computes in.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstring>
#include <random>
#include <sstream>
#include <type_traits>

#include "core/eigen_vector.hpp"
#include "tightex/vector.hpp"

namespace tightex {
namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

template <int N>
::testing::AssertionResult same_bits(const Eigen::Matrix<double, N, 1>& expected, const Vector<N>& v) {
  for (int i = 0; i < N; ++i)
    if (!same_bits(expected[i], v[i])) return ::testing::AssertionFailure() << "coefficient " << i << ": " << expected[i] << " vs " << v[i];
  return ::testing::AssertionSuccess();
}

/// Random vectors over 20 orders of magnitude, as positions and texture coordinates come.
template <int N>
void expect_eigen_bits(uint64_t seed) {
  using EigenVector = Eigen::Matrix<double, N, 1>;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> mantissa(-1000.0, 1000.0);
  for (int it = 0; it < 20000; ++it) {
    EigenVector a, b;
    for (int i = 0; i < N; ++i) a[i] = mantissa(rng) * std::pow(10.0, int(rng() % 20) - 10), b[i] = mantissa(rng);
    const Vector<N> va(a), vb(b);
    const double s = mantissa(rng);
    ASSERT_TRUE(same_bits(a.dot(b), va.dot(vb))) << "dot";
    ASSERT_TRUE(same_bits(a.squaredNorm(), va.squaredNorm())) << "squaredNorm";
    ASSERT_TRUE(same_bits(a.norm(), va.norm())) << "norm";
    ASSERT_TRUE(same_bits<N>(a.normalized(), va.normalized())) << "normalized";
    ASSERT_TRUE(same_bits<N>(s * a + b * 2.5 - a / s, s * va + vb * 2.5 - va / s)) << "sums and scales";
    ASSERT_TRUE(same_bits<N>(a.cwiseMin(b), va.cwiseMin(vb))) << "cwiseMin";
    ASSERT_TRUE(same_bits<N>(a.cwiseProduct(b), va.cwiseProduct(vb))) << "cwiseProduct";
    if constexpr (N == 3) ASSERT_TRUE(same_bits<N>(a.cross(b), va.cross(vb))) << "cross";
    ASSERT_TRUE(same_bits<N>(a, Vector<N>(as_eigen(va)))) << "through the Eigen view";
  }
}

TEST(Vector, ArithmeticHasEigensBits2) { expect_eigen_bits<2>(1); }
TEST(Vector, ArithmeticHasEigensBits3) { expect_eigen_bits<3>(2); }
TEST(Vector, ArithmeticHasEigensBits4) { expect_eigen_bits<4>(3); }

// A vector of another size does not convert: Eigen's 3-vector to a Vec2 would drop a coefficient.
static_assert(std::is_convertible_v<Eigen::Vector3d, Vec3> && std::is_convertible_v<Eigen::VectorXd, Vec3>);
static_assert(!std::is_convertible_v<Eigen::Vector3d, Vec2> && !std::is_convertible_v<Vec3, Vec2> &&
              !std::is_constructible_v<Vec4, Eigen::Vector2d>);

TEST(Vector, ZeroStaysZeroWhenNormalized) {
  EXPECT_EQ(Vec3::Zero().normalized(), Vec3::Zero());
  EXPECT_EQ(Vec3(0, 3, 4).normalized(), Vec3(0, 0.6, 0.8));
}

TEST(Vector, EigenViewSharesTheCoefficients) {
  Vec2 v(1, 2);
  as_eigen(v) = Eigen::Matrix2d{{0, 1}, {1, 0}} * as_eigen(v);
  EXPECT_EQ(v, Vec2(2, 1));
  EXPECT_EQ(Vec4(1, 2, 3, 4).head<3>(), Vec3(1, 2, 3));
  EXPECT_EQ(Vec4(Vec3(1, 2, 3), -1), Vec4(1, 2, 3, -1));
  std::ostringstream text;
  text << Vec3(1, 2.5, -3);
  EXPECT_EQ(text.str(), "1 2.5 -3");
}

}  // namespace
}  // namespace tightex
