#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include <filesystem>

#include "core/error.hpp"
#include "io/hdf5.hpp"
#include "sim/dataset.hpp"
#include "support/cli_runner.hpp"

namespace lb {
namespace {

Scene small_scene(const std::string& name)
{
    return load_scene(std::string(LB_SOURCE_DIR) + "/experiments/scenes/" + name + ".toml", {"small"});
}

TEST(Dataset, Hdf5RoundTrip)
{
    const Scene scene = small_scene("cantilever");
    SimulateOptions options;
    options.max_frames = 6;
    options.progress = false;
    const Dataset data = simulate_scene(scene, options);
    const std::string path = testing::fresh_dir("dataset_round_trip") + "/data.h5";
    save_dataset(data, path);
    const Dataset back = load_dataset(path);

    EXPECT_EQ(back.scene_name, "cantilever");
    EXPECT_EQ(back.variant, "small");
    EXPECT_EQ(back.scene_toml, data.scene_toml);
    EXPECT_EQ(back.physics.mesh.kind, MeshKind::Solid);
    EXPECT_EQ(MatrixXd(back.physics.mesh.rest_positions), MatrixXd(data.physics.mesh.rest_positions));
    EXPECT_EQ(back.physics.mesh.elements, data.physics.mesh.elements);
    EXPECT_EQ(back.physics.bc_indices, data.physics.bc_indices);
    EXPECT_EQ(back.physics.dt, data.physics.dt);
    EXPECT_EQ(back.physics.material.youngs_modulus, data.physics.material.youngs_modulus);
    ASSERT_EQ(back.sequences.size(), 1u);
    EXPECT_EQ(back.sequences[0].positions, data.sequences[0].positions);
    EXPECT_EQ(back.sequences[0].bc_positions, data.sequences[0].bc_positions);
    EXPECT_EQ(back.sequences[0].bc_params, data.sequences[0].bc_params);
    EXPECT_EQ(back.sequences[0].newton, data.sequences[0].newton);
    EXPECT_EQ(back.sequences[0].train_frames, std::min(6, scene.sequences[0].train_frames));

    // The documented on-disk shapes.
    const h5::File f = h5::File::open(path);
    const Index N = scene.mesh.num_vertices();
    const auto shape = f.shape("sequences/0/positions");
    ASSERT_EQ(shape.size(), 3u);
    EXPECT_EQ(shape[0], 6u);
    EXPECT_EQ(Index(shape[1]), N);
    EXPECT_EQ(shape[2], 3u);
    EXPECT_EQ(f.shape("sequences/0/newton")[1], 3u);
    EXPECT_EQ(Index(f.shape("masses")[0]), N);
}

TEST(Dataset, RejectsWrongShapes)
{
    const std::string dir = testing::fresh_dir("dataset_bad_shape");
    {
        h5::File f = h5::File::create(dir + "/bad.h5");
        f.write("rest_positions", MatrixXd(MatrixXd::Zero(4, 2)));
        f.write("elements", MatrixXi(MatrixXi::Zero(1, 4)));
        f.write("masses", VectorXd(VectorXd::Ones(4)));
        f.write("bc/indices", VectorXi(VectorXi::Zero(1)));
        f.write("gravity", VectorXd(VectorXd::Zero(3)));
        f.set_attribute("/", "scene", std::string("x"));
        f.set_attribute("/", "scene_toml", std::string(""));
        f.set_attribute("/", "object", std::string("solid"));
        // Every attribute present, so that the shape is the only problem.
        for (const char* key : {"dt", "youngs_modulus", "density"}) f.set_attribute("/", key, 1.0);
        for (const char* key : {"poisson_ratio", "thickness", "radius"}) f.set_attribute("/", key, 0.0);
        f.set_attribute("/", "num_sequences", 0LL);
    }
    try {
        load_dataset(dir + "/bad.h5");
        FAIL() << "expected IoError";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("rest_positions"), std::string::npos) << e.what();
    }
}

} // namespace
} // namespace lb
