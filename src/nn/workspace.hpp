#pragma once
// Batch workspaces that stop allocating once grown (issue 14: nothing allocated per batch).
//
// GrowingMatrix: a rows × cols matrix over storage that only grows. Eigen's resize frees and
// allocates whenever rows × cols changes, and the trainer's batches change size (near-equal
// batches differ by one column; the noisy half and the whole batch alternate); a view of
// the first rows × cols entries of kept storage has the layout of a fresh matrix of that
// shape, so every product and reduction over it rounds exactly as over the fresh matrix.
//
// gemm: C = A B or C += A B (A and B optionally transposed) through Eigen's own kernel and its
// own blocking sizes, with the packing buffers held by the caller. Eigen's product packs
// the operands into buffers of kc × mc and kc × nc scalars that it puts on the stack up
// to 128 KB and on the heap above; the full-size decoders' output layers pack megabytes
// (the armadillo's 10,020 × 50 layer: 3.9 MB), so only caller-kept buffers avoid the
// heap. Same kernel, same blocking, so the same round-off as `C.noalias() = A * B`
// (tested bit for bit in tests/nn/test_workspace.cpp). The general case calls
// Eigen::internal::general_matrix_matrix_product of Eigen 3.4 (Debian 12's); any other
// Eigen version, and the shapes Eigen evaluates without packing (tiny products, one row or
// one column), go through the ordinary Eigen product.
#include <vector>

#include <Eigen/Core>

#include "core/types.hpp"

namespace lb::nn {

template <typename S>
class GrowingMatrix {
public:
    using Matrix = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;

