// LatentPotential: E(D(z)) and its latent gradient J_Dᵀ∇E against central finite
// differences (cloth and solid with the Dirichlet penalty, rods with hard roots); the
// batched evaluation against the single-sample one and against a direct computation
// (decode, IncrementalPotential, decoder VJP); weights, normalisation, the boundary
// policy, and the errors.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <ostream>

#include "core/error.hpp"
#include "energy/inertia_energy.hpp"
#include "latent/latent_potential.hpp"
#include "latent/latent_test_support.hpp"
#include "support/finite_difference.hpp"

namespace lb {
namespace {

using latent_test::random_matrix;
using latent_test::targets_of;

constexpr double kPenaltyWeight = 1e5;  ///< the configured w_bc (the integrator default)

/// Relative closeness |a − b| ≤ tol · max(|a|, |b|, 1) of two matrices, entrywise.
::testing::AssertionResult close(const MatrixXd& a, const MatrixXd& b, double tol, const std::string& what)
{
    lb::testing::FdOptions o;
    o.tol = tol;
    return lb::testing::matrices_close(a, b, o, what);
}

/// A physics model, a tiny PCA-initialised autoencoder over random frames near rest,
/// and B steps: latents, Dirichlet targets, x_{t−1} and x_{t−2} near rest.
struct Problem {
    PhysicsSpec spec;
    std::unique_ptr<PhysicsModel> model;
    std::unique_ptr<Autoencoder> ae;
    MatrixXd Z, T, X_prev, X_prev2;

