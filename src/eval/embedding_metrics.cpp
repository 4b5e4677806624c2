#include "eval/embedding_metrics.hpp"

#include "core/error.hpp"
#include "eval/metrics.hpp"
#include "io/hdf5.hpp"

namespace lb {

namespace {

EmbeddingWindow window_of(const SummaryWindow& w)
{
    EmbeddingWindow e;
    e.m_rms = w.m_rms;
    e.sted = w.sted;
    e.m_phys = w.mean_residual;
    e.frames = w.evaluated_frames;
    return e;
}

/// The metric table of the reconstructed sequence (frames 0, 1 as the rollouts' given start).
MatrixXd reconstruction_metrics(Autoencoder& ae, MetricContext& context, const SequenceData& seq)
{
    const Index T = seq.num_frames();
    const MatrixXd X = seq.positions.transpose();
    const MatrixXd targets = seq.bc_positions.transpose();
    const MatrixXd X_hat = ae.decode(ae.encode(X), targets);
    MatrixXd metrics = MatrixXd::Zero(T, kNumMetricColumns);
    for (Index t = 2; t < T; ++t) {
        context.frame_metrics(X_hat.col(t), X_hat.col(t - 1), X_hat.col(t - 2), X.col(t), X.col(t - 1),
                              targets.col(t), metrics.row(t));
    }
    return metrics;
}

const char* const kFields[] = {"m_rms", "sted", "m_phys"};

double& field(EmbeddingWindow& w, int i) { return i == 0 ? w.m_rms : i == 1 ? w.sted : w.m_phys; }

} // namespace

EmbeddingMetrics embedding_metrics(Autoencoder& ae, const PhysicsModel& model, const Dataset& data,
                                   const std::string& label)
{
    MetricContext context(model);
    std::vector<RolloutSummary> per_sequence;
    for (const SequenceData& seq : data.sequences) {
        if (seq.num_frames() < 3) continue;
        per_sequence.push_back(summarize(reconstruction_metrics(ae, context, seq), model.length_scale(),
                                         seq.train_frames, 0));
    }
    if (per_sequence.empty()) throw Error("embedding metrics: no sequence has 3 frames");
    const RolloutSummary s = aggregate(per_sequence);
    EmbeddingMetrics m;
    m.label = label;
    m.train = window_of(s.train);
    m.test = window_of(s.test);
    return m;
}

void save_embedding_metrics(h5::File& file, const std::vector<EmbeddingMetrics>& rows)
{
    file.set_attribute("/", "embedding.count", (long long)rows.size());
    for (size_t i = 0; i < rows.size(); ++i) {
        const std::string p = "embedding." + std::to_string(i) + ".";
        EmbeddingMetrics r = rows[i];
        file.set_attribute("/", p + "label", r.label);
        for (int f = 0; f < 3; ++f) {
            file.set_attribute("/", p + "train_" + kFields[f], field(r.train, f));
            file.set_attribute("/", p + "test_" + kFields[f], field(r.test, f));
        }
        file.set_attribute("/", p + "train_frames", (long long)r.train.frames);
        file.set_attribute("/", p + "test_frames", (long long)r.test.frames);
    }
}

std::vector<EmbeddingMetrics> load_embedding_metrics(const h5::File& file)
{
    std::vector<EmbeddingMetrics> rows;
    if (!file.has_attribute("/", "embedding.count")) return rows;
    const long long n = file.attribute_int("/", "embedding.count");
    if (n < 0 || n > 100) throw IoError(file.path() + ": attribute embedding.count is " + std::to_string(n));
    auto need = [&](const std::string& key) {
        if (!file.has_attribute("/", key)) throw IoError(file.path() + ": missing attribute " + key);
        return key;
    };
    for (long long i = 0; i < n; ++i) {
        const std::string p = "embedding." + std::to_string(i) + ".";
        EmbeddingMetrics r;
        r.label = file.attribute_string("/", need(p + "label"));
        for (int f = 0; f < 3; ++f) {
            field(r.train, f) = file.attribute_double("/", need(p + "train_" + kFields[f]));
            field(r.test, f) = file.attribute_double("/", need(p + "test_" + kFields[f]));
        }
        r.train.frames = int(file.attribute_int("/", need(p + "train_frames")));
        r.test.frames = int(file.attribute_int("/", need(p + "test_frames")));
        rows.push_back(std::move(r));
    }
    return rows;
}

} // namespace lb
