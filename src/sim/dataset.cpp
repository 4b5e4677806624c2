#include "sim/dataset.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/timer.hpp"
#include "io/hdf5.hpp"
#include "sim/full_space_simulator.hpp"

namespace lb {

namespace {
/// A sequence needs two initial frames (every rollout starts from ground-truth frames
/// 0 and 1) and at least one step, as scenes require (`frames` ≥ 3).
constexpr int kMinFrames = 3;
} // namespace

MatrixX3d SequenceData::bc_targets(Index t) const
{
    return Eigen::Map<const MatrixX3d>(bc_positions.row(t).eval().data(), bc_positions.cols() / 3, 3);
}

Dataset simulate_scene(const Scene& scene, const SimulateOptions& options)
{
    if (options.max_frames < 0 || (options.max_frames > 0 && options.max_frames < kMinFrames))
        throw ConfigError("max_frames = " + std::to_string(options.max_frames) + ": a sequence needs at least " +
                          std::to_string(kMinFrames) + " frames (0: the scene's count)");
    Dataset data;
    data.scene_name = scene.name;
    data.variant = scene.variant;
    data.scene_toml = scene.resolved_toml;
    data.physics = physics_spec(scene);
    const PhysicsModel model(data.physics);
    FullSpaceSimulator sim(model, scene.newton);
    const Index n = model.num_dofs();
    const Index B = Index(scene.bc_indices.size());

    for (size_t k = 0; k < scene.sequences.size(); ++k) {
        const SequenceSpec& spec = scene.sequences[k];
        const int frames = options.max_frames > 0 ? std::min(options.max_frames, spec.frames) : spec.frames;
        const BoundaryTrajectory traj = scene.trajectory(spec);
        SequenceData seq;
        seq.name = spec.name;
        seq.train_frames = std::min(spec.train_frames, frames);
        seq.positions.resize(frames, n);
        seq.bc_positions.resize(frames, 3 * B);
        seq.bc_params = traj.params.topRows(frames);
        seq.newton = MatrixXd::Zero(frames, 3);
        for (int t = 0; t < frames; ++t) {
            seq.bc_positions.row(t) = flatten(traj.targets[size_t(t)]).transpose();
        }

        VectorXd x_prev2 = model.rest_state();
        VectorXd x_prev = x_prev2;
        seq.positions.row(0) = x_prev.transpose();
        Progress progress(scene.name + " sequence " + std::to_string(k + 1) + "/" +
                              std::to_string(scene.sequences.size()) + " (" + spec.name + ") frames",
                          frames - 1, options.progress ? 2.0 : 1e30);
        int total_iterations = 0;
        VectorXd x;
        for (int t = 1; t < frames; ++t) {
            const SolveSummary summary = sim.step(x_prev, x_prev2, traj.targets[size_t(t)], x);
            seq.newton.row(t) << summary.iterations, summary.residual, summary.seconds;
            total_iterations += summary.iterations;
            if (!summary.converged()) {
                const std::string msg = scene.source + ": scene '" + scene.name + "', sequence '" + spec.name +
                                        "', frame " + std::to_string(t) +
                                        ": Newton did not converge: " + summary.brief();
                if (options.fail_on_nonconvergence) throw NumericalError(msg);
                log_warn("%s", msg.c_str());
            }
            if (!x.allFinite()) {
                throw NumericalError(scene.source + ": scene '" + scene.name + "', sequence '" + spec.name +
                                     "', frame " + std::to_string(t) + ": non-finite state");
            }
            seq.positions.row(t) = x.transpose();
            x_prev2.swap(x_prev);
            x_prev = x;
            if (options.progress) {
                char extra[128];
                std::snprintf(extra, sizeof extra, "last: %d it, residual %.2e", summary.iterations, summary.residual);
                progress.update(t, extra);
            }
        }
        if (options.progress) {
            char extra[128];
            std::snprintf(extra, sizeof extra, "mean %.2f Newton it/frame, mean %.2f ms/frame",
                          double(total_iterations) / std::max(frames - 1, 1),
                          1e3 * seq.newton.col(2).sum() / std::max(frames - 1, 1));
            progress.finish(extra);
        }
        data.sequences.push_back(std::move(seq));
    }
    return data;
}

namespace {
// T × (3·count) matrix <-> T × count × 3 dataset.
void write_frames(h5::File& f, const std::string& name, const MatrixXd& m)
{
    const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> r = m;
    f.write_array(name, {hsize_t(m.rows()), hsize_t(m.cols() / 3), 3}, r.data());
}
} // namespace

void save_dataset(const Dataset& data, const std::string& path)
{
    h5::write_file_atomically(path, [&](h5::File& f) {
        const PhysicsSpec& p = data.physics;
        f.write("rest_positions", MatrixXd(p.mesh.rest_positions));
        f.write("elements", p.mesh.elements);
        f.write("masses", lumped_masses(p.mesh, p.material.density, p.material.thickness, p.material.radius));
        f.write("bc/indices", VectorXi(Eigen::Map<const VectorXi>(p.bc_indices.data(), Index(p.bc_indices.size()))));
        if (!p.mesh.rods.empty()) {
            MatrixXi rods(Index(p.mesh.rods.size()), Index(p.mesh.rods.front().size()));
            for (Index r = 0; r < rods.rows(); ++r) {
                if (Index(p.mesh.rods[size_t(r)].size()) != rods.cols()) throw Error("rods of unequal length");
                for (Index v = 0; v < rods.cols(); ++v) rods(r, v) = p.mesh.rods[size_t(r)][size_t(v)];
            }
            f.write("rods", rods);
        }
        f.set_attribute("/", "dt", p.dt);
        f.set_attribute("/", "scene", data.scene_name);
        f.set_attribute("/", "variant", data.variant);
        f.set_attribute("/", "object", to_string(p.mesh.kind));
        f.set_attribute("/", "scene_toml", data.scene_toml);
        f.set_attribute("/", "youngs_modulus", p.material.youngs_modulus);
        f.set_attribute("/", "poisson_ratio", p.material.poisson_ratio);
        f.set_attribute("/", "density", p.material.density);
        f.set_attribute("/", "thickness", p.material.thickness);
        f.set_attribute("/", "radius", p.material.radius);
        f.write("gravity", VectorXd(p.gravity));
        f.set_attribute("/", "num_sequences", (long long)data.sequences.size());
        for (size_t k = 0; k < data.sequences.size(); ++k) {
            const SequenceData& s = data.sequences[k];
            const std::string g = "sequences/" + std::to_string(k);
            write_frames(f, g + "/positions", s.positions);
            write_frames(f, g + "/bc_positions", s.bc_positions);
            f.write(g + "/bc_params", s.bc_params);
            f.write(g + "/newton", s.newton);
            f.set_attribute(g, "name", s.name);
            f.set_attribute(g, "train_frames", (long long)s.train_frames);
        }
    });
}

namespace {

/// One sequence as stored, before any of it is trusted.
struct StoredSequence {
    std::string group;  ///< "sequences/<k>"
    std::string name;
    long long train_frames = 0;
    std::vector<hsize_t> positions_dims, bc_positions_dims;
    std::vector<double> positions, bc_positions;  ///< flat, row-major
    MatrixXd bc_params, newton;
};

/// Everything load_dataset reads, as stored: shapes are not assumed, so that
/// validate() can check them against each other before anything is indexed.
struct StoredDataset {
    std::string object;
    MatrixXd rest_positions;
    MatrixXi elements;
    VectorXd masses;
    VectorXi bc_indices;
    bool has_rods = false;
    MatrixXi rods;
    VectorXd gravity;
    double dt = 0.0;
    Material material;
    long long num_sequences = 0;
    std::vector<StoredSequence> sequences;
};

std::string shape_text(Index rows, Index cols) { return std::to_string(rows) + "×" + std::to_string(cols); }

std::string shape_text(const std::vector<hsize_t>& dims)
{
    if (dims.empty()) return "a scalar";
    std::string s;
    for (size_t i = 0; i < dims.size(); ++i) s += (i ? "×" : "") + std::to_string(dims[i]);
    return s;
}

bool finite(const std::vector<double>& v)
{
    for (const double x : v)
        if (!std::isfinite(x)) return false;
    return true;
}

/// Every shape, range and finiteness condition of a dataset (layout in dataset.hpp),
/// checked against each other in one place; IoError naming the file and the dataset.
void validate(const StoredDataset& d, const std::string& path)
{
    const auto fail = [&](const std::string& name, const std::string& what) {
        throw IoError("dataset '" + path + "', '" + name + "': " + what);
    };
    const auto require_finite = [&](const std::string& name, bool ok) {
        if (!ok) fail(name, "non-finite value (NaN or inf)");
    };
    if (d.object != "solid" && d.object != "shell" && d.object != "rods")
        fail("object", "attribute must be solid, shell or rods, found '" + d.object + "'");
    const MeshKind kind = d.object == "rods" ? MeshKind::Rods : d.object == "shell" ? MeshKind::Shell : MeshKind::Solid;

    // Mesh: N vertices, M elements of K vertices each.
    const Index N = d.rest_positions.rows();
    if (d.rest_positions.cols() != 3 || N < 1)
        fail("rest_positions", "must be N×3 with N ≥ 1, found " + shape_text(N, d.rest_positions.cols()));
    require_finite("rest_positions", d.rest_positions.allFinite());
    const Index K = kind == MeshKind::Rods ? 2 : kind == MeshKind::Shell ? 3 : 4;
    if (d.elements.cols() != K || d.elements.rows() < 1)
        fail("elements", "must be M×" + std::to_string(K) + " with M ≥ 1 for " + d.object + ", found " +
                             shape_text(d.elements.rows(), d.elements.cols()));
    if (d.elements.minCoeff() < 0 || d.elements.maxCoeff() >= N)
        fail("elements", "indexes vertices out of range [0, " + std::to_string(N) + ")");
    if (d.masses.size() != N)
        fail("masses", "must have N = " + std::to_string(N) + " entries, found " + std::to_string(d.masses.size()));
    require_finite("masses", d.masses.allFinite());
    if (d.masses.minCoeff() <= 0.0) fail("masses", "must be positive");
    const Index B = d.bc_indices.size();
    if (B < 1) fail("bc/indices", "is empty (a scene needs at least one Dirichlet vertex)");
    if (d.bc_indices.minCoeff() < 0 || d.bc_indices.maxCoeff() >= N)
        fail("bc/indices", "indexes vertices out of range [0, " + std::to_string(N) + ")");
    std::vector<int> sorted(d.bc_indices.data(), d.bc_indices.data() + B);
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) fail("bc/indices", "lists a vertex twice");
    if (kind == MeshKind::Rods && !d.has_rods) fail("rods", "missing (a rods dataset stores its rod chains)");
    if (kind != MeshKind::Rods && d.has_rods) fail("rods", "present in a " + d.object + " dataset");
    if (d.has_rods) {
        if (d.rods.rows() < 1 || d.rods.cols() < 2)
            fail("rods", "must be R×V with R ≥ 1 and V ≥ 2, found " + shape_text(d.rods.rows(), d.rods.cols()));
        if (d.rods.minCoeff() < 0 || d.rods.maxCoeff() >= N)
            fail("rods", "indexes vertices out of range [0, " + std::to_string(N) + ")");
    }

