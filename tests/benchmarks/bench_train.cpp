// One training epoch of the paper's self-supervised integrator per full-size scene
// (issue 14's "train_epoch/<scene>"): the production epoch code (nn::EpochRunner over the
// trainer's learner, as run_training_loop runs it) with the suites' settings: batch 256,
// noise and balancing on, the scene's Table 1 latent size and Table 2 integrator widths,
// the paper's 200×3 ResNet decoder with a 50-wide PCA layer.
//
// The data: the scene's sample count S = Σ over sequences of (train_frames − 2), the
// number a suite trains on. To keep the set-up short the states are the first
// kSimulatedFrames frames of every sequence (full-space simulation), repeated
// until each sequence has its train_frames; the autoencoder is PCA-initialised on them
// and otherwise untrained. An epoch's cost depends on S, the widths and the mesh, not on
// the values. Counters: samples (S), columns (network columns per epoch, noisy copies
// included), batches. Full-size Armadillo/Bunny need scripts/prepare_meshes.
#include "lb_paths.hpp"
#include <benchmark/benchmark.h>

#include <map>
#include <memory>

#include "core/allocator.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "integrators/trainer.hpp"
#include "nn/inference_network.hpp"
#include "paper/scene_defaults.hpp"
#include "sim/dataset.hpp"

