// nn::gemm with caller-kept packing buffers against Eigen's own product, bit for bit, and
// without heap allocation once its workspace has grown; nn::GrowingMatrix keeps its storage.
#include <gtest/gtest.h>

#include <random>
#include <string>

#include "nn/workspace.hpp"
#include "support/heap_counter.hpp"

namespace lb::nn {
namespace {

template <typename S>
using Mat = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;

template <typename S>
Mat<S> random_matrix(Index rows, Index cols, unsigned seed)
{
    std::mt19937 gen(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Mat<S> m(rows, cols);
    for (Index j = 0; j < cols; ++j)
        for (Index i = 0; i < rows; ++i) m(i, j) = S(u(gen));
    return m;
}

struct Shape {
    Index m, n, k;
};

// Shapes of the decoders' and integrators' layers (features × batch), the tiny products
// Eigen evaluates coefficient-wise, single rows and columns, and an empty depth.
const Shape kShapes[] = {{200, 256, 12}, {200, 128, 200}, {50, 97, 200}, {3000, 64, 50}, {12, 200, 200},
                         {5, 4, 3},      {1, 40, 30},     {40, 1, 30},   {30, 40, 1},   {8, 8, 0}};

template <typename S>
void expect_same_as_eigen()
{
    GemmWorkspace<S> ws;
    unsigned seed = 1;
    for (const Shape& s : kShapes) {
        for (int transposes = 0; transposes < 4; ++transposes) {
            const bool ta = (transposes & 1) != 0, tb = (transposes & 2) != 0;
            const Mat<S> A_storage = ta ? random_matrix<S>(s.k, s.m, seed++) : random_matrix<S>(s.m, s.k, seed++);
            // As gemm sees it (a Ref), so that the tiny products take the same path.
            const Eigen::Ref<const Mat<S>> A(A_storage);
            // B and C as column blocks of wider matrices, as the batched passes use them.
            const Mat<S> B_full = tb ? random_matrix<S>(s.n, s.k + 3, seed++) : random_matrix<S>(s.k, s.n + 3, seed++);
            const Eigen::Ref<const Mat<S>> B = tb ? B_full.middleCols(2, s.k) : B_full.middleCols(2, s.n);
            const Mat<S> C0 = random_matrix<S>(s.m, s.n, seed++);
            // Both results in column blocks at the same offset of equal matrices: Eigen's
            // coefficient-wise path for tiny products rounds by the destination's alignment.
            Mat<S> got_full = random_matrix<S>(s.m, s.n + 5, seed++), expected_full = got_full;
            auto got = got_full.middleCols(1, s.n);
            auto expected = expected_full.middleCols(1, s.n);
            auto eigen_product = [&](GemmOp op) {
                const bool add = op == GemmOp::add;
                if (ta && tb)
                    add ? (expected.noalias() += A.transpose() * B.transpose())
                        : (expected.noalias() = A.transpose() * B.transpose());
                else if (ta)
                    add ? (expected.noalias() += A.transpose() * B) : (expected.noalias() = A.transpose() * B);
                else if (tb)
                    add ? (expected.noalias() += A * B.transpose()) : (expected.noalias() = A * B.transpose());
                else
                    add ? (expected.noalias() += A * B) : (expected.noalias() = A * B);
            };
            const std::string what = std::to_string(s.m) + "×" + std::to_string(s.n) + "×" + std::to_string(s.k) +
                                     (ta ? " Aᵀ" : " A") + (tb ? " Bᵀ" : " B");
            eigen_product(GemmOp::assign);
            gemm<S>(A, ta, B, tb, got, GemmOp::assign, ws);
            EXPECT_TRUE(got == expected) << what << " assign";
            expected = C0;
            got = C0;
            eigen_product(GemmOp::add);
            gemm<S>(A, ta, B, tb, got, GemmOp::add, ws);
            EXPECT_TRUE(got == expected) << what << " add";
        }
    }
}

TEST(Gemm, MatchesEigenBitForBitDouble) { expect_same_as_eigen<double>(); }
TEST(Gemm, MatchesEigenBitForBitFloat) { expect_same_as_eigen<float>(); }

// Eigen's product of the armadillo decoder's output layer (10,020 × 50 on 128 columns)
// packs 3.9 MB on the heap; with a kept workspace the second product allocates nothing.
TEST(Gemm, AllocatesNothingOnceGrown)
{
    if (!testing::heap_counting_available()) GTEST_SKIP() << "heap counting needs glibc without AddressSanitizer";
    const MatrixXd A = random_matrix<double>(10020, 50, 1), B = random_matrix<double>(50, 128, 2);
    MatrixXd C(10020, 128), C_eigen(10020, 128);
    {
        testing::HeapCounter counter;
        C_eigen.noalias() = A * B;
        EXPECT_GT(counter.count(), 0) << "Eigen's own product was expected to pack on the heap";
    }
    GemmWorkspace<double> ws;
    MatrixXd D(50, 128);
    gemm<double>(A, false, B, C, GemmOp::assign, ws);  // grow the workspace to both products
    gemm<double>(A, true, C, D, GemmOp::assign, ws);
    testing::HeapCounter counter;
    gemm<double>(A, false, B, C, GemmOp::assign, ws);
    gemm<double>(A, true, C, D, GemmOp::add, ws);
    EXPECT_EQ(counter.count(), 0);
    EXPECT_TRUE(C == C_eigen);
}

TEST(GrowingMatrix, KeepsItsStorageWhenShrinking)
{
    GrowingMatrix<double> g;
    g.resize(7, 10).setConstant(1.0);
    const double* data = g.view().data();
    testing::HeapCounter counter;
    for (Index cols : {9, 10, 3, 10}) {
        auto v = g.resize(7, cols);
        EXPECT_EQ(v.data(), data);
        EXPECT_EQ(v.rows(), 7);
        EXPECT_EQ(v.cols(), cols);
    }
    if (testing::heap_counting_available()) {
        EXPECT_EQ(counter.count(), 0);
    }
    EXPECT_NE(g.resize(7, 11).data(), nullptr);  // grows
}

} // namespace
} // namespace lb::nn