    // Physics.
    if (d.gravity.size() != 3) fail("gravity", "must have 3 entries, found " + std::to_string(d.gravity.size()));
    require_finite("gravity", d.gravity.allFinite());
    if (!std::isfinite(d.dt) || d.dt <= 0.0) fail("/", "attribute 'dt' must be positive and finite");
    const Material& m = d.material;
    const auto positive = [&](const char* key, double v, bool required) {
        if (!std::isfinite(v) || v < 0.0 || (required && v == 0.0))
            fail("/", std::string("attribute '") + key + "' must be " + (required ? "positive" : "non-negative") +
                          " and finite");
    };
    positive("youngs_modulus", m.youngs_modulus, true);
    positive("density", m.density, true);
    positive("thickness", m.thickness, kind == MeshKind::Shell);
    positive("radius", m.radius, kind == MeshKind::Rods);
    if (!(m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5)) fail("/", "attribute 'poisson_ratio' must lie in (-1, 0.5)");

    // Sequences: T frames each; every per-frame array has T rows.
    if (d.num_sequences < 1) fail("/", "attribute 'num_sequences' must be at least 1");
    for (const StoredSequence& s : d.sequences) {
        const std::string& g = s.group;
        const auto& pd = s.positions_dims;
        if (pd.size() != 3 || Index(pd[1]) != N || pd[2] != 3)
            fail(g + "/positions", "must be T×" + std::to_string(N) + "×3, found " + shape_text(pd));
        const Index T = Index(pd[0]);
        if (T < kMinFrames)
            fail(g + "/positions", "has " + std::to_string(T) + " frames; a sequence needs at least " +
                                       std::to_string(kMinFrames) + " (two initial frames and one step)");
        const auto& bd = s.bc_positions_dims;
        if (bd.size() != 3 || Index(bd[0]) != T || Index(bd[1]) != B || bd[2] != 3)
            fail(g + "/bc_positions", "must be T×B×3 = " + std::to_string(T) + "×" + std::to_string(B) + "×3, found " +
                                          shape_text(bd));
        if (s.bc_params.rows() != T || s.bc_params.cols() != Scene::kNumBcParams)
            fail(g + "/bc_params", "must be T×P = " + shape_text(T, Scene::kNumBcParams) +
                                       " (velocity, angular velocity), found " +
                                       shape_text(s.bc_params.rows(), s.bc_params.cols()));
        if (s.newton.rows() != T || s.newton.cols() != 3)
            fail(g + "/newton", "must be T×3 = " + shape_text(T, 3) + " (iterations, residual, seconds), found " +
                                    shape_text(s.newton.rows(), s.newton.cols()));
        if (s.train_frames < 0 || s.train_frames > T)
            fail(g, "attribute 'train_frames' = " + std::to_string(s.train_frames) + " must lie in [0, T = " +
                        std::to_string(T) + "]");
        require_finite(g + "/positions", finite(s.positions));
        require_finite(g + "/bc_positions", finite(s.bc_positions));
        require_finite(g + "/bc_params", s.bc_params.allFinite());
        require_finite(g + "/newton", s.newton.allFinite());
    }
}

MatrixXd frames_matrix(const std::vector<double>& flat, const std::vector<hsize_t>& dims)
{
    return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        flat.data(), Index(dims[0]), Index(dims[1] * 3));
}

} // namespace

