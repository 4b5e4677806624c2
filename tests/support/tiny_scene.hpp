#pragma once
// A minimal valid scene (a 2×1×1-cell tet beam clamped at x = 0, one 10-frame
// sequence with a translation then a rotation) shared by the scene and CLI tests.
namespace lb::testing {

inline constexpr const char* kTinySceneToml = R"(
name = "tiny"
object = "solid"
[mesh]
generator = "tet_beam"
nx = 2
ny = 1
nz = 1
size = [0.2, 0.1, 0.1]
[material]
youngs_modulus = 1e5
density = 1000.0
[[dirichlet.region]]
min = [0.0, 0.0, 0.0]
max = [0.0, 1.0, 1.0]
[[sequences]]
frames = 10
train_frames = 5
segments = [{ frames = 4, velocity = [1.0, 0.0, 0.0] }, { frames = 5, angular_velocity = [0.0, 0.0, 3.0] }]
)";

} // namespace lb::testing
