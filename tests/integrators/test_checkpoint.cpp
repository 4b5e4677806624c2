// Integrator checkpoints are resumed only when they were made from the same resolved
// options, autoencoder, training samples, physics and initial network; anything else
// (including a file of other shapes) is set aside as <path>.stale.1 and training starts
// from scratch.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>

#include "integrators/integrator_fixture.hpp"
#include "io/hdf5.hpp"

namespace lb {
namespace {

namespace fs = std::filesystem;
using testing::TinyProblem;

TinyProblem& tiny()
{
    static TinyProblem p;  // simulated once for the whole file
    return p;
}

std::string fresh_path(const std::string& name)
{
    const fs::path dir = fs::path(LB_TEST_TMP_DIR) / "integrator_checkpoint";
    fs::create_directories(dir);
    const fs::path path = dir / (name + ".h5");
    fs::remove(path);
    for (int n = 1; fs::remove(path.string() + ".stale." + std::to_string(n)); ++n) { }
    return path.string();
}

IntegratorTrainOptions base_options(const std::string& checkpoint)
{
    IntegratorTrainOptions o;
    o.hidden = {16};
    o.batch_size = 8;
    o.learning_rate = 1e-3;
    o.epochs = 3;
    o.checkpoint_every = 2;
    o.progress = false;
    o.checkpoint_path = checkpoint;
    return o;
}

IntegratorTrainSummary train(TinyProblem& p, Autoencoder& ae, const IntegratorTrainOptions& o,
                             const TrainingSamples& samples, std::uint64_t init_seed = 3)
{
    LatentMlpModel net = LatentMlpModel::create(ae.latent_dim(), samples.p.rows(), o.hidden, init_seed);
    return IntegratorTrainer(*p.model, ae, o).train(net, samples);
}

void expect_trained_from_scratch(const IntegratorTrainSummary& s, const IntegratorTrainOptions& o,
                                 const std::string& reason_part)
{
    EXPECT_FALSE(s.resumed);
    EXPECT_EQ(s.epochs_run, o.epochs);
    EXPECT_NE(s.final_loss, 0.0);
    EXPECT_NE(s.checkpoint_refused.find(reason_part), std::string::npos)
        << "reason '" << s.checkpoint_refused << "' does not mention '" << reason_part << "'";
    EXPECT_TRUE(fs::exists(o.checkpoint_path + ".stale.1"));
    EXPECT_TRUE(fs::exists(o.checkpoint_path));  // rewritten by this run
}

struct OptionChange {
    const char* name;
    std::function<void(IntegratorTrainOptions&)> apply;
};

void PrintTo(const OptionChange& c, std::ostream* os) { *os << c.name; }

class ChangedOption : public ::testing::TestWithParam<OptionChange> { };

TEST_P(ChangedOption, IsNotResumed)
{
    TinyProblem& p = tiny();
    const std::string ckpt = fresh_path(std::string("option_") + GetParam().name);
    const IntegratorTrainOptions o = base_options(ckpt);
    ASSERT_FALSE(train(p, *p.ae, o, p.samples).resumed);
    IntegratorTrainOptions changed = o;
    GetParam().apply(changed);
    expect_trained_from_scratch(train(p, *p.ae, changed, p.samples), changed, "options");
}

INSTANTIATE_TEST_SUITE_P(
    EveryTrainingOption, ChangedOption,
    ::testing::Values(OptionChange{"noise_fraction", [](auto& o) { o.noise_fraction = 0.2; }},
                      OptionChange{"training_noise", [](auto& o) { o.training_noise = false; }},
                      OptionChange{"balancing_floor", [](auto& o) { o.balancing_floor = 0.1; }},
                      OptionChange{"data_balancing", [](auto& o) { o.data_balancing = false; }},
                      OptionChange{"penalty_weight", [](auto& o) { o.penalty_weight = 1e4; }},
                      OptionChange{"epochs", [](auto& o) { o.epochs = 4; }},
                      OptionChange{"learning_rate", [](auto& o) { o.learning_rate = 2e-3; }},
                      OptionChange{"batch_size", [](auto& o) { o.batch_size = 4; }},
                      OptionChange{"seed", [](auto& o) { o.seed = 1; }},
                      OptionChange{"loss", [](auto& o) { o.loss = IntegratorLoss::SupervisedL2; }},
                      OptionChange{"hidden", [](auto& o) { o.hidden = {12}; }},
                      OptionChange{"max_seconds", [](auto& o) { o.max_seconds = 1e3; }}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(IntegratorCheckpoint, OtherAutoencoderIsNotResumed)
{
    TinyProblem& p = tiny();
    const std::string ckpt = fresh_path("other_autoencoder");
    const IntegratorTrainOptions o = base_options(ckpt);
    ASSERT_FALSE(train(p, *p.ae, o, p.samples).resumed);
    // Same architecture, other initial weights (as after retraining the autoencoder);
    // the same samples, so only the autoencoder differs.
    Autoencoder other(p.data.physics, p.ae->options(), 8);
    other.initialize_pca(other.encoding().to_features(training_frames(p.data).positions));
    expect_trained_from_scratch(train(p, other, o, p.samples), o, "autoencoder");
}

TEST(IntegratorCheckpoint, OtherSamplesAreNotResumed)
{
    TinyProblem& p = tiny();
    const std::string ckpt = fresh_path("other_samples");
    const IntegratorTrainOptions o = base_options(ckpt);
    ASSERT_FALSE(train(p, *p.ae, o, p.samples).resumed);
    TrainingSamples changed = p.samples;
    changed.p(0, 0) += 1e-9;
    expect_trained_from_scratch(train(p, *p.ae, o, changed), o, "data");
}

TEST(IntegratorCheckpoint, OtherInitialNetworkIsNotResumed)
{
    TinyProblem& p = tiny();
    const std::string ckpt = fresh_path("other_network");
    const IntegratorTrainOptions o = base_options(ckpt);
    ASSERT_FALSE(train(p, *p.ae, o, p.samples, 3).resumed);
    expect_trained_from_scratch(train(p, *p.ae, o, p.samples, 4), o, "network");
}

TEST(IntegratorCheckpoint, OtherLatentSizeIsRefusedNotCrashed)
{
    TinyProblem& p = tiny();
    TinyProblem wide("cantilever", 24, 4);
    const std::string ckpt = fresh_path("other_latent");
    const IntegratorTrainOptions o = base_options(ckpt);
    ASSERT_FALSE(train(wide, *wide.ae, o, wide.samples).resumed);
    const IntegratorTrainSummary s = train(p, *p.ae, o, p.samples);
    expect_trained_from_scratch(s, o, "differ");
}

// A checkpoint whose fingerprint claims to match but whose tensors have other shapes
// (a damaged or hand-edited file) is refused by the shape checks before anything is copied.
TEST(IntegratorCheckpoint, WrongShapesAreRefusedEvenIfTheFingerprintMatches)
{
    TinyProblem& p = tiny();
    const std::string narrow = fresh_path("shape_narrow");
    const std::string ckpt = fresh_path("shape");
    IntegratorTrainOptions o = base_options(ckpt);
    ASSERT_FALSE(train(p, *p.ae, o, p.samples).resumed);  // hidden {16}: the fingerprint to forge
    IntegratorTrainOptions n = base_options(narrow);
    n.hidden = {12};
    ASSERT_FALSE(train(p, *p.ae, n, p.samples).resumed);
    {
        const h5::File real = h5::File::open(ckpt);
        h5::File forged = h5::File::open(narrow, true);
        for (const char* part : {"options", "autoencoder", "data", "physics", "network"}) {
            const std::string key = std::string("fingerprint.") + part;
            forged.set_attribute("/", key, real.attribute_string("/", key));
        }
        forged.set_attribute("/", "fingerprint.parts", real.attribute_string("/", "fingerprint.parts"));
    }
    fs::copy_file(narrow, ckpt, fs::copy_options::overwrite_existing);
    expect_trained_from_scratch(train(p, *p.ae, o, p.samples), o, "shapes differ");
}

TEST(IntegratorCheckpoint, ResumeOffTrainsFromScratch)
{
    TinyProblem& p = tiny();
    const std::string ckpt = fresh_path("resume_off");
    IntegratorTrainOptions o = base_options(ckpt);
    const IntegratorTrainSummary first = train(p, *p.ae, o, p.samples);
    o.resume = false;
    const IntegratorTrainSummary again = train(p, *p.ae, o, p.samples);
    expect_trained_from_scratch(again, o, "resume is off");
    EXPECT_EQ(again.final_loss, first.final_loss);  // same inputs, from scratch: same numbers
}

TEST(IntegratorCheckpoint, FinishedRunIsResumedWithItsLoss)
{
    TinyProblem& p = tiny();
    const std::string ckpt = fresh_path("finished");
    const IntegratorTrainOptions o = base_options(ckpt);  // 3 epochs, checkpoints at 2 and the end
    const IntegratorTrainSummary first = train(p, *p.ae, o, p.samples);
    const IntegratorTrainSummary again = train(p, *p.ae, o, p.samples);
    EXPECT_TRUE(again.resumed);
    EXPECT_TRUE(again.checkpoint_refused.empty());
    EXPECT_EQ(again.epochs_run, 3);
    EXPECT_EQ(again.final_loss, first.final_loss);
    EXPECT_FALSE(fs::exists(ckpt + ".stale.1"));
}

// A resumed run's training time includes the earlier processes' (the tables' budget column
// and the wall-clock cap): the checkpoint records it, the resumed summary starts from it.
TEST(IntegratorCheckpoint, ResumedRunCountsTheEarlierTrainingTime)
{
    TinyProblem& p = tiny();
    const std::string ckpt = fresh_path("seconds");
    const IntegratorTrainOptions o = base_options(ckpt);
    const IntegratorTrainSummary first = train(p, *p.ae, o, p.samples);
    ASSERT_GT(first.seconds, 0.0);
    double recorded = -1.0;
    {
        const h5::File f = h5::File::open(ckpt);
        ASSERT_TRUE(f.has_attribute("/", "train_seconds"));
        recorded = std::stod(f.attribute_string("/", "train_seconds"));
    }
    EXPECT_GT(recorded, 0.0);
    EXPECT_LE(recorded, first.seconds);
    const IntegratorTrainSummary again = train(p, *p.ae, o, p.samples);
    ASSERT_TRUE(again.resumed);
    EXPECT_GE(again.seconds, recorded);
}

} // namespace
} // namespace lb