    /// Set the shape; the storage grows if needed and never shrinks. Contents are
    /// unspecified after a change of shape.
    Eigen::Map<Matrix> resize(Index rows, Index cols)
    {
        const std::size_t size = std::size_t(rows * cols);
        if (size > m_storage.size()) m_storage.resize(size);
        m_rows = rows;
        m_cols = cols;
        return view();
    }
    Eigen::Map<Matrix> view() { return Eigen::Map<Matrix>(m_storage.data(), m_rows, m_cols); }
    Eigen::Map<const Matrix> view() const { return Eigen::Map<const Matrix>(m_storage.data(), m_rows, m_cols); }
    Index rows() const { return m_rows; }
    Index cols() const { return m_cols; }

private:
    std::vector<S, Eigen::aligned_allocator<S>> m_storage;
    Index m_rows = 0, m_cols = 0;
};

/// Packing buffers of one thread's products (kept between calls; grow to the largest seen).
template <typename S>
struct GemmWorkspace {
    std::vector<S, Eigen::aligned_allocator<S>> lhs, rhs;
};

enum class GemmOp { assign, add };

namespace detail {

#if EIGEN_VERSION_AT_LEAST(3, 4, 0) && !EIGEN_VERSION_AT_LEAST(3, 4, 90)
#define LB_KEPT_GEMM 1
/// Eigen's blocking for one product (gemm_blocking_space's sizes for a column-major result,
/// one thread, L3 blocking on, as Eigen's product uses), pointed at the caller's buffers.
template <typename S>
class KeptBlocking : public Eigen::internal::level3_blocking<S, S> {
public:
    KeptBlocking(Index rows, Index cols, Index depth, GemmWorkspace<S>& ws)
    {
        this->m_mc = rows;
        this->m_nc = cols;
        this->m_kc = depth;
        Eigen::internal::computeProductBlockingSizes<S, S, 1>(this->m_kc, this->m_mc, this->m_nc, Index(1));
        const std::size_t a = std::size_t(this->m_kc * this->m_mc), b = std::size_t(this->m_kc * this->m_nc);
        if (ws.lhs.size() < a) ws.lhs.resize(a);
        if (ws.rhs.size() < b) ws.rhs.resize(b);
        this->m_blockA = ws.lhs.data();
        this->m_blockB = ws.rhs.data();
    }
};
#else
#define LB_KEPT_GEMM 0
#endif

} // namespace detail

namespace detail {
#if LB_KEPT_GEMM
template <typename S, int LhsOrder, int RhsOrder>
void packed_gemm(Index m, Index n, Index k, const S* A, Index lda, const S* B, Index ldb, S* C, Index ldc,
                 GemmWorkspace<S>& ws)
{
    KeptBlocking<S> blocking(m, n, k, ws);
    Eigen::internal::general_matrix_matrix_product<Index, S, LhsOrder, false, S, RhsOrder, false, Eigen::ColMajor,
                                                   1>::run(m, n, k, A, lda, B, ldb, C, 1, ldc, S(1), blocking, nullptr);
}
#endif
} // namespace detail

/// C = op(A) op(B) (GemmOp::assign) or C += op(A) op(B) (GemmOp::add), op(M) = Mᵀ if
/// transposed. Shapes: op(A) m × k, op(B) k × n, C m × n. No heap allocation once `ws` has
/// grown to the product's blocks (Eigen 3.4).
template <typename S>
void gemm(const Eigen::Ref<const Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>>& A, bool transpose_a,
          const Eigen::Ref<const Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>>& B, bool transpose_b,
          Eigen::Ref<Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>> C, GemmOp op, GemmWorkspace<S>& ws)
{
    const Index m = C.rows(), n = C.cols(), k = transpose_b ? B.cols() : B.rows();
    eigen_assert((transpose_a ? A.cols() : A.rows()) == m && (transpose_a ? A.rows() : A.cols()) == k &&
                 (transpose_b ? B.rows() : B.cols()) == n);
    // Eigen's own dispatch (generic_product_impl<..., GemmProduct>): tiny products are
    // evaluated coefficient-wise, one row or one column as a GEMV; neither packs.
    const bool packed = LB_KEPT_GEMM && !(k + m + n < EIGEN_GEMM_TO_COEFFBASED_THRESHOLD && k > 0) && m > 1 && n > 1;
    if (!packed) {
        const bool add = op == GemmOp::add;
        if (transpose_a && transpose_b)
            add ? (C.noalias() += A.transpose() * B.transpose()) : (C.noalias() = A.transpose() * B.transpose());
        else if (transpose_a)
            add ? (C.noalias() += A.transpose() * B) : (C.noalias() = A.transpose() * B);
        else if (transpose_b)
            add ? (C.noalias() += A * B.transpose()) : (C.noalias() = A * B.transpose());
        else
            add ? (C.noalias() += A * B) : (C.noalias() = A * B);
        return;
    }
#if LB_KEPT_GEMM
    if (op == GemmOp::assign) C.setZero();  // as Eigen's evalTo: zero, then accumulate
    if (k == 0) return;
    using Eigen::ColMajor;
    using Eigen::RowMajor;
    // A transposed column-major matrix is a row-major one with the same stride.
    if (transpose_a && transpose_b)
        detail::packed_gemm<S, RowMajor, RowMajor>(m, n, k, A.data(), A.outerStride(), B.data(), B.outerStride(),
                                                   C.data(), C.outerStride(), ws);
    else if (transpose_a)
        detail::packed_gemm<S, RowMajor, ColMajor>(m, n, k, A.data(), A.outerStride(), B.data(), B.outerStride(),
                                                   C.data(), C.outerStride(), ws);
    else if (transpose_b)
        detail::packed_gemm<S, ColMajor, RowMajor>(m, n, k, A.data(), A.outerStride(), B.data(), B.outerStride(),
                                                   C.data(), C.outerStride(), ws);
    else
        detail::packed_gemm<S, ColMajor, ColMajor>(m, n, k, A.data(), A.outerStride(), B.data(), B.outerStride(),
                                                   C.data(), C.outerStride(), ws);
#else
    (void)ws;
#endif
}

/// C = op(A) B or C += op(A) B: gemm with B as it is.
template <typename S>
void gemm(const Eigen::Ref<const Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>>& A, bool transpose_a,
          const Eigen::Ref<const Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>>& B,
          Eigen::Ref<Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>> C, GemmOp op, GemmWorkspace<S>& ws)
{
    gemm<S>(A, transpose_a, B, false, C, op, ws);
}

} // namespace lb::nn
