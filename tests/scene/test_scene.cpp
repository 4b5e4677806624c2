#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include <filesystem>

#include "core/error.hpp"
#include "scene/scene.hpp"
#include "support/tiny_scene.hpp"

namespace lb {
namespace {

const char* const kMinimal = testing::kTinySceneToml;

Scene load(const std::string& text) { return load_scene_from_string(text, "test.toml", "."); }

std::string error_of(const std::string& text)
{
    try {
        load(text);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

TEST(Scene, LoadsMinimalScene)
{
    const Scene scene = load(kMinimal);
    EXPECT_EQ(scene.name, "tiny");
    EXPECT_EQ(scene.kind(), MeshKind::Solid);
    EXPECT_EQ(scene.mesh.num_vertices(), 3 * 2 * 2);
    EXPECT_EQ(scene.bc_indices.size(), 4u);  // the x = 0 face
    ASSERT_EQ(scene.sequences.size(), 1u);
    EXPECT_EQ(scene.sequences[0].frames, 10);
    EXPECT_EQ(scene.sequences[0].train_frames, 5);
    EXPECT_NEAR(scene.dt, 1.0 / 30.0, 1e-15);
}

TEST(Scene, TrajectoryIntegratesPiecewiseRigidMotion)
{
    const Scene scene = load(kMinimal);
    const BoundaryTrajectory traj = scene.trajectory(scene.sequences[0]);
    ASSERT_EQ(traj.targets.size(), 10u);
    ASSERT_EQ(traj.params.rows(), 10);
    ASSERT_EQ(traj.params.cols(), Scene::kNumBcParams);
    // Frame 0 is the rest pose; 4 steps at 1 m/s translate by 4·dt along x.
    const MatrixX3d rest = traj.targets[0];
    EXPECT_NEAR((traj.targets[4] - rest).col(0).mean(), 4.0 * scene.dt, 1e-12);
    EXPECT_NEAR(traj.params(1, 0), 1.0, 0.0);
    EXPECT_NEAR(traj.params(5, 5), 3.0, 0.0);
    // Rotation keeps pairwise distances of the Dirichlet set.
    const double d0 = (rest.row(0) - rest.row(3)).norm();
    const double d9 = (traj.targets[9].row(0) - traj.targets[9].row(3)).norm();
    EXPECT_NEAR(d0, d9, 1e-12);
    EXPECT_GT((traj.targets[9] - traj.targets[4]).norm(), 1e-3);
}

TEST(Scene, FlipEveryReversesVelocity)
{
    std::string text = kMinimal;
    text.replace(text.find("segments"), std::string::npos,
                 "segments = [{ frames = 9, velocity = [1.0, 0.0, 0.0], flip_every = 2 }]\n");
    const Scene scene = load(text);
    const BoundaryTrajectory traj = scene.trajectory(scene.sequences[0]);
    EXPECT_EQ(traj.params(1, 0), 1.0);
    EXPECT_EQ(traj.params(2, 0), 1.0);
    EXPECT_EQ(traj.params(3, 0), -1.0);
    EXPECT_EQ(traj.params(5, 0), 1.0);
}

TEST(Scene, RejectsUnknownKeyByName)
{
    std::string text = kMinimal;
    text.replace(text.find("density"), 7, "densty");
    const std::string msg = error_of(text);
    EXPECT_NE(msg.find("material.densty"), std::string::npos) << msg;
}

TEST(Scene, RejectsMalformedToml)
{
    const std::string msg = error_of("name = \"x\"\n[mesh\n");
    EXPECT_NE(msg.find("malformed TOML"), std::string::npos) << msg;
    EXPECT_NE(msg.find("test.toml:2"), std::string::npos) << msg;
}

TEST(Scene, RejectsNaNValue)
{
    std::string text = kMinimal;
    text.replace(text.find("1e5"), 3, "nan");
    const std::string msg = error_of(text);
    EXPECT_NE(msg.find("material.youngs_modulus"), std::string::npos) << msg;
    EXPECT_NE(msg.find("finite"), std::string::npos) << msg;
}

TEST(Scene, RejectsMissingMeshFile)
{
    std::string text = kMinimal;
    const auto begin = text.find("generator");
    const auto end = text.find("[material]");
    text.replace(begin, end - begin, "generator = \"tetgen\"\nnode = \"nowhere/x.node\"\nele = \"nowhere/x.ele\"\n");
    const std::string msg = error_of(text);
    EXPECT_NE(msg.find("nowhere/x.node"), std::string::npos) << msg;
}

TEST(Scene, RejectsEmptyDirichletSelection)
{
    std::string text = kMinimal;
    // A box at the centre of the 2×1×1 beam's cross-section contains no vertex.
    text.replace(text.find("min = [0.0, 0.0, 0.0]"), 21, "min = [0.5, 0.5, 0.5]");
    text.replace(text.find("max = [0.0, 1.0, 1.0]"), 21, "max = [0.5, 0.5, 0.5]");
    const std::string msg = error_of(text);
    EXPECT_NE(msg.find("Dirichlet selection is empty"), std::string::npos) << msg;
}

TEST(Scene, UnknownVariantListsAvailable)
{
    try {
        load_scene_from_string(std::string(kMinimal) + "[variants.small]\nmesh = { nx = 1 }\n", "t.toml", ".",
                               {"huge"});
        FAIL() << "expected ConfigError";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("small"), std::string::npos) << e.what();
    }
}

TEST(Scene, EveryCatalogueSceneHasAValidSmallVariant)
{
    const std::filesystem::path dir = std::filesystem::path(LB_SOURCE_DIR) / "experiments/scenes";
    int count = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
        if (entry.path().extension() != ".toml") continue;
        const Scene scene = load_scene(entry.path().string(), {"small"});
        EXPECT_LE(scene.mesh.num_vertices(), 400) << entry.path();
        EXPECT_GE(scene.mesh.num_vertices(), 10) << entry.path();
        EXPECT_FALSE(scene.bc_indices.empty()) << entry.path();
        EXPECT_NE(scene.resolved_toml.find("name"), std::string::npos);
        ++count;
    }
    EXPECT_EQ(count, 7);  // the six scenes and rods_translate_paper (the translating rods with the paper's test)
}

} // namespace
} // namespace lb
