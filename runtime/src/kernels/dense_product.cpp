#include "dense_product.hpp"

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <new>
#include <string_view>

// A portable build compiles the kernel three times, for x86-64-v4 (AVX-512), x86-64-v3 (AVX2 and FMA) and the
// baseline (SSE2), and the dynamic loader picks the widest the machine has (GCC's target_clones, GCC 12 or later on
// glibc). A build for a given machine (FLEXBODY_NATIVE: __AVX2__ is defined) and other compilers build only the
// last; runtime/CMakeLists.txt asks for 512-bit vectors in that file where the machine has them.
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 12 && defined(__x86_64__) && defined(__GLIBC__) && \
    !defined(__AVX2__)
#define FLEXBODY_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define FLEXBODY_CLONES
#endif

namespace flexbody::runtime::detail {
namespace {

// Column-major A (rows x cols, leading dimension ld), four columns per pass over y: y is read and written a
// quarter as often as column by column, which is what bounds the one-column loop (measured 7.8 µs against
// 3.5 µs at 180 square). The compiler vectorizes the inner loop over rows.
FLEXBODY_CLONES void product_kernel(std::ptrdiff_t rows, std::ptrdiff_t cols, std::ptrdiff_t ld, const double* __restrict a,
                                    const double* __restrict x, double* __restrict y) {
  std::ptrdiff_t j = 0;
  if (cols >= 4) {  // the first four columns set y (a separate zeroing pass would be a call to memset)
    const double* c0 = a;
    const double* c1 = c0 + ld;
    const double* c2 = c1 + ld;
    const double* c3 = c2 + ld;
    const double x0 = x[0], x1 = x[1], x2 = x[2], x3 = x[3];
    for (std::ptrdiff_t i = 0; i < rows; ++i) y[i] = c0[i] * x0 + c1[i] * x1 + c2[i] * x2 + c3[i] * x3;
    j = 4;
  } else {
    for (std::ptrdiff_t i = 0; i < rows; ++i) y[i] = 0.0;
  }
  for (; j + 4 <= cols; j += 4) {
    const double* c0 = a + j * ld;
    const double* c1 = c0 + ld;
    const double* c2 = c1 + ld;
    const double* c3 = c2 + ld;
    const double x0 = x[j], x1 = x[j + 1], x2 = x[j + 2], x3 = x[j + 3];
    for (std::ptrdiff_t i = 0; i < rows; ++i) y[i] += c0[i] * x0 + c1[i] * x1 + c2[i] * x2 + c3[i] * x3;
  }
  for (; j < cols; ++j) {
    const double* c = a + j * ld;
    const double xj = x[j];
    for (std::ptrdiff_t i = 0; i < rows; ++i) y[i] += c[i] * xj;
  }
}

}  // namespace

void dense_product(const Eigen::MatrixXd& a, const double* x, double* y) {
  product_kernel(static_cast<std::ptrdiff_t>(a.rows()), static_cast<std::ptrdiff_t>(a.cols()), static_cast<std::ptrdiff_t>(a.rows()), a.data(), x, y);
}

PaddedMatrix::PaddedMatrix(const Eigen::Ref<const Eigen::MatrixXd>& a)
    : rows_(a.rows()), cols_(a.cols()), stride_((a.rows() + 7) / 8 * 8) {
  constexpr std::align_val_t kAlignment{64};
  const auto size = static_cast<std::size_t>(std::max<Eigen::Index>(1, stride_ * cols_));
  auto* data = static_cast<double*>(::operator new(size * sizeof(double), kAlignment));
  data_ = std::shared_ptr<const double[]>(data, [](const double* p) { ::operator delete(const_cast<double*>(p), kAlignment); });
  std::fill(data, data + size, 0.0);  // the padding rows are never read, but stay defined
  Eigen::Map<Eigen::MatrixXd, 0, Eigen::OuterStride<>>(data, rows_, cols_, Eigen::OuterStride<>(stride_)) = a;
}

void PaddedMatrix::multiply(const double* x, double* y) const {
  product_kernel(static_cast<std::ptrdiff_t>(rows_), static_cast<std::ptrdiff_t>(cols_), static_cast<std::ptrdiff_t>(stride_), data_.get(), x, y);
}

bool PaddedMatrix::holds(const Eigen::Ref<const Eigen::MatrixXd>& a) const {
  if (a.rows() != rows_ || a.cols() != cols_) return false;
  for (Eigen::Index c = 0; c < cols_; ++c)  // bytes, not values: -0.0 and 0.0 differ, as NaNs would
    if (std::memcmp(a.col(c).data(), data_.get() + c * stride_, static_cast<std::size_t>(rows_) * sizeof(double)) != 0)
      return false;
  return true;
}

PaddedMatrix SharedMatrices::get(const Eigen::Ref<const Eigen::MatrixXd>& a) {
  std::size_t hash = std::hash<Eigen::Index>()(a.rows() * 31 + a.cols());
  for (Eigen::Index c = 0; c < a.cols(); ++c) {
    const std::string_view bytes(reinterpret_cast<const char*>(a.col(c).data()), static_cast<std::size_t>(a.rows()) * sizeof(double));
    hash = hash * 1000003U ^ std::hash<std::string_view>()(bytes);
  }
  const auto [first, last] = made_.equal_range(hash);
  for (auto it = first; it != last; ++it)
    if (it->second.holds(a)) return it->second;
  return made_.emplace(hash, PaddedMatrix(a))->second;
}

}  // namespace flexbody::runtime::detail
