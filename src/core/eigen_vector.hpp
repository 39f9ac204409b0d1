// Eigen views of tightex's own vectors (tightex/vector.hpp), for the stages' products with Eigen
// matrices and rotations: the view shares the vector's doubles, so nothing is copied.
#pragma once
#include <Eigen/Core>

#include "tightex/vector.hpp"

namespace tightex {

template <int N>
Eigen::Map<const Eigen::Matrix<double, N, 1>> as_eigen(const Vector<N>& v) {
  return Eigen::Map<const Eigen::Matrix<double, N, 1>>(v.data());
}
template <int N>
Eigen::Map<Eigen::Matrix<double, N, 1>> as_eigen(Vector<N>& v) {
  return Eigen::Map<Eigen::Matrix<double, N, 1>>(v.data());
}

}  // namespace tightex