namespace lb {
namespace {

constexpr int kSimulatedFrames = 8;

struct TrainingSetup {
    std::unique_ptr<PhysicsModel> model;
    std::unique_ptr<Autoencoder> autoencoder;
    TrainingSamples samples;
};

/// The scene's dataset shape (sequence count, train_frames) filled with its first frames.
Dataset short_dataset(const Scene& scene)
{
    SimulateOptions options;
    options.progress = false;
    options.max_frames = kSimulatedFrames;
    Dataset data = simulate_scene(scene, options);
    for (std::size_t s = 0; s < data.sequences.size(); ++s) {
        SequenceData& seq = data.sequences[s];
        const Index want = scene.sequences[s].train_frames;
        const Index have = seq.num_frames();
        auto tile = [&](MatrixXd& m) {
            MatrixXd out(want, m.cols());
            for (Index t = 0; t < want; ++t) out.row(t) = m.row(t % have);
            m = std::move(out);
        };
        tile(seq.positions);
        tile(seq.bc_positions);
        tile(seq.bc_params);
        tile(seq.newton);
        seq.train_frames = int(want);
    }
    return data;
}

TrainingSetup& setup(const std::string& scene_name)
{
    static std::map<std::string, std::unique_ptr<TrainingSetup>> cache;
    auto& slot = cache[scene_name];
    if (slot) return *slot;
    auto made = std::make_unique<TrainingSetup>();
    const Scene scene = load_scene(std::string(LB_SOURCE_DIR) + "/experiments/scenes/" + scene_name + ".toml");
    const Dataset data = short_dataset(scene);
    made->model = std::make_unique<PhysicsModel>(data.physics);
    AutoencoderOptions ae;
    ae.latent_dim = default_latent_dim(scene_name);
    ae.hidden = {200, 200, 200};
    ae.pca_dim = 50;
    made->autoencoder = std::make_unique<Autoencoder>(data.physics, ae, 0);
    const FrameSet frames = training_frames(data);
    made->autoencoder->initialize_pca(made->autoencoder->encoding().to_features(frames.positions));
    made->samples = make_training_samples(*made->autoencoder, data);
    slot = std::move(made);
    return *slot;
}

/// setup(), or nullptr with the benchmark skipped and the reason given (e.g. missing meshes).
TrainingSetup* setup_or_skip(benchmark::State& state, const std::string& scene_name)
{
    try {
        return &setup(scene_name);
    } catch (const Error& e) {
        state.SkipWithError(e.what());
        return nullptr;
    }
}

/// @param float32  the frozen decoder in single precision (`float32_decoder`)
void train_epoch(benchmark::State& state, const std::string& scene_name, bool float32)
{
    set_log_level(LogLevel::Quiet);
    keep_freed_memory();  // the CLI's heap policy (core/allocator.hpp)
    TrainingSetup* s = setup_or_skip(state, scene_name);
    if (!s) return;
    IntegratorTrainOptions options;
    options.hidden = default_integrator_hidden(scene_name);
    options.batch_size = 256;
    options.learning_rate = 1e-3;
    options.progress = false;
    options.float32_decoder = float32;
    LatentMlpModel net =
        LatentMlpModel::create(s->autoencoder->latent_dim(), s->samples.p.rows(), options.hidden, options.seed);
    IntegratorTrainer trainer(*s->model, *s->autoencoder, options);
    trainer.prepare(net, s->samples);
    const std::unique_ptr<nn::Learner> learner = trainer.learner(net, s->samples);
    nn::EpochRunner runner(*learner, trainer.loop_options());
    int epoch = 0;
    for (auto _ : state) benchmark::DoNotOptimize(runner.run(epoch++));
    state.counters["samples"] = double(s->samples.size());
    state.counters["columns"] = double(runner.samples_per_epoch() * (options.training_noise ? 2 : 1));
    state.counters["batches"] = double(runner.num_batches());
    const double columns = state.counters["columns"];
    const double decoder_madds = double(nn::InferenceNetworkD(s->autoencoder->decoder()).multiply_adds());
    const double integrator_madds = double(nn::InferenceNetworkD(net.network).multiply_adds());
    state.counters["network_GFLOP"] = 2.0 * columns * 3.0 * (decoder_madds + integrator_madds) * 1e-9;
}

/// The frozen decoder's batched pass as the self-supervised loss runs it: forward with its
/// tape, then the vector-Jacobian product, on 512 columns (a batch of 256 and its noisy
/// copies), the columns split over the threads. Counter GFLOPS: 2 × the multiply-adds of
/// both passes per second, to set beside gemm_rate.
template <typename Scalar>
void decoder_batch(benchmark::State& state, const std::string& scene_name)
{
    set_log_level(LogLevel::Quiet);
    keep_freed_memory();  // as train_epoch
    TrainingSetup* s = setup_or_skip(state, scene_name);
    if (!s) return;
    using Matrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
    constexpr Index kColumns = 512;
    nn::BasicInferenceNetwork<Scalar> decoder(s->autoencoder->decoder());
    const Matrix Z = Matrix::Random(s->autoencoder->latent_dim(), kColumns);
    const Matrix dY = Matrix::Random(decoder.out_features(), kColumns);
    for (auto _ : state) {
        benchmark::DoNotOptimize(decoder.forward_batch(Z, true).data());
        benchmark::DoNotOptimize(decoder.vjp_batch(dY).data());
    }
    state.counters["GFLOPS"] = benchmark::Counter(4.0 * double(decoder.multiply_adds() * kColumns) * 1e-9,
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
void decoder_batch_float(benchmark::State& state, const std::string& scene) { decoder_batch<float>(state, scene); }
void decoder_batch_double(benchmark::State& state, const std::string& scene) { decoder_batch<double>(state, scene); }
BENCHMARK_CAPTURE(decoder_batch_float, cloth, "cloth")->Name("decoder_batch/float/cloth")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(decoder_batch_double, cloth, "cloth")->Name("decoder_batch/double/cloth")->Unit(benchmark::kMillisecond)->UseRealTime();

/// Eigen GEMM throughput on this machine at the paper's decoder width (200 × 200 weights
/// times 1,024 columns, the columns split over the threads as the frozen decoder's batched
/// pass splits them). Counter GFLOPS: 2 × multiply-adds per second.
template <typename Scalar>
void gemm_rate(benchmark::State& state)
{
    using Matrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
    constexpr Index kWidth = 200, kColumns = 1024;
    const int threads = int(state.range(0));
    const Matrix W = Matrix::Random(kWidth, kWidth);
    const Matrix X = Matrix::Random(kWidth, kColumns);
    Matrix Y(kWidth, kColumns);
    const Index block = kColumns / threads;
    for (auto _ : state) {
#pragma omp parallel for num_threads(threads) schedule(static)
        for (int t = 0; t < threads; ++t) Y.middleCols(t * block, block).noalias() = W * X.middleCols(t * block, block);
        benchmark::DoNotOptimize(Y.data());
        benchmark::ClobberMemory();
    }
    state.counters["GFLOPS"] = benchmark::Counter(2.0 * double(kWidth * kWidth * kColumns) * 1e-9,
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK_TEMPLATE(gemm_rate, double)->Name("gemm_rate/double")->Arg(1)->Arg(2)->UseRealTime();
BENCHMARK_TEMPLATE(gemm_rate, float)->Name("gemm_rate/float")->Arg(1)->Arg(2)->UseRealTime();

// Warm-up epochs run before the timed ones: the first epoch faults in every batch-sized
// matrix (the heap then keeps them, core/allocator.hpp), and on the large scenes 2 s holds a
// single epoch, so without them that first epoch would be what is timed.
void epoch_timing(benchmark::internal::Benchmark* b)
{
    b->Unit(benchmark::kMillisecond)->MinWarmUpTime(1.0)->MinTime(2.0);
}
#define LB_TRAIN_BENCH(name) BENCHMARK_CAPTURE(train_epoch, name, #name, false)->Apply(epoch_timing)
#define LB_TRAIN_BENCH_FLOAT32(name) BENCHMARK_CAPTURE(train_epoch, name##_float32, #name, true)->Apply(epoch_timing)

LB_TRAIN_BENCH(cloth);
LB_TRAIN_BENCH(cantilever);
LB_TRAIN_BENCH(rods_translate);
LB_TRAIN_BENCH(rods_rotate);
LB_TRAIN_BENCH(armadillo);
LB_TRAIN_BENCH(bunny_ears);
LB_TRAIN_BENCH_FLOAT32(cloth);
LB_TRAIN_BENCH_FLOAT32(cantilever);
LB_TRAIN_BENCH_FLOAT32(rods_translate);
LB_TRAIN_BENCH_FLOAT32(rods_rotate);
LB_TRAIN_BENCH_FLOAT32(armadillo);
LB_TRAIN_BENCH_FLOAT32(bunny_ears);

} // namespace
} // namespace lb
