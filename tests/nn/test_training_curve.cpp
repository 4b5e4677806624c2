// The loss curve of the shared training loop: one loss per epoch (and one validation loss
// with validation), ending at final_loss, kept in the checkpoint and continued by a resumed
// run exactly as an uninterrupted run has it; checkpoints written before curves were
// recorded still resume; files store and read the curves of several stages.
#include <gtest/gtest.h>

#include <hdf5.h>

#include <cmath>
#include <filesystem>

#include "core/error.hpp"
#include "io/hdf5.hpp"
#include "nn/training_curve.hpp"
#include "nn/training_loop.hpp"

namespace lb::nn {
namespace {

namespace fs = std::filesystem;

/// Least squares y ≈ w x + b on fixed samples (a learner with a real, decreasing loss).
class LineLearner final : public Learner {
public:
    explicit LineLearner(bool validation) : m_validation(validation), m_w(1, 2), m_grad(1, 2)
    {
        m_w << 0.3, -0.2;
        m_grad.setZero();
        for (int i = 0; i < 40; ++i) {
            const double x = -1.0 + 0.05 * i;
            m_x.push_back(x);
            m_y.push_back(2.0 * x + 0.5 + 0.1 * std::sin(7.0 * x));
        }
    }
    Index num_samples() const override { return Index(m_x.size()); }
    std::vector<ParameterRef> parameters() override
    {
        return {{"line.weight", Eigen::Map<MatrixXd>(m_w.data(), 1, 2), Eigen::Map<MatrixXd>(m_grad.data(), 1, 2), false}};
    }
    double loss_and_gradient(const std::vector<Index>& indices, Rng&) override
    {
        double loss = 0.0;
        const double n = double(indices.size());
        for (Index i : indices) {
            const double r = m_w(0, 0) * m_x[std::size_t(i)] + m_w(0, 1) - m_y[std::size_t(i)];
            loss += r * r / n;
            m_grad(0, 0) += 2.0 * r * m_x[std::size_t(i)] / n;
            m_grad(0, 1) += 2.0 * r / n;
        }
        return loss;
    }
    bool has_validation() const override { return m_validation; }
    double validation_loss() override
    {
        double loss = 0.0;
        for (double x : {-0.33, 0.21, 0.77}) {
            const double r = m_w(0, 0) * x + m_w(0, 1) - 2.0 * x - 0.5;
            loss += r * r / 3.0;
        }
        return loss;
    }

private:
    bool m_validation;
    MatrixXd m_w, m_grad;
    std::vector<double> m_x, m_y;
};

TrainingLoopOptions options(const std::string& checkpoint, int epochs)
{
    TrainingLoopOptions o;
    o.label = "curve test";
    o.epochs = epochs;
    o.batch_size = 8;
    o.learning_rate = 0.05;
    o.seed = 11;
    o.progress = false;
    o.checkpoint_path = checkpoint;
    o.checkpoint_every = 3;
    return o;
}

Fingerprint print() { return Fingerprint().add("options", "line"); }

std::string fresh(const std::string& name)
{
    const fs::path dir = fs::path(LB_TEST_TMP_DIR) / "training_curve";
    fs::create_directories(dir);
    const fs::path path = dir / (name + ".h5");
    fs::remove(path);
    for (int n = 1; fs::remove(path.string() + ".stale." + std::to_string(n)); ++n) { }
    return path.string();
}

/// Remove the object `name` from an HDF5 file (what an older writer would not have written).
void unlink(const std::string& path, const std::string& name)
{
    const hid_t id = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(id, 0);
    ASSERT_GE(H5Ldelete(id, name.c_str(), H5P_DEFAULT), 0);
    H5Fclose(id);
}

TEST(TrainingCurve, OneLossPerEpochEndingAtTheFinalLoss)
{
    for (bool validation : {false, true}) {
        LineLearner learner(validation);
        const TrainingLoopSummary s = run_training_loop(learner, options("", 9), print());
        ASSERT_EQ(s.curve.epochs(), 9);
        EXPECT_EQ(s.curve.train_loss.back(), s.final_loss);
        EXPECT_LT(s.curve.train_loss.back(), s.curve.train_loss.front());  // it learns
        ASSERT_EQ(s.curve.has_validation(), validation);
        if (validation) {
            ASSERT_EQ(s.curve.validation_loss.size(), 9u);
            EXPECT_EQ(s.curve.validation_loss[std::size_t(s.best_epoch - 1)], s.best_validation);
            for (double v : s.curve.validation_loss) EXPECT_GE(v, s.best_validation);
        }
    }
}

TEST(TrainingCurve, AResumedRunContinuesTheUninterruptedCurve)
{
    for (bool validation : {false, true}) {
        LineLearner straight_learner(validation);
        const TrainingLoopSummary straight =
            run_training_loop(straight_learner, options(fresh("straight"), 10), print());

        const std::string path = fresh("interrupted");
        TrainingLoopOptions o = options(path, 10);
        o.interrupt = [](int done) { return done == 5; };  // after the checkpoint at epoch 3
        LineLearner first_learner(validation);
        const TrainingLoopSummary first = run_training_loop(first_learner, o, print());
        EXPECT_TRUE(first.interrupted);
        EXPECT_EQ(first.curve.epochs(), 5);
        // The checkpoint holds the curve up to its epoch.
        EXPECT_EQ(load_curve_data(h5::File::open(path), "curve").epochs(), 3);

        o.interrupt = nullptr;
        LineLearner resumed_learner(validation);
        const TrainingLoopSummary resumed = run_training_loop(resumed_learner, o, print());
        EXPECT_TRUE(resumed.resumed);
        EXPECT_EQ(resumed.curve.train_loss, straight.curve.train_loss);  // bit for bit
        EXPECT_EQ(resumed.curve.validation_loss, straight.curve.validation_loss);
        EXPECT_EQ(resumed.curve.train_loss.back(), resumed.final_loss);
        EXPECT_EQ(load_curve_data(h5::File::open(path), "curve").train_loss, straight.curve.train_loss);
    }
}

TEST(TrainingCurve, ACheckpointWithoutACurveResumesWithTheEarlierEpochsUnknown)
{
    LineLearner straight_learner(true);
    const TrainingLoopSummary straight = run_training_loop(straight_learner, options("", 6), print());

    const std::string path = fresh("old_checkpoint");
    LineLearner first_learner(true);
    run_training_loop(first_learner, options(path, 3), print());
    unlink(path, "curve");  // as written before curves were recorded
    LineLearner resumed_learner(true);
    const TrainingLoopSummary resumed = run_training_loop(resumed_learner, options(path, 6), print());
    // (This test's fingerprint leaves the epochs out, so the longer run resumes.)
    ASSERT_TRUE(resumed.resumed) << resumed.checkpoint_refused;
    ASSERT_EQ(resumed.curve.epochs(), 6);
    EXPECT_TRUE(std::isnan(resumed.curve.train_loss[0]));
    EXPECT_TRUE(std::isnan(resumed.curve.train_loss[1]));
    EXPECT_EQ(resumed.curve.train_loss[2], straight.curve.train_loss[2]);  // the checkpoint's last loss
    for (int e = 3; e < 6; ++e) EXPECT_EQ(resumed.curve.train_loss[std::size_t(e)], straight.curve.train_loss[std::size_t(e)]);
    EXPECT_EQ(resumed.curve.train_loss.back(), resumed.final_loss);
    ASSERT_EQ(resumed.curve.validation_loss.size(), 6u);
    EXPECT_EQ(resumed.curve.validation_loss[5], straight.curve.validation_loss[5]);
    EXPECT_NE(describe_curve(resumed.curve).find("2 epochs not recorded"), std::string::npos)
        << describe_curve(resumed.curve);
}

TEST(TrainingCurve, ACheckpointWhoseCurveDisagreesWithItsCountersIsSetAside)
{
    const std::string path = fresh("bad_curve");
    LineLearner first_learner(false);
    run_training_loop(first_learner, options(path, 3), print());
    unlink(path, "curve/train_loss");
    {
        h5::File f = h5::File::open(path, true);
        f.write("curve/train_loss", VectorXd(VectorXd::Constant(2, 0.5)));  // two losses for three epochs
        f.close();
    }
    LineLearner learner(false);
    const TrainingLoopSummary s = run_training_loop(learner, options(path, 6), print());
    EXPECT_FALSE(s.resumed);
    EXPECT_NE(s.checkpoint_refused.find("loss curve has 2 epochs"), std::string::npos) << s.checkpoint_refused;
    EXPECT_TRUE(fs::exists(path + ".stale.1"));
    EXPECT_EQ(s.curve.epochs(), 6);
}

TEST(TrainingCurve, FilesStoreTheStagesInOrderAndOldFilesHaveNone)
{
    const std::string path = fresh("stages");
    TrainingCurves curves(2);
    curves[0].stage = "autoencoder";
    curves[0].train_loss = {3.0, 2.0, 1.5};
    curves[0].validation_loss = {3.5, 2.5, 2.6};
    curves[1].stage = "physics";
    curves[1].train_loss = {0.7, std::nan(""), 0.6};
    TrainingCurve empty;
    empty.stage = "skipped";  // no epochs: not stored
    h5::write_file_atomically(path, [&](h5::File& f) {
        save_training_curves(f, "p.", {curves[0], empty, curves[1]});
        f.set_attribute("/", "other", std::string("x"));
    });
    const h5::File f = h5::File::open(path);
    const TrainingCurves read = load_training_curves(f, "p.");
    ASSERT_EQ(read.size(), 2u);
    EXPECT_EQ(read[0].stage, "autoencoder");
    EXPECT_EQ(read[0].train_loss, curves[0].train_loss);
    EXPECT_EQ(read[0].validation_loss, curves[0].validation_loss);
    EXPECT_EQ(read[1].stage, "physics");
    EXPECT_FALSE(read[1].has_validation());
    EXPECT_TRUE(std::isnan(read[1].train_loss[1]));
    EXPECT_EQ(last_train_loss(read), 0.6);
    EXPECT_TRUE(load_training_curves(f, "").empty());  // another prefix: none (an old file)
    EXPECT_TRUE(std::isnan(last_train_loss({})));

    const std::string text = describe_curve(read[0]);
    for (const char* part : {"3 epochs", "3 first", "1.5 min (epoch 3)", "1.5 last", "validation 2.5 min (epoch 2)", "2.6 last"})
        EXPECT_NE(text.find(part), std::string::npos) << part << " in " << text;
}

TEST(TrainingCurve, AListedStageThatIsMissingIsAnErrorNamingTheFile)
{
    const std::string path = fresh("missing_stage");
    h5::write_file_atomically(path, [&](h5::File& f) {
        f.set_attribute("/", "training_curve.stages", std::string("integrator"));
    });
    try {
        load_training_curves(h5::File::open(path), "");
        FAIL() << "no error";
    } catch (const IoError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(path), std::string::npos) << what;
        EXPECT_NE(what.find("'integrator'"), std::string::npos) << what;
    }
}

} // namespace
} // namespace lb::nn
