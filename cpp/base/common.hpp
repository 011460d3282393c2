// Shared small types of the contactmg core.
#pragma once
#include <Eigen/Dense>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace cmg {

using Index = std::int64_t;

template <int d> using Vec = Eigen::Matrix<double, d, 1>;
template <int d> using Mat = Eigen::Matrix<double, d, d, Eigen::RowMajor>;
template <int d> using VecMap = Eigen::Map<Vec<d>>;
template <int d> using CVecMap = Eigen::Map<const Vec<d>>;
template <int d> using MatMap = Eigen::Map<Mat<d>>;
template <int d> using CMatMap = Eigen::Map<const Mat<d>>;

constexpr double kInf = std::numeric_limits<double>::infinity();

// Raised for bad input; the bindings turn it into ValueError.
struct InputError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// Raised when a long computation is interrupted (Ctrl-C); bindings re-raise KeyboardInterrupt.
struct Interrupted : std::runtime_error {
  Interrupted() : std::runtime_error("interrupted") {}
};

}  // namespace cmg
