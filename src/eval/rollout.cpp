#include "eval/rollout.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "io/hdf5.hpp"

namespace lb {

BoundaryState boundary_state(const SequenceData& sequence, Index t)
{
    return {sequence.bc_params.row(t).transpose(), sequence.bc_positions.row(t).transpose()};
}

std::string rollout_frames_problem(long long frames)
{
    if (frames == 0 || (frames >= kMinRolloutFrames && frames <= kMaxRolloutFrames)) return "";
    return "must be 0 (the whole sequence) or between " + std::to_string(kMinRolloutFrames) +
           " (two initial frames and one step) and " + std::to_string(kMaxRolloutFrames) + ", got " +
           std::to_string(frames);
}

RolloutResult rollout(Integrator& integrator, const PhysicsModel& model, const SequenceData& sequence,
                      const RolloutOptions& options)
{
    // Frames 0 and 1 are copied from the ground truth below: shorter rollouts would
    // write past a 1- or 2-row table.
    const std::string problem = rollout_frames_problem(options.max_frames);
    if (!problem.empty()) throw ConfigError("rollout: max_frames " + problem);
    if (sequence.num_frames() < kMinRolloutFrames)
        throw IoError("rollout: sequence '" + sequence.name + "' has " + std::to_string(sequence.num_frames()) +
                      " frames; a rollout needs at least " + std::to_string(kMinRolloutFrames));
    const Index T = options.max_frames > 0 ? std::min<Index>(options.max_frames, sequence.num_frames())
                                           : sequence.num_frames();
    RolloutResult r;
    r.method = integrator.name();
    r.sequence = sequence.name;
    r.metrics = MatrixXd::Constant(T, kNumMetricColumns, std::numeric_limits<double>::quiet_NaN());
    if (options.keep_positions) r.positions = MatrixXd::Constant(T, model.num_dofs(), std::numeric_limits<double>::quiet_NaN());
    MetricContext context(model);

    VectorXd x_prev2 = sequence.positions.row(0).transpose();
    VectorXd x_prev = sequence.positions.row(1).transpose();
    integrator.reset(x_prev2, boundary_state(sequence, 0), x_prev, boundary_state(sequence, 1));
    for (Index t = 0; t < 2; ++t) {
        r.metrics.row(t).setZero();
        if (t > 0) context.ground_truth_metrics(x_prev, x_prev2, r.metrics.row(t));
        r.metrics(t, kKinetic) = r.metrics(t, kKineticGt);
        r.metrics(t, kKineticFree) = r.metrics(t, kKineticFreeGt);
        r.metrics(t, kElastic) = r.metrics(t, kElasticGt);
        if (options.keep_positions) r.positions.row(t) = sequence.positions.row(t);
    }
    Progress progress("rollout " + r.method + " on " + sequence.name, T - 2, options.progress ? 2.0 : 1e30);
    for (Index t = 2; t < T; ++t) {
        const BoundaryState bc = boundary_state(sequence, t);
        const StepTiming timing = integrator.step(bc);
        const VectorXd& x = integrator.positions();
        context.frame_metrics(x, x_prev, x_prev2, sequence.positions.row(t).transpose(),
                              sequence.positions.row(t - 1).transpose(), bc.targets, r.metrics.row(t));
        r.metrics(t, kIntegrateSeconds) = timing.integrate_seconds;
        r.metrics(t, kDecodeSeconds) = timing.decode_seconds;
        if (options.keep_positions) r.positions.row(t) = x.transpose();
        if (!x.allFinite()) {
            log_warn("rollout of %s on %s: non-finite state at frame %ld; stopping", r.method.c_str(),
                     sequence.name.c_str(), long(t));
            // The prediction's columns stay NaN after the stop; the truth's are filled in.
            for (Index u = t + 1; u < T; ++u) {
                context.ground_truth_metrics(sequence.positions.row(u).transpose(),
                                             sequence.positions.row(u - 1).transpose(), r.metrics.row(u));
            }
            break;
        }
        x_prev2.swap(x_prev);
        x_prev = x;
        if (options.progress) progress.update(t - 1);
    }
    r.summary = summarize(r.metrics, model.length_scale(), int(sequence.train_frames));
    r.summary.timing_threads = double(num_threads());  // the times above ran with these threads
    return r;
}

void save_rollouts(const std::vector<RolloutResult>& results, const std::string& path, const std::string& config_text)
{
    h5::write_file_atomically(path, [&](h5::File& f) {
        f.set_attribute("/", "config", config_text);
        f.set_attribute("/", "num_rollouts", (long long)results.size());
        std::string columns;
        for (const auto& c : metric_column_names()) columns += (columns.empty() ? "" : ",") + c;
        f.set_attribute("/", "metric_columns", columns);
        for (size_t k = 0; k < results.size(); ++k) {
            const RolloutResult& r = results[k];
            const std::string g = "rollouts/" + std::to_string(k);
            f.write(g + "/metrics", r.metrics);
            if (r.positions.size() > 0) {
                const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> p = r.positions;
                f.write_array(g + "/positions", {hsize_t(p.rows()), hsize_t(p.cols() / 3), 3}, p.data());
            }
            f.set_attribute(g, "method", r.method);
            f.set_attribute(g, "sequence", r.sequence);
            write_summary(f, g, r.summary);
        }
    });
}

std::vector<size_t> select_sequences(const Dataset& data, const std::string& which)
{
    std::vector<size_t> out;
    for (size_t k = 0; k < data.sequences.size(); ++k) {
        const auto& s = data.sequences[k];
        if (which == "all" || (which == "test" && s.train_frames < s.num_frames()) || which == s.name) out.push_back(k);
    }
    if (out.empty()) throw ConfigError("no sequence matches '" + which + "' (use test, all or a sequence name)");
    return out;
}

std::vector<RolloutRecord> load_rollout_summaries(const std::string& path)
{
    const h5::File f = h5::File::open(path);
    if (!f.has_attribute("/", "num_rollouts")) throw IoError("'" + path + "' is not a rollout file");
    std::vector<RolloutRecord> records;
    const long long n = f.attribute_int("/", "num_rollouts");
    for (long long k = 0; k < n; ++k) {
        const std::string g = "rollouts/" + std::to_string(k);
        RolloutRecord r;
        r.method = f.attribute_string(g, "method");
        r.sequence = f.attribute_string(g, "sequence");
        r.summary = read_summary(f, g);
        records.push_back(std::move(r));
    }
    return records;
}

} // namespace lb
