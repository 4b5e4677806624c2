#include "lb_paths.hpp"
#include "scene/scene.hpp"

#include <Eigen/Geometry>
#include <filesystem>
#include <tuple>
#include <set>

#include "core/error.hpp"
#include "io/toml_config.hpp"
#include "mesh/generators.hpp"

namespace lb {
namespace {

namespace fs = std::filesystem;

void transform_mesh(Mesh& mesh, ConfigTable& cfg)
{
    const double scale = cfg.get_double("scale", 1.0);
    if (scale <= 0.0) cfg.fail("scale", "must be positive");
    const Vector3d rotate_deg = cfg.get_vec3("rotate_deg", Vector3d::Zero());
    const Vector3d translate = cfg.get_vec3("translate", Vector3d::Zero());
    const double to_rad = M_PI / 180.0;
    const Matrix3d R = (Eigen::AngleAxisd(rotate_deg.z() * to_rad, Vector3d::UnitZ()) *
                        Eigen::AngleAxisd(rotate_deg.y() * to_rad, Vector3d::UnitY()) *
                        Eigen::AngleAxisd(rotate_deg.x() * to_rad, Vector3d::UnitX()))
                           .toRotationMatrix();
    for (Index i = 0; i < mesh.rest_positions.rows(); ++i) {
        const Vector3d p = mesh.rest_positions.row(i).transpose();
        mesh.rest_positions.row(i) = (scale * (R * p) + translate).transpose();
    }
}

/// "a string", "an integer", ... for messages.
std::string type_name(const toml::node& node)
{
    switch (node.type()) {
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a number";
    case toml::node_type::boolean: return "a boolean";
    default: return "a date or time";
    }
}

std::string resolve_path(const std::string& path, const std::string& base_dir)
{
    if (path.empty() || fs::path(path).is_absolute()) return path;
    // Relative paths: first against the scene file's folder, then the repository root.
    const fs::path local = fs::path(base_dir) / path;
    if (fs::exists(local)) return local.string();
    return (fs::path(LB_SOURCE_DIR) / path).string();
}

// Limits on generated meshes and sequences: beyond them a scene could not be simulated
// on one machine anyway, and checking first gives a message instead of bad_alloc.
constexpr int kMaxGridAxis = 100'000;
constexpr int kMaxVertices = int(kMaxMeshVertices);
constexpr int kMaxSceneFrames = 10'000'000;

void check_vertex_count(const ConfigTable& cfg, const std::string& key, double vertices)
{
    if (vertices > kMaxVertices)
        cfg.fail(key, "the generated mesh would have " + std::to_string((long long)vertices) + " vertices; at most " +
                          std::to_string(kMaxVertices) + " are supported");
}

Mesh build_mesh(ConfigTable cfg, const std::string& base_dir)
{
    const std::string generator = cfg.require_string("generator");
    Mesh mesh;
    if (generator == "rod_bundle") {
        RodBundleOptions o;
        o.num_rods_x = cfg.get_count("rods_x", o.num_rods_x, 1, kMaxGridAxis);
        o.num_rods_y = cfg.get_count("rods_y", o.num_rods_y, 1, kMaxGridAxis);
        o.vertices_per_rod = cfg.get_count("vertices_per_rod", o.vertices_per_rod, 3, kMaxGridAxis);
        check_vertex_count(cfg, "rods_x", double(o.num_rods_x) * o.num_rods_y * o.vertices_per_rod);
        o.length = cfg.get_double("length", o.length);
        o.spacing = cfg.get_double("spacing", o.spacing);
        if (o.num_rods_x < 1 || o.num_rods_y < 1) cfg.fail("rods_x", "need at least one rod");
        if (o.vertices_per_rod < 3) cfg.fail("vertices_per_rod", "need at least 3 vertices per rod");
        if (o.length <= 0.0) cfg.fail("length", "must be positive");
        mesh = make_rod_bundle(o);
    } else if (generator == "cloth_grid") {
        ClothGridOptions o;
        o.nx = cfg.get_count("nx", o.nx, 2, kMaxGridAxis);
        o.ny = cfg.get_count("ny", o.ny, 2, kMaxGridAxis);
        check_vertex_count(cfg, "nx", double(o.nx) * o.ny);
        o.width = cfg.get_double("width", o.width);
        o.height = cfg.get_double("height", o.height);
        if (o.nx < 2 || o.ny < 2) cfg.fail("nx", "a cloth grid needs at least 2×2 vertices");
        if (o.width <= 0.0 || o.height <= 0.0) cfg.fail("width", "must be positive");
        mesh = make_cloth_grid(o);
    } else if (generator == "tet_beam") {
        TetBeamOptions o;
        o.nx = cfg.get_count("nx", o.nx, 1, kMaxGridAxis);
        o.ny = cfg.get_count("ny", o.ny, 1, kMaxGridAxis);
        o.nz = cfg.get_count("nz", o.nz, 1, kMaxGridAxis);
        check_vertex_count(cfg, "nx", double(o.nx + 1) * (o.ny + 1) * (o.nz + 1));
        o.size = cfg.get_vec3("size", o.size);
        if (o.nx < 1 || o.ny < 1 || o.nz < 1) cfg.fail("nx", "need at least one cell per axis");
        if ((o.size.array() <= 0.0).any()) cfg.fail("size", "must be positive");
        mesh = make_tet_beam(o);
    } else if (generator == "tetgen") {
        const std::string node_written = cfg.require_string("node"), ele_written = cfg.require_string("ele");
        const std::string node = resolve_path(node_written, base_dir);
        const std::string ele = resolve_path(ele_written, base_dir);
        for (const auto& [key, written, resolved] : {std::tuple{"node", node_written, node}, {"ele", ele_written, ele}}) {
            if (!fs::exists(resolved)) {
                // A relative path is tried beside the scene file first, then under the repository.
                const bool relative = !written.empty() && !fs::path(written).is_absolute();
                const std::string tried =
                    relative ? "'" + (fs::path(base_dir) / written).string() + "' (beside the scene file) and '" +
                                   resolved + "' (in the repository)"
                             : "'" + resolved + "'";
                throw IoError(cfg.source() + ": key '" + cfg.key_path(key) + "': mesh file '" + written +
                              "' does not exist (looked for " + tried + "); run scripts/prepare_meshes to build it");
            }
        }
        mesh = read_tetgen(node, ele);
    } else {
        cfg.fail("generator", "unknown generator '" + generator +
                                  "' (expected rod_bundle, cloth_grid, tet_beam or tetgen)");
    }
    transform_mesh(mesh, cfg);
    cfg.finish();
    return mesh;
}

std::vector<int> select_dirichlet(ConfigTable cfg, const Mesh& mesh)
{
    std::set<int> selected;
    if (cfg.get_bool("rod_roots", false)) {
        if (mesh.kind != MeshKind::Rods) cfg.fail("rod_roots", "only valid for rod meshes");
        for (const auto& rod : mesh.rods) selected.insert(rod.front());
    }
    for (long long i : cfg.get_int_array("indices", {}, 0, kMaxVertices)) {
        if (i < 0 || i >= mesh.num_vertices()) {
            cfg.fail("indices", "vertex " + std::to_string(i) + " out of range [0, " +
                                    std::to_string(mesh.num_vertices()) + ")");
        }
        selected.insert(int(i));
    }
    const Vector3d lo = mesh.rest_positions.colwise().minCoeff().transpose();
    const Vector3d hi = mesh.rest_positions.colwise().maxCoeff().transpose();
    const Vector3d extent = (hi - lo).cwiseMax(1e-12);
    for (ConfigTable region : cfg.table_array("region")) {
        // Box in bounding-box fractions: 0 = min, 1 = max on each axis.
        const Vector3d rmin = region.require_vec3("min");
        const Vector3d rmax = region.require_vec3("max");
        region.finish();
        const double eps = 1e-9;
        for (Index i = 0; i < mesh.num_vertices(); ++i) {
            const Vector3d f = (mesh.rest_positions.row(i).transpose() - lo).cwiseQuotient(extent);
            if ((f.array() >= rmin.array() - eps).all() && (f.array() <= rmax.array() + eps).all()) {
                selected.insert(int(i));
            }
        }
    }
    cfg.finish();
    if (selected.empty()) {
        cfg.fail("", "the Dirichlet selection is empty (set rod_roots, indices or [[dirichlet.region]])");
    }
    return {selected.begin(), selected.end()};
}

SequenceSpec read_sequence(ConfigTable cfg, int index)
{
    SequenceSpec seq;
    seq.name = cfg.get_string("name", "seq" + std::to_string(index));
    seq.frames = int(cfg.require_int("frames", 3, kMaxSceneFrames));
    seq.train_frames = cfg.get_count("train_frames", 0, 0, kMaxSceneFrames);
    if (seq.train_frames > seq.frames) {
        cfg.fail("train_frames", "must lie in [0, frames]");
    }
    for (ConfigTable s : cfg.table_array("segments")) {
        MotionSegment m;
        m.frames = int(s.require_int("frames", 1, kMaxSceneFrames));
        m.velocity = s.get_vec3("velocity", Vector3d::Zero());
        m.angular_velocity = s.get_vec3("angular_velocity", Vector3d::Zero());
        m.flip_every = s.get_count("flip_every", 0, 0, kMaxSceneFrames);
        s.finish();
        seq.segments.push_back(m);
    }
    cfg.finish();
    return seq;
}

} // namespace

BoundaryTrajectory Scene::trajectory(const SequenceSpec& sequence) const
{
    BoundaryTrajectory traj;
    const Index B = Index(bc_indices.size());
    MatrixX3d rest(B, 3);
    for (Index b = 0; b < B; ++b) rest.row(b) = mesh.rest_positions.row(bc_indices[size_t(b)]);
    traj.targets.assign(size_t(sequence.frames), rest);
    traj.params = MatrixXd::Zero(sequence.frames, kNumBcParams);

    Vector3d translation = Vector3d::Zero();
    Matrix3d rotation = Matrix3d::Identity();
    size_t segment = 0;
    int segment_start = 1;  // first step of the current segment
    for (int t = 1; t < sequence.frames; ++t) {
        while (segment + 1 < sequence.segments.size() &&
               t >= segment_start + sequence.segments[segment].frames) {
            segment_start += sequence.segments[segment].frames;
            ++segment;
        }
        Vector3d v = Vector3d::Zero(), w = Vector3d::Zero();
        if (!sequence.segments.empty()) {
            const MotionSegment& m = sequence.segments[segment];
            const int flips = m.flip_every > 0 ? (t - segment_start) / m.flip_every : 0;
            const double sign = (flips % 2 == 0) ? 1.0 : -1.0;
            v = sign * m.velocity;
            w = sign * m.angular_velocity;
        }
        translation += dt * v;
        const double angle = w.norm() * dt;
        if (angle > 0.0) rotation = Eigen::AngleAxisd(angle, w.normalized()).toRotationMatrix() * rotation;
        for (Index b = 0; b < B; ++b) {
            const Vector3d X = rest.row(b).transpose();
            traj.targets[size_t(t)].row(b) =
                (rotation_center + translation + rotation * (X - rotation_center)).transpose();
        }
        traj.params.row(t) << v.transpose(), w.transpose();
    }
    return traj;
}

Scene load_scene_from_string(const std::string& text, const std::string& source,
                             const std::string& base_dir, const SceneLoadOptions& options)
{
    toml::table root = parse_toml(text, source);
    // Apply the variant, then drop the variants table from the resolved config.
    toml::table resolved = root;
    resolved.erase("variants");
    if (!options.variant.empty()) {
        const toml::node* variants_node = root.get("variants");
        if (variants_node && !variants_node->is_table())
            throw ConfigError(source + ": key 'variants' must be a table of variant tables ([variants." +
                              options.variant + "]), found " + type_name(*variants_node));
        const toml::table* variants = root["variants"].as_table();
        const toml::node* variant_node = variants ? variants->get(options.variant) : nullptr;
        if (variant_node && !variant_node->is_table())
            throw ConfigError(source + ": variant '" + options.variant + "' (key 'variants." + options.variant +
                              "') is " + type_name(*variant_node) + ", not a table; write it as [variants." +
                              options.variant + "] with the keys it changes");
        const toml::table* variant = variant_node ? variant_node->as_table() : nullptr;
        if (!variant) {
            std::string available;
            if (variants) {
                for (const auto& [k, v] : *variants) available += " " + std::string(k.str());
            }
            throw ConfigError(source + ": no variant '" + options.variant + "' (available:" +
                              (available.empty() ? " none" : available) + ")");
        }
        // A variant that switches the mesh generator replaces the whole [mesh] table
        // (the base's generator-specific keys would not apply); everything else merges.
        const auto* variant_mesh = (*variant)["mesh"].as_table();
        if (variant_mesh && variant_mesh->contains("generator") &&
            (*variant_mesh)["generator"].value<std::string>() != resolved["mesh"]["generator"].value<std::string>()) {
            resolved.erase("mesh");
        }
        merge_toml(resolved, *variant);
    }

    ConfigTable cfg(resolved, "", source);
    Scene scene;
    scene.variant = options.variant;
    scene.resolved_toml = to_toml_string(resolved);
    scene.source = source;
    scene.name = cfg.require_string("name");
    scene.description = cfg.get_string("description", "");
    const std::string object = cfg.require_string("object");
    scene.dt = cfg.get_double("dt", 1.0 / 30.0);
    if (scene.dt <= 0.0) cfg.fail("dt", "must be positive");
    scene.gravity = cfg.get_vec3("gravity", scene.gravity);
    cfg.accept("variants");

    scene.mesh = build_mesh(cfg.require_table("mesh"), base_dir);
    const MeshKind expected = object == "rods"    ? MeshKind::Rods
                              : object == "shell" ? MeshKind::Shell
                              : object == "solid" ? MeshKind::Solid
                                                  : (cfg.fail("object", "expected rods, shell or solid"), MeshKind::Solid);
    if (scene.mesh.kind != expected) {
        cfg.fail("object", "'" + object + "' does not match the mesh generator's object type '" +
                               to_string(scene.mesh.kind) + "'");
    }

    ConfigTable mat = cfg.require_table("material");
    scene.material.youngs_modulus = mat.require_double("youngs_modulus");
    scene.material.poisson_ratio = mat.get_double("poisson_ratio", 0.3);
    scene.material.density = mat.require_double("density");
    scene.material.thickness = mat.get_double("thickness", 0.0);
    scene.material.radius = mat.get_double("radius", 0.0);
    mat.finish();
    if (scene.material.youngs_modulus <= 0.0) mat.fail("youngs_modulus", "must be positive");
    if (scene.material.density <= 0.0) mat.fail("density", "must be positive");
    if (scene.material.poisson_ratio <= -1.0 || scene.material.poisson_ratio >= 0.5) {
        mat.fail("poisson_ratio", "must lie in (-1, 0.5)");
    }
    if (expected == MeshKind::Shell && scene.material.thickness <= 0.0) {
        mat.fail("thickness", "shells need a positive thickness");
    }
    if (expected == MeshKind::Rods && scene.material.radius <= 0.0) {
        mat.fail("radius", "rods need a positive radius");
    }

    scene.bc_indices = select_dirichlet(cfg.require_table("dirichlet"), scene.mesh);
    Vector3d mean = Vector3d::Zero();
    for (int i : scene.bc_indices) mean += scene.mesh.rest_positions.row(i).transpose();
    mean /= double(scene.bc_indices.size());
    scene.rotation_center = mean;
    if (auto boundary = cfg.table("boundary")) {
        scene.rotation_center = boundary->get_vec3("center", mean);
        boundary->finish();
    }

    if (auto solver = cfg.table("solver")) {
        scene.newton.gradient_tolerance = solver->get_double("gradient_tolerance", scene.newton.gradient_tolerance);
        scene.newton.step_tolerance = solver->get_double("step_tolerance", scene.newton.step_tolerance);
        scene.newton.max_iterations = solver->get_count("max_iterations", scene.newton.max_iterations, 1, 1'000'000);
        scene.newton.lagged_factor_cg = solver->get_count("lagged_factor_cg", scene.newton.lagged_factor_cg, 0, 10'000);
        if (scene.newton.gradient_tolerance <= 0.0) solver->fail("gradient_tolerance", "must be positive");
        solver->finish();
    }

    int index = 0;
    for (ConfigTable s : cfg.table_array("sequences")) scene.sequences.push_back(read_sequence(s, index++));
    if (scene.sequences.empty()) cfg.fail("sequences", "at least one [[sequences]] entry is required");
    cfg.finish();
    return scene;
}

Scene load_scene(const std::string& path, const SceneLoadOptions& options)
{
    if (!fs::exists(path)) throw ConfigError("scene file '" + path + "' does not exist");
    const std::string text = read_text_file(path);
    return load_scene_from_string(text, path, fs::path(path).parent_path().string(), options);
}

} // namespace lb
