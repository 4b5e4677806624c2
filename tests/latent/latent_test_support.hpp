#pragma once
// Shared fixtures of the latent tests: small physics built from the mesh
// generators, and the small cloth dataset.
#include "lb_paths.hpp"
#include <string>

#include "core/rng.hpp"
#include "mesh/generators.hpp"
#include "scene/scene.hpp"
#include "sim/dataset.hpp"

namespace lb::latent_test {

inline MatrixXd random_matrix(Index rows, Index cols, Rng& rng, double lo = -1.0, double hi = 1.0)
{
    MatrixXd m(rows, cols);
    for (Index j = 0; j < cols; ++j)
        for (Index i = 0; i < rows; ++i) m(i, j) = rng.uniform(lo, hi);
    return m;
}

/// Dirichlet targets of positions X (3N × S): the Dirichlet vertices' own positions (3B × S).
inline MatrixXd targets_of(const MatrixXd& X, const std::vector<int>& bc)
{
    MatrixXd T(3 * Index(bc.size()), X.cols());
    for (std::size_t b = 0; b < bc.size(); ++b) T.middleRows<3>(3 * Index(b)) = X.middleRows<3>(3 * Index(bc[b]));
    return T;
}

/// 2 × 3 rods of 5 vertices, roots Dirichlet.
inline PhysicsSpec rod_physics()
{
    RodBundleOptions o;
    o.num_rods_x = 2;
    o.num_rods_y = 3;
    o.vertices_per_rod = 5;
    o.length = 0.2;
    o.spacing = 0.05;
    PhysicsSpec p;
    p.mesh = make_rod_bundle(o);
    p.material.radius = 1e-3;
    for (const auto& rod : p.mesh.rods) p.bc_indices.push_back(rod.front());
    return p;
}

/// 5 × 4 cloth grid pinned at two corners.
inline PhysicsSpec cloth_physics()
{
    ClothGridOptions o;
    o.nx = 5;
    o.ny = 4;
    PhysicsSpec p;
    p.mesh = make_cloth_grid(o);
    p.material.thickness = 3e-3;
    p.bc_indices = {0, o.nx - 1};
    return p;
}

/// 3 × 1 × 1 tet beam clamped at x = 0.
inline PhysicsSpec solid_physics()
{
    TetBeamOptions o;
    o.nx = 3;
    o.ny = 1;
    o.nz = 1;
    o.size = Vector3d(0.3, 0.1, 0.1);
    PhysicsSpec p;
    p.mesh = make_tet_beam(o);
    for (Index i = 0; i < p.mesh.num_vertices(); ++i)
        if (p.mesh.rest_positions(i, 0) == 0.0) p.bc_indices.push_back(int(i));
    return p;
}

/// The first `frames` frames of the small cloth scene (8 × 6 vertices, 144 DOF; its
/// first 300 frames are training frames), simulated on demand (≈ 1 ms per frame).
inline Dataset small_cloth_prefix(int frames)
{
    SimulateOptions options;
    options.progress = false;
    options.max_frames = frames;
    return simulate_scene(load_scene(std::string(LB_SOURCE_DIR) + "/experiments/scenes/cloth.toml", {"small"}),
                          options);
}

} // namespace lb::latent_test
