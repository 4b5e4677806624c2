// The shared assembly (energy/hessian_assembler.hpp) against the reference
// Energy::hessian on a weighted sum of real energies, with some DOFs prescribed.
#include "energy/hessian_assembler.hpp"

#include "energy/gravity_energy.hpp"
#include "energy/inertia_energy.hpp"
#include "energy/shell_hinge_bending.hpp"
#include "energy/shell_membrane.hpp"
#include "energy_checks.hpp"
#include "mesh/generators.hpp"

namespace lb {
namespace {

TEST(HessianAssembler, MatchesSumOfEnergyHessiansOnUnknowns)
{
    ClothGridOptions options;
    options.nx = 4;
    options.ny = 3;
    options.width = 0.3;
    options.height = 0.2;
    const Mesh mesh = make_cloth_grid(options);
    const VectorXd masses = lumped_masses(mesh, 200.0, 1e-3, 0.0);
    auto inertia = std::make_shared<InertiaEnergy>(masses, 1.0 / 30);
    Rng rng(97);
    inertia->set_x_tilde(testing::perturbed_state(mesh.rest_positions, 0.01, rng));
    EnergySum sum;
    sum.add(inertia);
    sum.add(std::make_shared<ShellMembrane>(mesh.rest_positions, mesh.elements, 1e5, 0.3, 1e-3), 2.0);
    sum.add(std::make_shared<ShellHingeBending>(mesh.rest_positions, shell_hinge_stencils(mesh.elements), 1e5, 0.3,
                                                1e-3),
            0.5);
    sum.add(std::make_shared<GravityEnergy>(masses, GravityEnergy::standard_gravity()));

    // Vertices 0 and 3 prescribed.
    const Index ndof = 3 * mesh.num_vertices();
    VectorXi dof_to_unknown(ndof);
    int next = 0;
    for (Index d = 0; d < ndof; ++d) dof_to_unknown[d] = (d / 3 == 0 || d / 3 == 3) ? -1 : next++;

    HessianAssembler assembler(dof_to_unknown, sum);
    EXPECT_EQ(assembler.num_unknowns(), next);
    const VectorXd x = testing::perturbed_state(mesh.rest_positions, 0.03, rng);
    for (bool project : {false, true}) {
        assembler.assemble(sum, x, project);
        MatrixXd reference = MatrixXd::Zero(ndof, ndof);
        for (const auto& term : sum.terms()) reference += term.weight * MatrixXd(term.energy->hessian(x, project));
        MatrixXd reduced(next, next);
        for (Index i = 0; i < ndof; ++i) {
            for (Index j = 0; j < ndof; ++j) {
                if (dof_to_unknown[i] >= 0 && dof_to_unknown[j] >= 0) {
                    reduced(dof_to_unknown[i], dof_to_unknown[j]) = reference(i, j);
                }
            }
        }
        const MatrixXd lower = reduced.triangularView<Eigen::Lower>();
        const MatrixXd assembled = MatrixXd(assembler.matrix());
        EXPECT_LT((assembled - lower).cwiseAbs().maxCoeff(), 1e-10 * lower.cwiseAbs().maxCoeff())
            << "project_psd = " << project;
        EXPECT_EQ(MatrixXd(assembled.triangularView<Eigen::StrictlyUpper>()).cwiseAbs().maxCoeff(), 0.0);
    }
    const VectorXd g = sum.gradient(x);
    const VectorXd g_free = assembler.restrict(g);
    VectorXd back = VectorXd::Zero(ndof);
    assembler.add_prolonged(g_free, back);
    for (Index d = 0; d < ndof; ++d) EXPECT_EQ(back[d], dof_to_unknown[d] >= 0 ? g[d] : 0.0);
}

} // namespace
} // namespace lb
