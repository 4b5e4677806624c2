// SIGTERM/SIGINT during training (core/stop_signal.hpp): the loop finishes the epoch,
// checkpoints it and throws Stopped; rerun, it resumes there and ends where an
// uninterrupted run ends. Outside a training loop, and when the same signal comes again,
// the signal terminates the process as it would without the handlers.
#include <gtest/gtest.h>
#include <signal.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "core/stop_signal.hpp"
#include "nn/training_loop.hpp"

namespace lb::nn {
namespace {

/// Least squares y = w·x on 32 fixed samples: a learner with parameters and no extra state.
class LineLearner : public Learner {
public:
    LineLearner() : m_x(3, 32), m_y(1, 32), m_w(MatrixXd::Zero(1, 3)), m_grad(MatrixXd::Zero(1, 3))
    {
        Rng rng(7);
        for (Index j = 0; j < m_x.cols(); ++j) {
            for (Index i = 0; i < m_x.rows(); ++i) m_x(i, j) = rng.uniform(-1.0, 1.0);
            m_y(0, j) = 0.5 * m_x(0, j) - 2.0 * m_x(1, j) + m_x(2, j);
        }
    }
    Index num_samples() const override { return m_x.cols(); }
    std::vector<ParameterRef> parameters() override
    {
        return {ParameterRef{"w", Eigen::Map<MatrixXd>(m_w.data(), 1, 3), Eigen::Map<MatrixXd>(m_grad.data(), 1, 3)}};
    }
    double loss_and_gradient(const std::vector<Index>& indices, Rng& /*rng*/) override
    {
        double loss = 0.0;
        for (Index j : indices) {
            const double r = (m_w * m_x.col(j))(0) - m_y(0, j);
            loss += r * r;
            m_grad += 2.0 * r * m_x.col(j).transpose() / double(indices.size());
        }
        return loss / double(indices.size());
    }
    const MatrixXd& weights() const { return m_w; }

private:
    MatrixXd m_x, m_y, m_w, m_grad;
};

TrainingLoopOptions options(const std::string& checkpoint)
{
    TrainingLoopOptions o;
    o.label = "line";
    o.epochs = 6;
    o.batch_size = 8;
    o.learning_rate = 1e-2;
    o.progress = false;
    o.checkpoint_path = checkpoint;
    o.checkpoint_every = 100;  // no periodic checkpoint: only the stop writes one
    return o;
}

TEST(StopSignal, TrainingCheckpointsTheEpochAndResumesFromIt)
{
    install_stop_handlers();
    const std::filesystem::path dir = std::filesystem::path(LB_TEST_TMP_DIR) / "stop_signal_training";
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    const Fingerprint fingerprint = Fingerprint{}.add("options", "line");

    LineLearner straight;
    run_training_loop(straight, options(""), fingerprint);

    const std::string checkpoint = (dir / "line.checkpoint.h5").string();
    TrainingLoopOptions signalled = options(checkpoint);
    signalled.interrupt = [](int epochs_done) {
        if (epochs_done == 2) ::raise(SIGTERM);  // as pre-emption would, during epoch 2's bookkeeping
        return false;
    };
    LineLearner first;
    try {
        run_training_loop(first, signalled, fingerprint);
        FAIL() << "training went on after SIGTERM";
    } catch (const Stopped& e) {
        EXPECT_EQ(e.signal(), SIGTERM);
        const std::string message = e.what();
        EXPECT_NE(message.find("stopped by SIGTERM after epoch 2 of 6"), std::string::npos) << message;
        EXPECT_NE(message.find(checkpoint), std::string::npos) << message;
    }
    EXPECT_EQ(pending_stop_signal(), 0);
    ASSERT_TRUE(std::filesystem::exists(checkpoint));

    LineLearner resumed;
    const TrainingLoopSummary s = run_training_loop(resumed, options(checkpoint), fingerprint);
    EXPECT_TRUE(s.resumed);
    EXPECT_EQ(s.epochs_run, 6);
    EXPECT_EQ(resumed.weights(), straight.weights());  // bit for bit: no epoch lost or repeated
    EXPECT_NE(resumed.weights(), first.weights());
}

TEST(StopSignalDeathTest, OutsideTrainingTheSignalTerminates)
{
    EXPECT_EXIT(
        {
            install_stop_handlers();
            ::raise(SIGTERM);
            std::exit(0);
        },
        ::testing::KilledBySignal(SIGTERM), "");
    // The same signal twice inside a stop point does not wait for the safe point.
    EXPECT_EXIT(
        {
            install_stop_handlers();
            StopPoint point;
            ::raise(SIGINT);
            ::raise(SIGINT);
            std::exit(0);
        },
        ::testing::KilledBySignal(SIGINT), "");
    // The other signal while one is pending (Ctrl-C's SIGINT, then a driver's SIGTERM to its
    // children) waits for the safe point too.
    EXPECT_EXIT(
        {
            install_stop_handlers();
            StopPoint point;
            ::raise(SIGINT);
            ::raise(SIGTERM);
            std::exit(take_stop_signal() == SIGINT ? 0 : 3);
        },
        ::testing::ExitedWithCode(0), "");
    // A signal no loop took is not lost: leaving the stop point terminates.
    EXPECT_EXIT(
        {
            install_stop_handlers();
            {
                StopPoint point;
                ::raise(SIGTERM);
            }
            std::exit(0);
        },
        ::testing::KilledBySignal(SIGTERM), "");
    // A taken signal is the taker's to act on.
    EXPECT_EXIT(
        {
            install_stop_handlers();
            {
                StopPoint point;
                ::raise(SIGTERM);
                if (take_stop_signal() != SIGTERM) std::exit(3);
            }
            std::exit(0);
        },
        ::testing::ExitedWithCode(0), "");
}

} // namespace
} // namespace lb::nn
