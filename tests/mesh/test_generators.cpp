#include "mesh/generators.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "core/error.hpp"

namespace lb {
namespace {

double signed_volume(const Mesh& mesh, Index t)
{
    Matrix3d Dm;
    for (int a = 1; a < 4; ++a) {
        Dm.col(a - 1) = (mesh.rest_positions.row(mesh.elements(t, a)) - mesh.rest_positions.row(mesh.elements(t, 0)))
                            .transpose();
    }
    return Dm.determinant() / 6.0;
}

std::string temp_path(const std::string& name)
{
    return std::string(LB_TEST_TMP_DIR) + "/mesh_" + name;
}

void write_file(const std::string& path, const std::string& text)
{
    std::ofstream out(path);
    out << text;
    ASSERT_TRUE(out.good()) << path;
}

// Expect `f` to throw IoError whose message contains every string in `needles`.
template <typename F>
void expect_io_error(F&& f, std::initializer_list<std::string> needles)
{
    try {
        f();
        ADD_FAILURE() << "expected IoError";
    } catch (const IoError& error) {
        for (const auto& needle : needles) {
            EXPECT_NE(std::string(error.what()).find(needle), std::string::npos)
                << "message '" << error.what() << "' lacks '" << needle << "'";
        }
    }
}

// ---- generators -------------------------------------------------------------------

TEST(Generators, RodBundleHangsStraightDownFromAGridOfRoots)
{
    RodBundleOptions options;
    options.num_rods_x = 3;
    options.num_rods_y = 2;
    options.vertices_per_rod = 5;
    options.length = 0.4;
    options.spacing = 0.1;
    options.center = Vector3d(1.0, 2.0, 3.0);
    const Mesh mesh = make_rod_bundle(options);
    EXPECT_EQ(mesh.kind, MeshKind::Rods);
    ASSERT_EQ(mesh.num_vertices(), 30);
    ASSERT_EQ(mesh.elements.rows(), 6 * 4);
    ASSERT_EQ(mesh.rods.size(), 6u);
    Vector3d root_mean = Vector3d::Zero();
    for (const auto& rod : mesh.rods) {
        ASSERT_EQ(rod.size(), 5u);
        const Vector3d root = mesh.rest_positions.row(rod.front()).transpose();
        const Vector3d tip = mesh.rest_positions.row(rod.back()).transpose();
        EXPECT_NEAR(root.z(), 3.0, 1e-15);  // roots in the top plane
        EXPECT_TRUE((tip - (root - Vector3d(0, 0, 0.4))).norm() < 1e-14);  // hanging along −z
        root_mean += root / 6.0;
    }
    EXPECT_TRUE((root_mean - options.center).norm() < 1e-14);
    EXPECT_NEAR((mesh.rest_positions.row(mesh.rods[1][0]) - mesh.rest_positions.row(mesh.rods[0][0])).norm(), 0.1,
                1e-14);
    for (Index e = 0; e < mesh.elements.rows(); ++e) {
        EXPECT_NEAR((mesh.rest_positions.row(mesh.elements(e, 1)) - mesh.rest_positions.row(mesh.elements(e, 0))).norm(),
                    0.1, 1e-14);
    }
    EXPECT_THROW(make_rod_bundle(RodBundleOptions{1, 1, 1, 0.5, 0.1, Vector3d::Zero()}), Error);
}

TEST(Generators, ClothGridIsHorizontalWithUpwardNormalsAndAlternatingDiagonals)
{
    ClothGridOptions options;
    options.nx = 4;
    options.ny = 3;
    options.width = 0.6;
    options.height = 0.4;
    const Mesh mesh = make_cloth_grid(options);
    EXPECT_EQ(mesh.kind, MeshKind::Shell);
    ASSERT_EQ(mesh.num_vertices(), 12);
    ASSERT_EQ(mesh.elements.rows(), 2 * 3 * 2);
    EXPECT_EQ(mesh.rest_positions.col(2).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_TRUE((mesh.rest_positions.row(11) - Eigen::RowVector3d(0.6, 0.4, 0.0)).norm() < 1e-15);
    double area = 0.0;
    for (Index f = 0; f < mesh.elements.rows(); ++f) {
        const Vector3d x0 = mesh.rest_positions.row(mesh.elements(f, 0)).transpose();
        const Vector3d n = (mesh.rest_positions.row(mesh.elements(f, 1)).transpose() - x0)
                               .cross(mesh.rest_positions.row(mesh.elements(f, 2)).transpose() - x0);
        EXPECT_GT(n.z(), 0.0) << "triangle " << f;
        area += 0.5 * n.norm();
    }
    EXPECT_NEAR(area, 0.6 * 0.4, 1e-14);
    // Cell (0,0) uses the diagonal 0–5, its neighbour (1,0) the diagonal 2–5.
    EXPECT_EQ(mesh.elements.row(0), Eigen::RowVector3i(0, 1, 5));
    EXPECT_EQ(mesh.elements.row(2), Eigen::RowVector3i(1, 2, 5));
}

TEST(Generators, TetBeamIsPositivelyOrientedConformingAndFillsTheBox)
{
    TetBeamOptions options;
    options.nx = 4;
    options.ny = 3;
    options.nz = 2;
    options.size = Vector3d(1.0, 0.3, 0.2);
    const Mesh mesh = make_tet_beam(options);
    EXPECT_EQ(mesh.kind, MeshKind::Solid);
    ASSERT_EQ(mesh.num_vertices(), 5 * 4 * 3);
    ASSERT_EQ(mesh.elements.rows(), 6 * 4 * 3 * 2);
    double volume = 0.0;
    for (Index t = 0; t < mesh.elements.rows(); ++t) {
        const double v = signed_volume(mesh, t);
        EXPECT_GT(v, 0.0) << "tet " << t;
        volume += v;
    }
    EXPECT_NEAR(volume, 1.0 * 0.3 * 0.2, 1e-14);

    // Conforming: every triangular face is shared by two tets, except the boundary
    // faces, which are exactly two per boundary quad.
    std::map<std::array<int, 3>, int> faces;
    for (Index t = 0; t < mesh.elements.rows(); ++t) {
        for (int skip = 0; skip < 4; ++skip) {
            std::array<int, 3> face;
            int k = 0;
            for (int a = 0; a < 4; ++a) {
                if (a != skip) face[size_t(k++)] = mesh.elements(t, a);
            }
            std::sort(face.begin(), face.end());
            ++faces[face];
        }
    }
    int boundary = 0;
    for (const auto& [face, count] : faces) {
        EXPECT_LE(count, 2);
        if (count == 1) ++boundary;
    }
    EXPECT_EQ(boundary, 2 * 2 * (4 * 3 + 3 * 2 + 4 * 2));
}

// ---- readers ----------------------------------------------------------------------

TEST(Readers, OffRoundTripWithCommentsColoursAndAQuad)
{
    const std::string path = temp_path("quad.off");
    write_file(path,
               "OFF\n"
               "# a unit square and a triangle\n"
               "5 2 0\n"
               "0 0 0\n"
               "1 0 0 255 0 0\n"
               "1 1 0\n"
               "0 1 0\n"
               "0.5 0.5 1.25  # apex\n"
               "4 0 1 2 3\n"
               "3 0 1 4 10 20 30\n");
    const Mesh mesh = read_off_triangles(path);
    EXPECT_EQ(mesh.kind, MeshKind::Shell);
    ASSERT_EQ(mesh.num_vertices(), 5);
    EXPECT_TRUE((mesh.rest_positions.row(4) - Eigen::RowVector3d(0.5, 0.5, 1.25)).norm() < 1e-15);
    ASSERT_EQ(mesh.elements.rows(), 3);  // quad fan-triangulated into two
    EXPECT_EQ(mesh.elements.row(0), Eigen::RowVector3i(0, 1, 2));
    EXPECT_EQ(mesh.elements.row(1), Eigen::RowVector3i(0, 2, 3));
    EXPECT_EQ(mesh.elements.row(2), Eigen::RowVector3i(0, 1, 4));
    std::remove(path.c_str());
}

TEST(Readers, OffErrorsNameTheFileAndLine)
{
    expect_io_error([] { read_off_triangles(temp_path("does_not_exist.off")); }, {"does_not_exist.off"});

    const std::string bad_number = temp_path("bad_number.off");
    write_file(bad_number, "OFF\n3 1 0\n0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n");
    expect_io_error([&] { read_off_triangles(bad_number); }, {"bad_number.off", ":4:", "zero"});

    const std::string bad_index = temp_path("bad_index.off");
    write_file(bad_index, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
    expect_io_error([&] { read_off_triangles(bad_index); }, {"bad_index.off", ":6:", "vertex 7"});

    const std::string truncated = temp_path("truncated.off");
    write_file(truncated, "OFF\n3 1 0\n0 0 0\n1 0 0\n");
    expect_io_error([&] { read_off_triangles(truncated); }, {"truncated.off", "end of file"});

    const std::string no_header = temp_path("no_header.off");
    write_file(no_header, "PLY\n3 1 0\n");
    expect_io_error([&] { read_off_triangles(no_header); }, {"no_header.off", ":1:", "OFF"});
    for (const auto& p : {bad_number, bad_index, truncated, no_header}) std::remove(p.c_str());
}

TEST(Readers, TetgenRoundTripReorientsNegativeTets)
{
    TetBeamOptions options;
    options.nx = 2;
    options.ny = options.nz = 1;
    options.size = Vector3d(0.2, 0.1, 0.1);
    const Mesh beam = make_tet_beam(options);

    const std::string node_path = temp_path("beam.node");
    const std::string ele_path = temp_path("beam.ele");
    {
        std::ofstream node(node_path);
        node << "# tetgen-style, 1-based\n" << beam.num_vertices() << " 3 0 1\n";
        node.precision(17);
        for (Index v = 0; v < beam.num_vertices(); ++v) {
            node << v + 1 << " " << beam.rest_positions(v, 0) << " " << beam.rest_positions(v, 1) << " "
                 << beam.rest_positions(v, 2) << " 0\n";
        }
        std::ofstream ele(ele_path);
        ele << beam.elements.rows() << " 4 1\n";
        for (Index t = 0; t < beam.elements.rows(); ++t) {
            // Odd tets written with two vertices swapped (negative orientation).
            int a = beam.elements(t, 0), b = beam.elements(t, 1), c = beam.elements(t, 2), d = beam.elements(t, 3);
            if (t % 2 == 1) std::swap(b, c);
            ele << t + 1 << "  " << a + 1 << " " << b + 1 << " " << c + 1 << " " << d + 1 << "  -1\n";
        }
    }
    const Mesh mesh = read_tetgen(node_path, ele_path);
    EXPECT_EQ(mesh.kind, MeshKind::Solid);
    ASSERT_EQ(mesh.num_vertices(), beam.num_vertices());
    ASSERT_EQ(mesh.elements.rows(), beam.elements.rows());
    EXPECT_LT((mesh.rest_positions - beam.rest_positions).cwiseAbs().maxCoeff(), 1e-15);
    for (Index t = 0; t < mesh.elements.rows(); ++t) {
        EXPECT_GT(signed_volume(mesh, t), 0.0) << "tet " << t;
        EXPECT_NEAR(signed_volume(mesh, t), signed_volume(beam, t), 1e-15);
    }
    EXPECT_EQ(mesh.elements.row(0), beam.elements.row(0));
    std::remove(node_path.c_str());
    std::remove(ele_path.c_str());
}

TEST(Readers, TetgenErrorsNameTheFileAndLine)
{
    const std::string node_path = temp_path("err.node");
    write_file(node_path, "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n");
    expect_io_error([&] { read_tetgen(node_path, temp_path("missing.ele")); }, {"missing.ele"});
    expect_io_error([&] { read_tetgen(temp_path("missing.node"), temp_path("missing.ele")); }, {"missing.node"});

    const std::string bad_ele = temp_path("bad.ele");
    write_file(bad_ele, "1 4 0\n0 0 1 2 9\n");
    expect_io_error([&] { read_tetgen(node_path, bad_ele); }, {"bad.ele", ":2:", "node 9"});

    const std::string flat_ele = temp_path("flat.ele");
    write_file(flat_ele, "1 4 0\n0 0 1 2 2\n");
    expect_io_error([&] { read_tetgen(node_path, flat_ele); }, {"flat.ele", ":2:", "degenerate"});

    const std::string bad_node = temp_path("bad.node");
    write_file(bad_node, "2 2 0 0\n0 0 0\n1 1 0\n");
    expect_io_error([&] { read_tetgen(bad_node, flat_ele); }, {"bad.node", ":1:", "dimension"});
    for (const auto& p : {node_path, bad_ele, flat_ele, bad_node}) std::remove(p.c_str());
}

// A header's count is checked against the mesh limits and the file's size before anything
// is allocated: 10^11 points used to end in std::bad_alloc.
TEST(Readers, TetgenAndOffHeaderCountsAreCheckedBeforeAllocating)
{
    const std::string node_path = temp_path("count.node");
    write_file(node_path, "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n");
    const std::string ele_path = temp_path("count.ele");
    write_file(ele_path, "1 4 0\n0 0 1 2 3\n");
    EXPECT_EQ(read_tetgen(node_path, ele_path).elements.rows(), 1);

    const std::string huge_node = temp_path("huge.node");
    write_file(huge_node, "# comment\n100000000000 3 0 0\n0 0 0 0\n");
    expect_io_error([&] { read_tetgen(huge_node, ele_path); }, {"huge.node", ":2:", "100000000000 points", "at most"});
    const std::string huge_ele = temp_path("huge.ele");
    write_file(huge_ele, "99999999999 4 0\n0 0 1 2 3\n");
    expect_io_error([&] { read_tetgen(node_path, huge_ele); }, {"huge.ele", ":1:", "99999999999 tetrahedra"});
    // Within the limits but more records than the file could hold.
    const std::string long_node = temp_path("long.node");
    write_file(long_node, "1000 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n");
    expect_io_error([&] { read_tetgen(long_node, ele_path); }, {"long.node", ":1:", "1000 points", "bytes"});
    const std::string long_ele = temp_path("long.ele");
    write_file(long_ele, "50 4 0\n0 0 1 2 3\n");
    expect_io_error([&] { read_tetgen(node_path, long_ele); }, {"long.ele", ":1:", "50 tetrahedra", "bytes"});
    const std::string huge_off = temp_path("huge.off");
    write_file(huge_off, "OFF\n3 99999999999 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    expect_io_error([&] { read_off_triangles(huge_off); }, {"huge.off", ":2:", "99999999999 faces"});
    const std::string wide_face = temp_path("wide_face.off");
    write_file(wide_face, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n");
    expect_io_error([&] { read_off_triangles(wide_face); }, {"wide_face.off", ":6:", "4000000000 vertices"});
    for (const auto& p : {node_path, ele_path, huge_node, huge_ele, long_node, long_ele, huge_off, wide_face})
        std::remove(p.c_str());
}

} // namespace
} // namespace lb
