// Heap allocations of the integrator trainer's batches. The production epoch
// (nn::EpochRunner over the trainer's learner, as run_training_loop and train_epoch/<scene>
// run it) on the small cloth with the paper's decoder (200×3 + PCA 50) and integrator widths,
// noise and balancing on. Issue 14 asks for nothing allocated per batch; that is not met
// (about 25 blocks per batch, from the integrator network's layers, the potential's result and
// the loss weights; README "Latent integrators"): what is guarded here is that nothing is
// allocated per sample. The frozen decoder's passes allocate nothing once grown
// (tests/nn/test_inference_network.cpp).
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "core/allocator.hpp"
#include "integrators/integrator_fixture.hpp"
#include "integrators/trainer.hpp"
#include "nn/training_loop.hpp"
#include "paper/scene_defaults.hpp"
#include "support/heap_counter.hpp"

namespace lb {
namespace {

using testing::TinyProblem;


/// The small cloth's first 320 frames with the paper's decoder widths (200×3 + PCA 50).
TinyProblem& cloth()
{
    static TinyProblem problem("cloth", 320, default_latent_dim("cloth"), {200, 200, 200}, 50);
    return problem;
}

struct AllocationCase {
    const char* name;
    IntegratorLoss loss;
    bool float32_decoder;
    bool overwrite_dirichlet;
};

class EpochAllocations : public ::testing::TestWithParam<AllocationCase> {
protected:
    struct Count {
        double per_batch;  ///< heap allocations per batch over two epochs after two warm-up epochs
        double samples;    ///< mean samples per batch (near-equal batches of at most batch_size)
    };
    Count allocations_per_batch(Index batch_size)
    {
        TinyProblem& p = cloth();
        IntegratorTrainOptions o;
        o.loss = GetParam().loss;
        o.float32_decoder = GetParam().float32_decoder;
        o.overwrite_dirichlet = GetParam().overwrite_dirichlet;
        o.hidden = default_integrator_hidden("cloth");
        o.batch_size = batch_size;
        o.progress = false;
        LatentMlpModel net = LatentMlpModel::create(p.ae->latent_dim(), p.samples.p.rows(), o.hidden, o.seed);
        IntegratorTrainer trainer(*p.model, *p.ae, o);
        trainer.prepare(net, p.samples);
        const std::unique_ptr<nn::Learner> learner = trainer.learner(net, p.samples);
        nn::EpochRunner runner(*learner, trainer.loop_options());
        EXPECT_GE(runner.num_batches(), 2) << p.samples.size() << " samples";
        for (int epoch = 0; epoch < 2; ++epoch) runner.run(epoch);  // warm-up
        testing::HeapCounter counter;
        for (int epoch = 2; epoch < 4; ++epoch) runner.run(epoch);
        const double batches = double(runner.num_batches());
        return {double(counter.count()) / (2.0 * batches), double(p.samples.size()) / batches};
    }
};

// A batch allocates about as many blocks whatever its size: nothing per sample (the batch's
// matrices, the network passes and the energies' per-thread buffers are made or resized
// once per batch, never per column). Batches of at most 64 and 256 samples.
TEST_P(EpochAllocations, DoNotGrowWithTheBatch)
{
    if (!testing::heap_counting_available()) GTEST_SKIP() << "heap counting needs glibc without AddressSanitizer";
    keep_freed_memory();
    const Count small = allocations_per_batch(64);
    const Count large = allocations_per_batch(256);
    std::printf("[ allocations per batch: %.1f with %.1f samples, %.1f with %.1f ]\n", small.per_batch, small.samples,
                large.per_batch, large.samples);
    EXPECT_GT(small.per_batch, 0.0);  // the counter sees the trainer's allocations
    // One allocation per sample would add one per added sample (per column two); the count
    // moves by a few between sizes (Eigen's GEMM packs on the stack or the heap by size, and
    // the threads' share of the per-column energy jobs varies): allow under one per two.
    EXPECT_LT(large.per_batch - small.per_batch, 0.5 * (large.samples - small.samples));
}

INSTANTIATE_TEST_SUITE_P(Trainer, EpochAllocations,
                         ::testing::Values(AllocationCase{"self_supervised", IntegratorLoss::SelfSupervised, false, false},
                                           AllocationCase{"float32_decoder", IntegratorLoss::SelfSupervised, true, false},
                                           AllocationCase{"overwrite_dirichlet", IntegratorLoss::SelfSupervised, false, true},
                                           AllocationCase{"supervised_l2", IntegratorLoss::SupervisedL2, false, false}),
                         [](const auto& info) { return std::string(info.param.name); });

} // namespace
} // namespace lb