Dataset load_dataset(const std::string& path)
{
    const h5::File f = h5::File::open(path);
    for (const char* name : {"rest_positions", "elements", "masses", "bc/indices", "gravity"}) {
        if (!f.exists(name))
            throw IoError("dataset '" + path + "': missing '" + name + "' (not a latentbench dataset?)");
    }
    StoredDataset d;
    d.object = f.attribute_string("/", "object");
    d.rest_positions = f.read_matrix("rest_positions");
    d.elements = f.read_matrix_int("elements");
    d.masses = f.read_vector("masses");
    d.bc_indices = f.read_vector_int("bc/indices");
    d.has_rods = f.exists("rods");
    if (d.has_rods) d.rods = f.read_matrix_int("rods");
    d.gravity = f.read_vector("gravity");
    d.dt = f.attribute_double("/", "dt");
    d.material.youngs_modulus = f.attribute_double("/", "youngs_modulus");
    d.material.poisson_ratio = f.attribute_double("/", "poisson_ratio");
    d.material.density = f.attribute_double("/", "density");
    d.material.thickness = f.attribute_double("/", "thickness");
    d.material.radius = f.attribute_double("/", "radius");
    d.num_sequences = f.attribute_int("/", "num_sequences");
    for (long long k = 0; k < d.num_sequences; ++k) {
        StoredSequence s;
        s.group = "sequences/" + std::to_string(k);
        if (!f.exists(s.group))
            throw IoError("dataset '" + path + "': missing group '" + s.group + "' (num_sequences = " +
                          std::to_string(d.num_sequences) + ")");
        s.name = f.attribute_string(s.group, "name");
        s.train_frames = f.attribute_int(s.group, "train_frames");
        s.positions = f.read_array(s.group + "/positions", s.positions_dims);
        s.bc_positions = f.read_array(s.group + "/bc_positions", s.bc_positions_dims);
        s.bc_params = f.read_matrix(s.group + "/bc_params");
        s.newton = f.read_matrix(s.group + "/newton");
        d.sequences.push_back(std::move(s));
    }
    validate(d, path);

    Dataset data;
    data.scene_name = f.attribute_string("/", "scene");
    data.variant = f.has_attribute("/", "variant") ? f.attribute_string("/", "variant") : "";
    data.scene_toml = f.attribute_string("/", "scene_toml");
    PhysicsSpec& p = data.physics;
    p.mesh.kind = d.object == "rods" ? MeshKind::Rods : d.object == "shell" ? MeshKind::Shell : MeshKind::Solid;
    p.mesh.rest_positions = d.rest_positions;
    p.mesh.elements = d.elements;
    for (Index r = 0; r < d.rods.rows(); ++r) {
        std::vector<int>& rod = p.mesh.rods.emplace_back(size_t(d.rods.cols()));
        for (Index v = 0; v < d.rods.cols(); ++v) rod[size_t(v)] = d.rods(r, v);
    }
    p.bc_indices.assign(d.bc_indices.data(), d.bc_indices.data() + d.bc_indices.size());
    p.dt = d.dt;
    p.material = d.material;
    p.gravity = d.gravity;
    for (StoredSequence& stored : d.sequences) {
        SequenceData s;
        s.name = std::move(stored.name);
        s.train_frames = int(stored.train_frames);
        s.positions = frames_matrix(stored.positions, stored.positions_dims);
        s.bc_positions = frames_matrix(stored.bc_positions, stored.bc_positions_dims);
        s.bc_params = std::move(stored.bc_params);
        s.newton = std::move(stored.newton);
        data.sequences.push_back(std::move(s));
    }
    return data;
}

} // namespace lb
