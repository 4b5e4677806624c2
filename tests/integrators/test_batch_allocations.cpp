// Heap allocations of the integrator trainer's batches (issue 14: nothing allocated per
// batch). The production epoch (nn::EpochRunner over the trainer's learner, as
// run_training_loop and train_epoch/<scene> run it) on the small cloth with the paper's
// decoder (200×3 + PCA 50) and integrator widths, noise and balancing on: after two warm-up
// epochs (in which the batch buffers, the network's and the decoder's buffers and the GEMMs'
// packing space grow to the batch sizes), two more epochs allocate nothing at all.
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
        long warm_up;    ///< heap allocations of the first epoch
        long steady;     ///< heap allocations of epochs 2 and 3
        Index batches;   ///< batches per epoch (near-equal, of at most batch_size)
    };
    Count allocations(Index batch_size)
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
        Count c{};
        {
            testing::HeapCounter counter;
            runner.run(0);
            c.warm_up = counter.count();
        }
        runner.run(1);
        testing::HeapCounter counter;
        for (int epoch = 2; epoch < 4; ++epoch) runner.run(epoch);
        c.steady = counter.count();
        c.batches = runner.num_batches();
        return c;
    }
};

// Batches of at most 64 and 256 samples (318 samples: 5 batches of 63-64, 2 of 159), on
// however many threads OpenMP has (ctest runs this on 2; the serial paths open no OpenMP
// region, whose team libgomp would allocate).
TEST_P(EpochAllocations, NothingAllocatedOnceGrown)
{
    if (!testing::heap_counting_available()) GTEST_SKIP() << "heap counting needs glibc without AddressSanitizer";
    keep_freed_memory();
    for (Index batch_size : {Index(64), Index(256)}) {
        const Count c = allocations(batch_size);
        std::printf("[ batch %ld: %ld allocations in the first epoch, %ld in epochs 2-3 (%ld batches each) ]\n",
                    long(batch_size), c.warm_up, c.steady, long(c.batches));
        EXPECT_GT(c.warm_up, 0) << "the counter sees the trainer's allocations";
        EXPECT_EQ(c.steady, 0) << "batch size " << batch_size;
    }
}

INSTANTIATE_TEST_SUITE_P(Trainer, EpochAllocations,
                         ::testing::Values(AllocationCase{"self_supervised", IntegratorLoss::SelfSupervised, false, false},
                                           AllocationCase{"float32_decoder", IntegratorLoss::SelfSupervised, true, false},
                                           AllocationCase{"overwrite_dirichlet", IntegratorLoss::SelfSupervised, false, true},
                                           AllocationCase{"supervised_l2", IntegratorLoss::SupervisedL2, false, false}),
                         [](const auto& info) { return std::string(info.param.name); });

} // namespace
} // namespace lb
