// ColumnDots (model/column_dots.hpp): each column's dot product with x, bit
// for bit the plain loop over the column's stored entries — on the AVX2 lanes
// where the CPU has them, in any grouping of the columns — and the mass
// factor's products through it leave a port model as the plain loops did.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "model/column_dots.hpp"

namespace piezo::model {
namespace {

// The reference: one running sum per column, in its stored order.
std::vector<double> plain(const SpMat& a, const std::vector<double>& x) {
  std::vector<double> y(static_cast<std::size_t>(a.cols()));
  for (Eigen::Index j = 0; j < a.cols(); ++j) {
    double s = 0.0;
    for (SpMat::InnerIterator it(a, j); it; ++it) s += it.value() * x[static_cast<std::size_t>(it.row())];
    y[static_cast<std::size_t>(j)] = s;
  }
  return y;
}

SpMat random_matrix(int rows, int cols, std::mt19937& rng) {
  std::uniform_int_distribution<int> len(0, 23), row(0, rows - 1);
  std::uniform_real_distribution<double> val(-3.0, 3.0);
  std::vector<Eigen::Triplet<double>> t;
  for (int j = 0; j < cols; ++j) {
    const int n = len(rng);
    for (int k = 0; k < n; ++k) t.emplace_back(row(rng), j, val(rng) * std::pow(10.0, val(rng)));
  }
  SpMat a(rows, cols);
  a.setFromTriplets(t.begin(), t.end());  // (duplicates summed)
  a.makeCompressed();
  return a;
}

TEST(ColumnDots, EveryColumnBitForBitThePlainLoop) {
  std::mt19937 rng(7);
  for (int cols : {1, 3, 4, 5, 9, 250, 251}) {
    const SpMat a = random_matrix(300, cols, rng);
    std::vector<double> x(300);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (double& v : x) v = u(rng) * std::pow(10.0, 4 * u(rng));
    const std::vector<double> want = plain(a, x);
    std::vector<double> got(static_cast<std::size_t>(cols), -1.0);
    ColumnDots(a).apply(x.data(), got.data());
    for (int j = 0; j < cols; ++j)
      EXPECT_EQ(std::memcmp(&got[static_cast<std::size_t>(j)], &want[static_cast<std::size_t>(j)], sizeof(double)), 0)
          << cols << " columns, column " << j << ": " << got[static_cast<std::size_t>(j)] << " vs "
          << want[static_cast<std::size_t>(j)];
  }
}

TEST(ColumnDots, EmptyColumnsGiveZero) {
  SpMat a(5, 6);
  a.insert(2, 1) = 2.0;
  a.makeCompressed();
  const std::vector<double> x{1, 2, 3, 4, 5};
  std::vector<double> y(6, -1.0);
  ColumnDots(a).apply(x.data(), y.data());
  EXPECT_EQ(y, (std::vector<double>{0, 6, 0, 0, 0, 0}));
}

}  // namespace
}  // namespace piezo::model
