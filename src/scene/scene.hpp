#pragma once
// A scene: mesh + material + Dirichlet set + boundary trajectories, read from
// a TOML file (schema in README.md, "Scene files"). Variants ([variants.<name>])
// are deep-merged over the base table before validation; the resolved TOML is
// kept so every output can embed exactly what produced it.
#include <string>
#include <vector>

#include "mesh/mesh.hpp"
#include "solver/newton.hpp"

namespace lb {

struct Material {
    double youngs_modulus = 1e6;  ///< E (Pa)
    double poisson_ratio = 0.3;   ///< ν
    double density = 1000.0;      ///< ρ (kg/m³)
    double thickness = 0.0;       ///< shells (m)
    double radius = 0.0;          ///< rods (m)
};

/// Piecewise-constant rigid motion of the Dirichlet set over `frames` steps.
struct MotionSegment {
    int frames = 0;
    Vector3d velocity = Vector3d::Zero();          ///< m/s
    Vector3d angular_velocity = Vector3d::Zero();  ///< rad/s about the scene's rotation centre
    /// If > 0, the velocity's sign flips every `flip_every` frames (rods_translate).
    int flip_every = 0;
};

struct SequenceSpec {
    std::string name;
    int frames = 0;        ///< number of frames stored, frame 0 = rest
    int train_frames = 0;  ///< frames [0, train_frames) are training data, the rest test
    std::vector<MotionSegment> segments;
};

/// The boundary state at each frame of a sequence: targets of the Dirichlet
/// vertices and the parameters p_t an integrator is given.
struct BoundaryTrajectory {
    /// frames × B × 3, row-major per frame: targets[t] is B×3.
    std::vector<MatrixX3d> targets;
    /// frames × P: p_t = (velocity, angular velocity) applied during step t (0 at frame 0).
    MatrixXd params;
};

struct Scene {
    std::string name;
    std::string description;
    std::string variant;       ///< "" for the full-size scene
    std::string resolved_toml; ///< the merged, validated configuration text
    std::string source;        ///< the file it was read from (for messages)
    Mesh mesh;
    Material material;
    double dt = 1.0 / 30.0;
    Vector3d gravity{0.0, 0.0, -9.81};
    std::vector<int> bc_indices;  ///< Dirichlet vertices (rods: the roots)
    Vector3d rotation_center = Vector3d::Zero();
    std::vector<SequenceSpec> sequences;
    NewtonOptions newton;  ///< tolerances; scales are set by the simulator

    MeshKind kind() const { return mesh.kind; }
    /// Number of boundary parameters per frame (P).
    static constexpr int kNumBcParams = 6;

    BoundaryTrajectory trajectory(const SequenceSpec& sequence) const;
};

struct SceneLoadOptions {
    std::string variant;  ///< "" or the name of a [variants.<name>] table
};

/// Load and validate a scene file. Throws ConfigError (naming the key) on bad
/// input, IoError for a missing mesh file.
Scene load_scene(const std::string& path, const SceneLoadOptions& options = {});
/// Same from TOML text; `source` names it in messages, `base_dir` resolves relative mesh paths.
Scene load_scene_from_string(const std::string& text, const std::string& source,
                             const std::string& base_dir, const SceneLoadOptions& options = {});

} // namespace lb
