#pragma once
// out += Wᵀ A for a column-major W (m × n) and an A with few columns (k ≲ 8): one
// pass over W, each column of W reused from L1 for the k dot products. Eigen's GEMM
// would repack all of W on every call, which costs several times the product itself
// when k is tiny (reverse-mode Jacobian rows, single-sample backward passes).
#include <Eigen/Core>

namespace lb::nn {

inline constexpr Eigen::Index small_product_max_columns = 8;

template <typename DerivedW, typename DerivedA, typename DerivedOut>
void add_transpose_product(const Eigen::MatrixBase<DerivedW>& W, const Eigen::MatrixBase<DerivedA>& A,
                           Eigen::MatrixBase<DerivedOut>& out)
{
    static_assert(!DerivedW::IsRowMajor, "W must be column-major");
    for (Eigen::Index j = 0; j < W.cols(); ++j) {
        const auto w = W.col(j);
        for (Eigen::Index c = 0; c < A.cols(); ++c) out(j, c) += w.dot(A.col(c));
    }
}

} // namespace lb::nn
