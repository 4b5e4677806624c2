#include "sim/dataset.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/timer.hpp"
#include "io/hdf5.hpp"
#include "sim/full_space_simulator.hpp"

namespace lb {

MatrixX3d SequenceData::bc_targets(Index t) const
{
    return Eigen::Map<const MatrixX3d>(bc_positions.row(t).eval().data(), bc_positions.cols() / 3, 3);
}

Dataset simulate_scene(const Scene& scene, const SimulateOptions& options)
{
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
                const std::string msg = "scene '" + scene.name + "', sequence '" + spec.name + "', frame " +
                                        std::to_string(t) + ": Newton did not converge: " + summary.brief();
                if (options.fail_on_nonconvergence) throw NumericalError(msg);
                log_warn("%s", msg.c_str());
            }
            if (!x.allFinite()) {
                throw NumericalError("scene '" + scene.name + "', sequence '" + spec.name + "', frame " +
                                     std::to_string(t) + ": non-finite state");
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

MatrixXd read_frames(const h5::File& f, const std::string& name, Index count)
{
    std::vector<hsize_t> dims;
    const std::vector<double> data = f.read_array(name, dims);
    if (dims.size() != 3 || dims[2] != 3 || Index(dims[1]) != count) {
        throw IoError("dataset '" + f.path() + "', '" + name + "': expected shape T×" +
                      std::to_string(count) + "×3");
    }
    return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        data.data(), Index(dims[0]), Index(dims[1] * 3));
}
} // namespace

void save_dataset(const Dataset& data, const std::string& path)
{
    h5::AtomicOutput out(path);
    {
        h5::File f = h5::File::create(out.temp_path());
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
    }
    out.commit();
}

Dataset load_dataset(const std::string& path)
{
    const h5::File f = h5::File::open(path);
    Dataset data;
    PhysicsSpec& p = data.physics;
    const auto fail = [&](const std::string& what) { throw IoError("dataset '" + path + "': " + what); };
    for (const char* name : {"rest_positions", "elements", "masses", "bc/indices", "gravity"}) {
        if (!f.exists(name)) fail(std::string("missing '") + name + "' (not a latentbench dataset?)");
    }
    data.scene_name = f.attribute_string("/", "scene");
    data.variant = f.has_attribute("/", "variant") ? f.attribute_string("/", "variant") : "";
    data.scene_toml = f.attribute_string("/", "scene_toml");
    const std::string object = f.attribute_string("/", "object");
    p.mesh.kind = object == "rods" ? MeshKind::Rods : object == "shell" ? MeshKind::Shell : MeshKind::Solid;
    const MatrixXd rest = f.read_matrix("rest_positions");
    if (rest.cols() != 3) fail("'rest_positions' must be N×3");
    p.mesh.rest_positions = rest;
    p.mesh.elements = f.read_matrix_int("elements");
    const Index expected_k = p.mesh.kind == MeshKind::Rods ? 2 : p.mesh.kind == MeshKind::Shell ? 3 : 4;
    if (p.mesh.elements.cols() != expected_k) fail("'elements' has the wrong number of columns for " + object);
    if (p.mesh.elements.size() > 0 &&
        (p.mesh.elements.minCoeff() < 0 || p.mesh.elements.maxCoeff() >= rest.rows())) {
        fail("'elements' indexes vertices out of range");
    }
    if (f.exists("rods")) {
        const MatrixXi rods = f.read_matrix_int("rods");
        for (Index r = 0; r < rods.rows(); ++r) {
            p.mesh.rods.emplace_back(rods.row(r).data(), rods.row(r).data() + rods.cols());
            auto& rod = p.mesh.rods.back();
            for (Index v = 0; v < rods.cols(); ++v) rod[size_t(v)] = rods(r, v);
        }
    }
    const VectorXi bc = f.read_vector_int("bc/indices");
    p.bc_indices.assign(bc.data(), bc.data() + bc.size());
    p.dt = f.attribute_double("/", "dt");
    p.material.youngs_modulus = f.attribute_double("/", "youngs_modulus");
    p.material.poisson_ratio = f.attribute_double("/", "poisson_ratio");
    p.material.density = f.attribute_double("/", "density");
    p.material.thickness = f.attribute_double("/", "thickness");
    p.material.radius = f.attribute_double("/", "radius");
    const VectorXd gravity = f.read_vector("gravity");
    if (gravity.size() != 3) fail("'gravity' must have 3 entries");
    p.gravity = gravity;

    const Index N = rest.rows();
    const Index B = bc.size();
    const long long count = f.attribute_int("/", "num_sequences");
    for (long long k = 0; k < count; ++k) {
        const std::string g = "sequences/" + std::to_string(k);
        if (!f.exists(g)) fail("missing group '" + g + "'");
        SequenceData s;
        s.name = f.attribute_string(g, "name");
        s.train_frames = int(f.attribute_int(g, "train_frames"));
        s.positions = read_frames(f, g + "/positions", N);
        s.bc_positions = read_frames(f, g + "/bc_positions", B);
        s.bc_params = f.read_matrix(g + "/bc_params");
        s.newton = f.read_matrix(g + "/newton");
        const Index T = s.positions.rows();
        if (s.bc_positions.rows() != T || s.bc_params.rows() != T || s.newton.rows() != T) {
            fail("sequence " + std::to_string(k) + ": positions, bc_positions, bc_params and newton disagree on T");
        }
        if (!s.positions.allFinite()) fail("sequence " + std::to_string(k) + ": non-finite positions");
        data.sequences.push_back(std::move(s));
    }
    return data;
}

} // namespace lb
