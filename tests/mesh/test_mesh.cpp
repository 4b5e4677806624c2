#include "mesh/mesh.hpp"

#include <Eigen/Geometry>
#include <cmath>

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "mesh/generators.hpp"

namespace lb {
namespace {

TEST(Mesh, KindNamesAndBoundingBoxDiagonal)
{
    EXPECT_EQ(to_string(MeshKind::Rods), "rods");
    EXPECT_EQ(to_string(MeshKind::Shell), "shell");
    EXPECT_EQ(to_string(MeshKind::Solid), "solid");
    TetBeamOptions options;
    options.size = Vector3d(1.0, 0.2, 0.1);
    options.origin = Vector3d(-3, 2, 1);
    EXPECT_NEAR(make_tet_beam(options).bounding_box_diagonal(), options.size.norm(), 1e-14);
    EXPECT_EQ(Mesh().bounding_box_diagonal(), 0.0);
}

TEST(Mesh, LumpedMassesSumToDensityTimesMeasure)
{
    const double density = 1000.0;  // kg/m³
    const double thickness = 2e-3;   // m
    const double radius = 1e-3;      // m

    TetBeamOptions beam;
    beam.nx = 4;
    beam.ny = 2;
    beam.nz = 3;
    beam.size = Vector3d(1.0, 0.1, 0.15);
    const VectorXd solid = lumped_masses(make_tet_beam(beam), density, thickness, radius);
    EXPECT_NEAR(solid.sum(), density * 1.0 * 0.1 * 0.15, 1e-12);
    EXPECT_GT(solid.minCoeff(), 0.0);

    ClothGridOptions cloth;
    cloth.nx = 6;
    cloth.ny = 5;
    cloth.width = 0.8;
    cloth.height = 0.6;
    const VectorXd shell = lumped_masses(make_cloth_grid(cloth), density, thickness, radius);
    EXPECT_NEAR(shell.sum(), density * thickness * 0.8 * 0.6, 1e-12);

    RodBundleOptions rods;
    rods.num_rods_x = 3;
    rods.num_rods_y = 2;
    rods.vertices_per_rod = 5;
    rods.length = 0.4;
    const Mesh bundle = make_rod_bundle(rods);
    const VectorXd rod = lumped_masses(bundle, density, thickness, radius);
    EXPECT_NEAR(rod.sum(), density * M_PI * radius * radius * 6 * 0.4, 1e-15);
    // Interior rod vertices carry two half-edges, ends one.
    EXPECT_NEAR(rod[1], 2 * rod[0], 1e-18);
}

TEST(Mesh, LumpedMassesRejectElementsOfTheWrongKind)
{
    Mesh mesh = make_cloth_grid({});
    mesh.kind = MeshKind::Solid;
    EXPECT_THROW(lumped_masses(mesh, 1000, 1e-3, 1e-3), Error);
}

TEST(Mesh, RodBendingStencilsCoverEveryInteriorRodVertex)
{
    RodBundleOptions options;
    options.num_rods_x = 3;
    options.num_rods_y = 2;
    options.vertices_per_rod = 7;
    const Mesh mesh = make_rod_bundle(options);
    const MatrixXi stencils = rod_bending_stencils(mesh);
    ASSERT_EQ(stencils.rows(), 6 * (7 - 2));
    for (Index s = 0; s < stencils.rows(); ++s) {
        EXPECT_EQ(stencils(s, 1), stencils(s, 0) + 1);  // rods are contiguous chains
        EXPECT_EQ(stencils(s, 2), stencils(s, 1) + 1);
    }
    EXPECT_EQ(stencils.row(0), Eigen::RowVector3i(0, 1, 2));
    EXPECT_EQ(stencils.row(5), Eigen::RowVector3i(7, 8, 9));  // second rod starts at vertex 7
}

TEST(Mesh, HingeStencilCountEqualsInteriorEdgeCountOnGrid)
{
    for (const auto& [nx, ny] : {std::pair{2, 2}, std::pair{5, 4}, std::pair{16, 12}}) {
        ClothGridOptions options;
        options.nx = nx;
        options.ny = ny;
        const Mesh mesh = make_cloth_grid(options);
        const MatrixXi hinges = shell_hinge_stencils(mesh.elements);
        // Edges: horizontal + vertical + one diagonal per cell; boundary edges: the perimeter.
        const int edges = (nx - 1) * ny + nx * (ny - 1) + (nx - 1) * (ny - 1);
        const int boundary = 2 * (nx - 1) + 2 * (ny - 1);
        EXPECT_EQ(hinges.rows(), edges - boundary) << nx << "x" << ny;

        // Convention: (v0, v1, v2) is a triangle of the mesh in its own orientation, and
        // (v1, v0, v3) is the other one.
        auto has_oriented_triangle = [&](int a, int b, int c) {
            for (Index f = 0; f < mesh.elements.rows(); ++f) {
                for (int k = 0; k < 3; ++k) {
                    if (mesh.elements(f, k) == a && mesh.elements(f, (k + 1) % 3) == b &&
                        mesh.elements(f, (k + 2) % 3) == c) {
                        return true;
                    }
                }
            }
            return false;
        };
        for (Index h = 0; h < hinges.rows(); ++h) {
            EXPECT_TRUE(has_oriented_triangle(hinges(h, 0), hinges(h, 1), hinges(h, 2))) << "hinge " << h;
            EXPECT_TRUE(has_oriented_triangle(hinges(h, 1), hinges(h, 0), hinges(h, 3))) << "hinge " << h;
        }
    }
}

TEST(Mesh, HingeStencilsRejectInconsistentOrientation)
{
    MatrixXi triangles(2, 3);
    triangles << 0, 1, 2, 0, 1, 3;  // both contain the directed edge 0→1
    EXPECT_THROW(shell_hinge_stencils(triangles), Error);
}

} // namespace
} // namespace lb
