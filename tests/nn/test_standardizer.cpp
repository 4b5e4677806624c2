#include <gtest/gtest.h>

#include "nn/standardizer.hpp"

namespace lb::nn {
namespace {

TEST(Standardizer, FitGivesZeroMeanUnitStd)
{
    MatrixXd X(3, 5);
    X << 1, 2, 3, 4, 5,      //
        10, 10, 10, 10, 10,  // constant feature
        -4, 0, 4, 8, 12;
    const Standardizer s = Standardizer::fit(X);
    EXPECT_DOUBLE_EQ(s.mean()[0], 3.0);
    EXPECT_DOUBLE_EQ(s.stddev()[0], std::sqrt(2.0));  // population std
    EXPECT_DOUBLE_EQ(s.stddev()[1], 1.0);             // constant -> 1, passes through centred
    const MatrixXd Xs = s.apply(X);
    EXPECT_LT(Xs.rowwise().mean().cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_NEAR(Xs.row(0).squaredNorm() / 5.0, 1.0, 1e-14);
    EXPECT_NEAR(Xs.row(2).squaredNorm() / 5.0, 1.0, 1e-14);
    EXPECT_EQ(Xs.row(1).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_LT((s.invert(Xs) - X).cwiseAbs().maxCoeff(), 1e-13);
}

TEST(Standardizer, BackwardIsChainRule)
{
    const Standardizer s(VectorXd::Constant(2, 1.0), (VectorXd(2) << 2.0, 0.5).finished());
    const MatrixXd g = s.backward(MatrixXd::Ones(2, 3));
    EXPECT_DOUBLE_EQ(g(0, 1), 0.5);
    EXPECT_DOUBLE_EQ(g(1, 2), 2.0);
    EXPECT_THROW(Standardizer(VectorXd::Zero(2), VectorXd::Zero(2)), std::invalid_argument);
}

} // namespace
} // namespace lb::nn
