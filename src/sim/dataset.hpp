#pragma once
// Ground-truth datasets: full-space simulations of every sequence of a scene,
// stored in HDF5 (layout in README.md, "Datasets"):
//   rest_positions N×3, elements M×K, masses N, bc/indices B, rods R×V (rods only)
//   sequences/<k>/positions T×N×3, bc_positions T×B×3, bc_params T×P, newton T×3
//     (iterations, residual, seconds)
//   attributes: dt, scene, variant, object, scene_toml, material and gravity,
//   per sequence name and train_frames.
#include <string>
#include <vector>

#include "sim/physics_model.hpp"

namespace lb {

struct SequenceData {
    std::string name;
    int train_frames = 0;
    MatrixXd positions;     ///< T × 3N (row t = x_t)
    MatrixXd bc_positions;  ///< T × 3B
    MatrixXd bc_params;     ///< T × P
    MatrixXd newton;        ///< T × 3: iterations, residual, seconds (row 0: zeros)
    Index num_frames() const { return positions.rows(); }
    MatrixX3d bc_targets(Index t) const;
};

struct Dataset {
    std::string scene_name;
    std::string variant;
    std::string scene_toml;
    PhysicsSpec physics;
    std::vector<SequenceData> sequences;
};

struct SimulateOptions {
    bool progress = true;
    /// Stop with NumericalError if a step does not converge (default) instead of
    /// recording it and continuing.
    bool fail_on_nonconvergence = true;
    /// Simulate at most this many frames per sequence (0: the scene's count; else ≥ 3,
    /// the shortest sequence a dataset may hold); for tests.
    int max_frames = 0;
};

/// Simulate every sequence of the scene.
Dataset simulate_scene(const Scene& scene, const SimulateOptions& options = {});

/// Write atomically (temporary name, then rename).
void save_dataset(const Dataset& data, const std::string& path);
/// Read, then validate every array against the others before use (one function,
/// dataset.cpp `validate`): rest_positions N×3 (N ≥ 1), elements M×K (M ≥ 1, K of the
/// object) and rods indexing [0, N), masses N positive, bc/indices B ≥ 1 distinct in
/// [0, N); per sequence positions T×N×3 with T ≥ 3, bc_positions T×B×3, bc_params
/// T×Scene::kNumBcParams, newton T×3, train_frames in [0, T]; dt, material and gravity
/// in range; every array finite. IoError naming the file and dataset on any problem.
Dataset load_dataset(const std::string& path);

} // namespace lb
