#include "energy/dirichlet_penalty.hpp"

#include "core/error.hpp"
#include "energy_checks.hpp"

namespace lb {
namespace {

using testing::check_element_hessians;
using testing::check_energy_gradient;
using testing::check_energy_hessian;

TEST(DirichletPenalty, GradientAndHessianMatchFiniteDifferences)
{
    Rng rng(89);
    DirichletPenalty energy({1, 4, 2}, DirichletPenalty::kDefaultWeight);
    MatrixX3d targets(3, 3);
    targets.setRandom();
    energy.set_targets(targets);
    const VectorXd x = rng.uniform_vector(3 * 6, -1, 1);
    EXPECT_TRUE(check_energy_gradient(energy, x, 1.0));
    EXPECT_TRUE(check_energy_hessian(energy, x, 1.0));
    EXPECT_TRUE(check_element_hessians(energy, x));
}

TEST(DirichletPenalty, IsWeightedSquaredDistanceOfBoundaryVerticesOnly)
{
    const double w = 1e5;
    DirichletPenalty energy({2, 0}, w);
    MatrixX3d targets(2, 3);
    targets << 1, 1, 1, 0, 0, 0;
    energy.set_targets(targets);
    VectorXd x = VectorXd::Zero(9);
    x.segment<3>(6) << 1, 1, 3;  // vertex 2: distance 2 from its target
    x.segment<3>(3) << 7, 7, 7;  // vertex 1 is free: no contribution
    EXPECT_NEAR(energy.value(x), w * 4.0, 1e-9);
    const VectorXd g = energy.gradient(x);
    EXPECT_NEAR(g[8], 2 * w * 2.0, 1e-9);
    EXPECT_EQ(g.segment<3>(3).norm(), 0.0);
    EXPECT_THROW(energy.set_targets(MatrixX3d::Zero(3, 3)), Error);
    EXPECT_THROW(DirichletPenalty({-1}, w), Error);
}

} // namespace
} // namespace lb
