#include "energy/rod_bending.hpp"

#include <cmath>

#include "core/error.hpp"
#include "energy_checks.hpp"
#include "mesh/generators.hpp"

namespace lb {
namespace {

using testing::check_derivatives_near_rest;
using testing::check_element_hessians;
using testing::check_rigid_invariance_near_rest;
using testing::perturbed_state;
using testing::small_bundle;

constexpr double kYoungs = 1e7;   // Pa
constexpr double kRadius = 1e-3;  // m
constexpr double kSegment = 0.1;  // m


TEST(RodBending, GradientAndHessianMatchFiniteDifferences)
{
    const Mesh mesh = small_bundle();
    const RodBending energy(mesh.rest_positions, rod_bending_stencils(mesh), kYoungs, kRadius);
    ASSERT_EQ(energy.num_elements(), 4 * 4);
    Rng rng(61);
    EXPECT_TRUE(check_derivatives_near_rest(energy, mesh.rest_positions, 0.3 * kSegment, kSegment, rng));
}

TEST(RodBending, InvariantUnderRigidMotion)
{
    const Mesh mesh = small_bundle();
    const RodBending energy(mesh.rest_positions, rod_bending_stencils(mesh), kYoungs, kRadius);
    Rng rng(67);
    EXPECT_TRUE(check_rigid_invariance_near_rest(energy, mesh.rest_positions, 0.2 * kSegment, rng));
}

TEST(RodBending, ElementHessiansSymmetricAndPsdAfterProjection)
{
    const Mesh mesh = small_bundle();
    const RodBending energy(mesh.rest_positions, rod_bending_stencils(mesh), kYoungs, kRadius);
    Rng rng(71);
    Index indefinite = 0;
    EXPECT_TRUE(check_element_hessians(energy, perturbed_state(mesh.rest_positions, 0.4 * kSegment, rng), &indefinite));
    EXPECT_GT(indefinite, 0);
}

TEST(RodBending, CircularArcOfHundredSegmentsStores0990OfContinuumEnergy)
{
    // One straight rod of n = 100 segments, L = 1 m, bent so that its vertices lie on a
    // circle of radius R at arc length k·L/n. Continuum: ½ E·I·L/R². Discrete: n − 1
    // interior vertices each store E·I·(2 tan(Δφ/2))²/(2L/n), Δφ = L/(nR), i.e. the
    // continuum value times (n−1)/n · (tan(Δφ/2)/(Δφ/2))² = 0.990 to O(Δφ²) (DESIGN §3).
    constexpr int kSegments = 100;
    constexpr double kLength = 1.0;
    constexpr double kExpectedRatio = 0.990;
    constexpr double kRatioTolerance = 0.005;
    RodBundleOptions options;
    options.num_rods_x = options.num_rods_y = 1;
    options.vertices_per_rod = kSegments + 1;
    options.length = kLength;
    const Mesh rod = make_rod_bundle(options);
    const RodBending energy(rod.rest_positions, rod_bending_stencils(rod), kYoungs, kRadius);
    const double EI = kYoungs * M_PI * std::pow(kRadius, 4) / 4;
    EXPECT_NEAR(energy.bending_stiffness(), EI, 1e-15 * EI);

    for (double R : {0.5, 1.0, 3.0}) {
        MatrixX3d arc(kSegments + 1, 3);
        for (int k = 0; k <= kSegments; ++k) {
            const double phi = k * kLength / kSegments / R;
            arc.row(k) << R * (1 - std::cos(phi)), 0.0, -R * std::sin(phi);
        }
        const double continuum = 0.5 * EI * kLength / (R * R);
        const double ratio = energy.value(flatten(arc)) / continuum;
        EXPECT_NEAR(ratio, kExpectedRatio, kRatioTolerance) << "R = " << R;
        const double half_angle = 0.5 * kLength / kSegments / R;
        const double exact = double(kSegments - 1) / kSegments * std::pow(std::tan(half_angle) / half_angle, 2);
        EXPECT_NEAR(ratio, exact, 1e-10) << "R = " << R;
    }
}

TEST(RodBending, StraightRodStoresNothingAndCurvedRestIsRejected)
{
    const Mesh mesh = small_bundle();
    const RodBending energy(mesh.rest_positions, rod_bending_stencils(mesh), kYoungs, kRadius);
    EXPECT_NEAR(energy.value(flatten(mesh.rest_positions)), 0.0, 1e-30);
    // Stretching along the rods does not bend them.
    EXPECT_NEAR(energy.value(1.3 * flatten(mesh.rest_positions)), 0.0, 1e-30);

    MatrixX3d bent = mesh.rest_positions;
    bent(2, 0) += 0.05;
    EXPECT_THROW(RodBending(bent, rod_bending_stencils(mesh), kYoungs, kRadius), Error);
}

} // namespace
} // namespace lb