    Problem(const PhysicsSpec& physics, Index B, std::uint64_t seed) : spec(physics)
    {
        model = std::make_unique<PhysicsModel>(spec);
        AutoencoderOptions o;
        o.latent_dim = 3;
        o.hidden = {8, 8};
        o.pca_dim = 6;
        o.progress = false;
        ae = std::make_unique<Autoencoder>(spec, o, seed);
        Rng rng(seed + 100);
        const VectorXd rest = flatten(spec.mesh.rest_positions);
        const MatrixXd frames = random_matrix(rest.size(), 20, rng, -0.01, 0.01).colwise() + rest;
        ae->initialize_pca(ae->encoding().to_features(frames));
        Z = random_matrix(3, B, rng, -0.5, 0.5);
        X_prev = random_matrix(rest.size(), B, rng, -0.01, 0.01).colwise() + rest;
        X_prev2 = random_matrix(rest.size(), B, rng, -0.01, 0.01).colwise() + rest;
        // Targets near (not on) the previous positions' Dirichlet vertices, so the penalty acts.
        T = targets_of(X_prev, spec.bc_indices) + random_matrix(3 * Index(spec.bc_indices.size()), B, rng, -0.01, 0.01);
    }
};

struct Case {
    const char* name;
    PhysicsSpec (*physics)();
    bool penalty;  ///< the boundary policy applies w_bc (cloth, solids), not rods
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

class LatentPotentialPhysics : public ::testing::TestWithParam<Case> { };

TEST_P(LatentPotentialPhysics, BoundaryPolicyGivesThePenaltyWeight)
{
    Problem p(GetParam().physics(), 1, 1);
    const double expected = GetParam().penalty ? kPenaltyWeight : 0.0;
    EXPECT_EQ(applied_penalty_weight(*p.model, kPenaltyWeight), expected);
    LatentPotential potential(*p.model, *p.ae, kPenaltyWeight);
    EXPECT_EQ(potential.penalty_weight(), expected);
}

/// grad_z = J_D(z)ᵀ ∇_x E(D(z)) against central differences of E(D(z)), every sample of p.
void expect_gradient_matches_finite_differences(const Problem& p, LatentPotential& potential, const std::string& what)
{
    for (Index s = 0; s < p.Z.cols(); ++s) {
        const VectorXd t = p.T.col(s), x1 = p.X_prev.col(s), x2 = p.X_prev2.col(s);
        VectorXd grad;
        potential.value_and_gradient(p.Z.col(s), t, x1, x2, grad);
        ASSERT_EQ(grad.size(), 3);
        EXPECT_GT(grad.cwiseAbs().maxCoeff(), 0.0);
        lb::testing::FdOptions fd;
        fd.step = 1e-6;
        fd.tol = 1e-5;
        fd.scale = 1e-6 * grad.cwiseAbs().maxCoeff();
        EXPECT_TRUE(lb::testing::check_gradient([&](const VectorXd& z) { return potential.value(z, t, x1, x2); },
                                                [&](const VectorXd&) { return grad; }, p.Z.col(s), fd,
                                                what + " sample " + std::to_string(s)));
    }
}

TEST_P(LatentPotentialPhysics, GradientMatchesFiniteDifferences)
{
    Problem p(GetParam().physics(), 3, 2);
    LatentPotential potential(*p.model, *p.ae, kPenaltyWeight);
    expect_gradient_matches_finite_differences(p, potential, GetParam().name);
}

// overwrite_dirichlet (issue 14): the decoded Dirichlet rows are the targets exactly (in
// evaluate() and decode()), everything else is the plain decode bit for bit, the penalty is
// 0, no gradient flows from the Dirichlet rows, and grad_z is still E's derivative.
TEST_P(LatentPotentialPhysics, OverwrittenDirichletRowsAreTheTargetsAndTheGradientHolds)
{
    const Index B = 3;
    Problem p(GetParam().physics(), B, 7);
    LatentPotential overwriting(*p.model, *p.ae, kPenaltyWeight, true);
    EXPECT_TRUE(overwriting.overwrites_dirichlet());
    expect_gradient_matches_finite_differences(p, overwriting, std::string(GetParam().name) + " overwritten");

    LatentEnergyOptions options;
    options.gradient = true;
    options.decoded = true;
    const LatentEnergies e = overwriting.evaluate(p.Z, p.T, p.X_prev, p.X_prev2, options);
    MatrixXd expected = p.ae->decode(p.Z, p.T);
    const auto& bc = p.model->bc_indices();
    for (Index i = 0; i < B; ++i) {
        for (size_t b = 0; b < bc.size(); ++b)
            expected.col(i).segment<3>(3 * Index(bc[b])) = p.T.col(i).segment<3>(3 * Index(b));
    }
    EXPECT_EQ(e.X, expected);
    EXPECT_EQ(overwriting.decode(p.Z, p.T), expected);
    if (GetParam().penalty) {
        EXPECT_NE(p.ae->decode(p.Z, p.T), expected) << "the test needs decoded rows off target";
    }
    for (int v : bc) EXPECT_EQ(e.grad_x.middleRows<3>(3 * Index(v)).cwiseAbs().maxCoeff(), 0.0) << "vertex " << v;

    // The energies are those of the overwritten positions, where the penalty vanishes.
    IncrementalPotential no_penalty(*p.model, 0.0);
    for (Index i = 0; i < B; ++i) {
        no_penalty.set_previous(p.X_prev.col(i), p.X_prev2.col(i));
        EXPECT_NEAR(e.energies[i], no_penalty.value(expected.col(i)), 1e-12 * std::abs(e.energies[i]));
    }

    // Off (the default): the plain decode, bit for bit.
    LatentPotential plain(*p.model, *p.ae, kPenaltyWeight);
    LatentPotential off(*p.model, *p.ae, kPenaltyWeight, false);
    const LatentEnergies a = plain.evaluate(p.Z, p.T, p.X_prev, p.X_prev2, options);
    const LatentEnergies b = off.evaluate(p.Z, p.T, p.X_prev, p.X_prev2, options);
    EXPECT_EQ(a.X, p.ae->decode(p.Z, p.T));
    EXPECT_EQ(a.X, b.X);
    EXPECT_EQ(a.energies, b.energies);
    EXPECT_EQ(a.grad_z, b.grad_z);
}

// The batch: its energies are those of decode + IncrementalPotential, its gradient the
// decoder VJP of the weighted x-gradients, and both agree with the single-sample calls.
TEST_P(LatentPotentialPhysics, BatchAgreesWithSingleSamplesAndTheDirectComputation)
{
    const Index B = 4;
    Problem p(GetParam().physics(), B, 3);
    LatentPotential potential(*p.model, *p.ae, kPenaltyWeight);
    LatentEnergyOptions options;
    options.gradient = true;
    options.decoded = true;
    options.weights = (VectorXd(B) << 0.5, 2.0, 1.0, 3.0).finished();
    options.normalization = 7.0;
    const LatentEnergies e = potential.evaluate(p.Z, p.T, p.X_prev, p.X_prev2, options);
    ASSERT_EQ(e.energies.size(), B);
    ASSERT_EQ(e.grad_z.rows(), 3);
    ASSERT_EQ(e.grad_z.cols(), B);

    // Direct: decode, one IncrementalPotential with the policy's weight, one VJP.
    const MatrixXd X = p.ae->decode(p.Z, p.T);
    EXPECT_EQ(e.X, X);
    IncrementalPotential direct(*p.model, GetParam().penalty ? kPenaltyWeight : 0.0);
    EXPECT_EQ(direct.has_penalty(), GetParam().penalty);
    VectorXd energies(B);
    MatrixXd grad_x(X.rows(), B);
    for (Index i = 0; i < B; ++i) {
        direct.set_previous(p.X_prev.col(i), p.X_prev2.col(i));
        direct.set_bc_targets(as_rows(VectorXd(p.T.col(i))));
        energies[i] = direct.value(X.col(i));
        grad_x.col(i) = direct.gradient(X.col(i)) * options.weights[i] / options.normalization;
    }
    EXPECT_TRUE(close(e.energies, energies, 1e-12, "energies vs direct"));
    EXPECT_NEAR(e.objective, options.weights.dot(energies) / options.normalization,
                1e-12 * std::abs(e.objective));
    EXPECT_TRUE(close(e.grad_z, p.ae->decoder_vjp(p.Z, grad_x, p.T), 1e-12, "grad_z vs direct"));

    // Single samples: the same energies; the batch gradient is (w_i / n) × theirs.
    for (Index i = 0; i < B; ++i) {
        VectorXd grad;
        const double value = potential.value_and_gradient(p.Z.col(i), p.T.col(i), p.X_prev.col(i),
                                                          p.X_prev2.col(i), grad);
        EXPECT_NEAR(value, e.energies[i], 1e-10 * std::abs(value));
        // value() sums the elements one by one, the gradient pass eight at a time
        // (energy/element_lanes.hpp): equal to round-off, not bitwise.
        EXPECT_NEAR(potential.value(p.Z.col(i), p.T.col(i), p.X_prev.col(i), p.X_prev2.col(i)), value,
                    1e-12 * std::abs(value));
        EXPECT_TRUE(close(e.grad_z.col(i), grad * options.weights[i] / options.normalization, 1e-10,
                          "batch vs single gradient, sample " + std::to_string(i)));
    }
}

// Whole groups of Energy::kColumnLanes columns take the column pass (the elastic terms
// vectorised over the samples), the rest go one at a time: the same energies and weighted
// x-gradients bit for bit as each column on its own.
TEST_P(LatentPotentialPhysics, ColumnPassEqualsOneColumnAtATimeBitForBit)
{
    const Index B = 2 * Energy::kColumnLanes + 3;
    Problem p(GetParam().physics(), B, 5);
    LatentPotential potential(*p.model, *p.ae, kPenaltyWeight);
    const MatrixXd X = p.ae->decode(p.Z, p.T);
    LatentEnergyOptions options;
    options.gradient = true;
    Rng rng(9);
    options.weights = rng.uniform_vector(B, 0.5, 2.0);
    options.normalization = 3.0;
    const LatentEnergies batch = potential.evaluate_positions(X, p.T, p.X_prev, p.X_prev2, options);
    for (Index i = 0; i < B; ++i) {
        LatentEnergyOptions one;
        one.gradient = true;
        one.weights = VectorXd::Constant(1, options.weights[i]);
        one.normalization = options.normalization;
        const LatentEnergies single =
            potential.evaluate_positions(X.col(i), p.T.col(i), p.X_prev.col(i), p.X_prev2.col(i), one);
        EXPECT_EQ(batch.energies[i], single.energies[0]) << "sample " << i;
        EXPECT_TRUE(batch.grad_x.col(i) == single.grad_x.col(0)) << "sample " << i;
    }
    EXPECT_GT(batch.grad_x.norm(), 0.0);
}

// The trainer hands the potential x̃ (cached per sample) instead of x_{t−1}, x_{t−2}: the same
// numbers, bit for bit, as evaluate() and as an IncrementalPotential given the two states.
TEST_P(LatentPotentialPhysics, EvaluateTildeEqualsEvaluateAndTheStepsPotentialBitForBit)
{
    const Index B = Energy::kColumnLanes + 3;
    Problem p(GetParam().physics(), B, 13);
    LatentEnergyOptions options;
    options.gradient = true;
    options.decoded = true;
    LatentPotential potential(*p.model, *p.ae, kPenaltyWeight);
    const LatentEnergies e = potential.evaluate(p.Z, p.T, p.X_prev, p.X_prev2, options);
    const LatentEnergies t = potential.evaluate_tilde(p.Z, p.T, inertial_target(p.X_prev, p.X_prev2), options);
    EXPECT_TRUE(t.energies == e.energies);
    EXPECT_TRUE(t.grad_z == e.grad_z);
    EXPECT_GT(e.grad_z.norm(), 0.0);
    IncrementalPotential step(*p.model, applied_penalty_weight(*p.model, kPenaltyWeight));
    VectorXd g;
    for (Index i = 0; i < B; ++i) {
        step.set_previous(p.X_prev.col(i), p.X_prev2.col(i));
        step.set_bc_targets(Eigen::Map<const MatrixX3d>(p.T.col(i).data(), p.T.rows() / 3, 3));
        EXPECT_EQ(t.energies[i], step.value_gradient(t.X.col(i), g)) << "sample " << i;  // the gradient pass's sums
    }
    // Wrong shapes name what was given.
    EXPECT_THROW(potential.evaluate_tilde(p.Z, p.T, p.X_prev.leftCols(B - 1), options), Error);
    EXPECT_THROW(potential.evaluate(p.Z, p.T, p.X_prev, p.X_prev2.topRows(3), options), Error);
}

// The frozen decoder (the integrator trainers' path): the compiled double copy equals the
// live decoder to round-off; the float32 copy (issue 14) to single-precision round-off, and
// it really is single precision (not bit-identical to double).
TEST_P(LatentPotentialPhysics, FrozenDecoderMatchesTheLiveOneInDoubleAndToFloatRoundOffInFloat)
{
    const Index B = 5;
    Problem p(GetParam().physics(), B, 9);
    LatentEnergyOptions options;
    options.gradient = true;
    options.decoded = true;
    LatentPotential live(*p.model, *p.ae, kPenaltyWeight);
    const LatentEnergies e = live.evaluate(p.Z, p.T, p.X_prev, p.X_prev2, options);
    LatentPotential frozen(*p.model, *p.ae, kPenaltyWeight);
    frozen.freeze_decoder();
    EXPECT_TRUE(frozen.decoder_frozen());
    EXPECT_FALSE(frozen.decoder_float32());
    const LatentEnergies d = frozen.evaluate(p.Z, p.T, p.X_prev, p.X_prev2, options);
    EXPECT_TRUE(close(d.energies, e.energies, 1e-10, "double copy: energies"));
    EXPECT_TRUE(close(d.grad_z, e.grad_z, 1e-9, "double copy: grad_z"));
    LatentPotential single(*p.model, *p.ae, kPenaltyWeight);
    single.freeze_decoder(true);
    EXPECT_TRUE(single.decoder_float32());
    const LatentEnergies f = single.evaluate(p.Z, p.T, p.X_prev, p.X_prev2, options);
    const double scale = e.X.cwiseAbs().maxCoeff();
    const double position_error = (f.X - e.X).cwiseAbs().maxCoeff();
    EXPECT_GT(position_error, 0.0) << "the float32 copy gave double results";
    EXPECT_LT(position_error, 1e-5 * scale);
    EXPECT_TRUE(close(f.energies, e.energies, 1e-3, "float copy: energies"));
    EXPECT_TRUE(close(f.grad_z, e.grad_z, 1e-2, "float copy: grad_z"));
    EXPECT_TRUE(close(single.decode(p.Z, p.T), f.X, 0.0, "float copy: decode = evaluate's positions"));
}

// Without weights every w_i = 1; without the flags no gradient and no positions.
TEST_P(LatentPotentialPhysics, DefaultsAreUnitWeightsAndNoGradient)
{
    const Index B = 3;
    Problem p(GetParam().physics(), B, 4);
    LatentPotential potential(*p.model, *p.ae, kPenaltyWeight);
    LatentEnergyOptions options;
    options.normalization = double(B);
    const LatentEnergies e = potential.evaluate(p.Z, p.T, p.X_prev, p.X_prev2, options);
    EXPECT_EQ(e.grad_z.size(), 0);
    EXPECT_EQ(e.X.size(), 0);
    EXPECT_NEAR(e.objective, e.energies.mean(), 1e-12 * std::abs(e.objective));

    options.gradient = true;
    const LatentEnergies unit = potential.evaluate(p.Z, p.T, p.X_prev, p.X_prev2, options);
    options.weights = VectorXd::Ones(B);
    const LatentEnergies ones = potential.evaluate(p.Z, p.T, p.X_prev, p.X_prev2, options);
    EXPECT_TRUE(close(unit.energies, e.energies, 1e-12, "energies with and without the gradient"));
    EXPECT_EQ(unit.grad_z, ones.grad_z);
    EXPECT_EQ(unit.objective, ones.objective);
}

INSTANTIATE_TEST_SUITE_P(Physics, LatentPotentialPhysics,
                         ::testing::Values(Case{"cloth", latent_test::cloth_physics, true},
                                           Case{"solid", latent_test::solid_physics, true},
                                           Case{"rods", latent_test::rod_physics, false}),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(LatentPotential, NonFiniteEnergyThrowsNamingTheColumnAndIsReturnedForOneSample)
{
    Problem p(latent_test::cloth_physics(), 2, 5);
    LatentPotential potential(*p.model, *p.ae, kPenaltyWeight);
    p.X_prev(0, 1) = std::numeric_limits<double>::quiet_NaN();
    try {
        potential.evaluate(p.Z, p.T, p.X_prev, p.X_prev2, {});
        ADD_FAILURE() << "no NumericalError";
    } catch (const NonFinitePotential& e) {  // a NumericalError naming the column, for the caller to map
        EXPECT_EQ(e.column, 1);
        EXPECT_FALSE(std::isfinite(e.value));
        EXPECT_NE(std::string(e.what()).find("in column 1 of the training batch"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::isfinite(potential.value(p.Z.col(1), p.T.col(1), p.X_prev.col(1), p.X_prev2.col(1))));
    EXPECT_TRUE(std::isfinite(potential.value(p.Z.col(0), p.T.col(0), p.X_prev.col(0), p.X_prev2.col(0))));
}

TEST(LatentPotential, WrongShapesThrow)
{
    Problem p(latent_test::cloth_physics(), 2, 6);
    LatentPotential potential(*p.model, *p.ae, kPenaltyWeight);
    LatentEnergyOptions options;
    options.weights = VectorXd::Ones(3);
    EXPECT_THROW(potential.evaluate(p.Z, p.T, p.X_prev, p.X_prev2, options), Error);
    EXPECT_THROW(potential.evaluate(p.Z, p.T.leftCols(1), p.X_prev, p.X_prev2), Error);
    EXPECT_THROW(potential.evaluate(p.Z.topRows(2), p.T, p.X_prev, p.X_prev2), Error);
    EXPECT_THROW(potential.evaluate(p.Z, p.T, p.X_prev.topRows(3), p.X_prev2), Error);
}

} // namespace
} // namespace lb
