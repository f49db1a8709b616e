// The runtime's dispatched matrix-vector kernel (runtime/src/kernels) against Eigen's product.
#include "kernels/dense_product.hpp"

#include <Eigen/Core>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <utility>

namespace {

// Shapes the runtime uses (3 n_f square; 3 n_f x (12 + constraint rows)) and ones that leave a remainder after
// the kernel's blocks of four columns, down to empty.
TEST(DenseProduct, AgreesWithEigenToTheRoundOffOfAReorderedSum) {
  const std::pair<Eigen::Index, Eigen::Index> shapes[] = {{180, 180}, {180, 21}, {21, 180}, {7, 13}, {1, 1}, {5, 0}, {0, 3}};
  for (const auto& [rows, cols] : shapes) {
    SCOPED_TRACE(std::to_string(rows) + " x " + std::to_string(cols));
    const Eigen::MatrixXd a = Eigen::MatrixXd::Random(rows, cols);
    const Eigen::VectorXd x = Eigen::VectorXd::Random(cols);
    Eigen::VectorXd y = Eigen::VectorXd::Constant(rows, std::numeric_limits<double>::quiet_NaN());  // must be overwritten
    flexbody::runtime::detail::dense_product(a, x.data(), y.data());
    const Eigen::VectorXd expected = a * x;
    // Each entry is a sum of `cols` products in another order: the two differ by at most 2 cols ε Σ_j |a_ij x_j|.
    const Eigen::VectorXd bound =
        2.0 * static_cast<double>(cols) * std::numeric_limits<double>::epsilon() * (a.cwiseAbs() * x.cwiseAbs());
    for (Eigen::Index i = 0; i < rows; ++i) EXPECT_LE(std::abs(y(i) - expected(i)), bound(i)) << "row " << i;
  }
}

// The padded storage: every column starts on a 64-byte boundary, whatever the row count, and the product is the
// same as on the plain matrix (the same sums in the same order: equal to the last bit).
TEST(DenseProduct, PaddedMatrixGivesTheSameProduct) {
  const std::pair<Eigen::Index, Eigen::Index> shapes[] = {{180, 180}, {21, 180}, {7, 13}, {9, 1}, {3, 0}};
  for (const auto& [rows, cols] : shapes) {
    SCOPED_TRACE(std::to_string(rows) + " x " + std::to_string(cols));
    const Eigen::MatrixXd a = Eigen::MatrixXd::Random(rows, cols);
    const Eigen::VectorXd x = Eigen::VectorXd::Random(cols);
    const flexbody::runtime::detail::PaddedMatrix padded(a), copy = padded;
    EXPECT_EQ(copy.rows(), rows);
    EXPECT_EQ(copy.cols(), cols);
    Eigen::VectorXd plain(rows), y(rows);
    flexbody::runtime::detail::dense_product(a, x.data(), plain.data());
    copy.multiply(x.data(), y.data());
    EXPECT_EQ(y, plain);
  }
}

// Equal constant matrices are stored once (a scene of copies of one part); a matrix that differs in one bit, even
// 0.0 against -0.0, or in shape gets its own storage.
TEST(DenseProduct, SharedMatricesStoreEqualMatricesOnce) {
  flexbody::runtime::detail::SharedMatrices shared;
  const Eigen::MatrixXd a = Eigen::MatrixXd::Random(54, 54);
  const flexbody::runtime::detail::PaddedMatrix first = shared.get(a), again = shared.get(Eigen::MatrixXd(a));
  EXPECT_EQ(first.storage(), again.storage());
  EXPECT_TRUE(again.holds(a));
  Eigen::MatrixXd b = a;
  b(53, 53) = std::nextafter(b(53, 53), 2.0);
  const flexbody::runtime::detail::PaddedMatrix other = shared.get(b);
  EXPECT_NE(other.storage(), first.storage());
  EXPECT_TRUE(other.holds(b));
  EXPECT_FALSE(other.holds(a));
  Eigen::MatrixXd zero = Eigen::MatrixXd::Zero(3, 3), negative = zero;
  negative(1, 1) = -0.0;
  EXPECT_NE(shared.get(zero).storage(), shared.get(negative).storage());
  EXPECT_NE(shared.get(Eigen::MatrixXd::Zero(9, 1)).storage(), shared.get(Eigen::MatrixXd::Zero(3, 3)).storage());
  EXPECT_EQ(shared.get(a.topRows(20)).storage(), shared.get(Eigen::MatrixXd(a.topRows(20))).storage());  // strided input
}

}  // namespace
