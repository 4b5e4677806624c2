// Static tip deflection of a tet cantilever under its own weight against
// Euler–Bernoulli, δ = qL⁴/(8EI) with q = ρgA, I = bh³/12. Linear tets lock in
// bending, so the ratio must rise toward 1 under refinement and lie within 10%
// of theory on a fine enough mesh (DESIGN §3: ≈0.79 at 40×4×4, 0.92 at 80×8×8).
#include <gtest/gtest.h>

#include "core/log.hpp"
#include "energy/gravity_energy.hpp"
#include "energy/tet_stvk.hpp"
#include "mesh/generators.hpp"
#include "solver/newton.hpp"

namespace lb {
namespace {

constexpr double kLength = 1.0, kWidth = 0.1;
constexpr double kYoungs = 1e7, kPoisson = 0.3, kDensity = 1000.0, kG = 9.81;

double euler_bernoulli_deflection()
{
    const double q = kDensity * kG * kWidth * kWidth;
    const double I = kWidth * kWidth * kWidth * kWidth / 12.0;
    return q * std::pow(kLength, 4) / (8.0 * kYoungs * I);
}

/// Computed static tip deflection (mean −Δz of the x = L face) on an n×(n/10)×(n/10) mesh.
double computed_deflection(int nx, int nyz)
{
    TetBeamOptions o;
    o.nx = nx;
    o.ny = nyz;
    o.nz = nyz;
    o.size = Vector3d(kLength, kWidth, kWidth);
    const Mesh mesh = make_tet_beam(o);
    const VectorXd masses = lumped_masses(mesh, kDensity, 0.0, 0.0);
    EnergySum energy;
    energy.add(std::make_shared<TetStVK>(mesh.rest_positions, mesh.elements, kYoungs, kPoisson));
    energy.add(std::make_shared<GravityEnergy>(masses, Vector3d(0.0, 0.0, -kG)));

    VectorXi dof_to_unknown(3 * mesh.num_vertices());
    int next = 0;
    for (Index i = 0; i < mesh.num_vertices(); ++i) {
        const bool clamped = mesh.rest_positions(i, 0) < 1e-9;
        for (int c = 0; c < 3; ++c) dof_to_unknown[3 * i + c] = clamped ? -1 : next++;
    }
    NewtonOptions options;
    options.force_scale = masses.sum() * kG;
    options.length_scale = kLength;
    options.gradient_tolerance = 1e-10;
    NewtonSolver newton(dof_to_unknown, energy, options);
    VectorXd x = flatten(mesh.rest_positions);
    const SolveSummary summary = newton.minimize(energy, x);
    EXPECT_TRUE(summary.converged()) << summary.brief();

    double sum = 0.0;
    int count = 0;
    for (Index i = 0; i < mesh.num_vertices(); ++i) {
        if (mesh.rest_positions(i, 0) > kLength - 1e-9) {
            sum += mesh.rest_positions(i, 2) - x[3 * i + 2];
            ++count;
        }
    }
    return sum / count;
}

TEST(Cantilever, ConvergesToEulerBernoulliUnderRefinement)
{
    const double theory = euler_bernoulli_deflection();
    std::vector<double> ratios;
    for (int n : {10, 20, 40, 80}) {
        const double ratio = computed_deflection(n, n / 10) / theory;
        log_info("cantilever %dx%dx%d: tip deflection / Euler-Bernoulli = %.4f (theory %.5f m)", n, n / 10, n / 10,
                 ratio, theory);
        ratios.push_back(ratio);
    }
    for (size_t i = 1; i < ratios.size(); ++i) {
        EXPECT_GT(ratios[i], ratios[i - 1]) << "deflection must rise under refinement";
    }
    EXPECT_NEAR(ratios.back(), 1.0, 0.10) << "80x8x8 must lie within 10% of beam theory";
    EXPECT_LT(ratios.back(), 1.05) << "linear tets are stiffer than the beam, not softer";
}

} // namespace
} // namespace lb
