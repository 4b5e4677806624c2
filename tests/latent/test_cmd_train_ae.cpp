// `latentbench train-ae` end to end: a trained file that loads, the summary line,
// resuming from a checkpoint, and bad input (message, exit 1, no output file).
#include <gtest/gtest.h>
#include <hdf5.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "io/hdf5.hpp"
#include "latent/autoencoder.hpp"
#include "latent/latent_test_support.hpp"
#include "support/cli_runner.hpp"

namespace lb {
namespace {

namespace fs = std::filesystem;
using testing::fresh_dir;
using testing::run_cli;

TEST(TrainAeCli, TrainsSavesAndResumes)
{
    const std::string dir = fresh_dir("train_ae_cli");
    const std::string data = dir + "/cloth.h5", out = dir + "/ae.h5", ckpt = dir + "/ckpt.h5";
    const Dataset dataset = latent_test::small_cloth_prefix(60);
    save_dataset(dataset, data);

    const std::string common = "train-ae " + data + " -o " + out +
                               " --hidden 16,16 --pca 8 --batch 16 --lr 1e-3 --seed 3 --checkpoint " + ckpt;
    auto r = run_cli(common + " --epochs 2");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("validation relative RMSE"), std::string::npos) << r.output;
    ASSERT_TRUE(fs::exists(out));
    ASSERT_TRUE(fs::exists(ckpt));
    const Autoencoder ae = Autoencoder::load(out, dataset.physics);
    EXPECT_EQ(ae.latent_dim(), 4);  // the cloth default
    EXPECT_EQ(ae.options().hidden, (std::vector<Index>{16, 16}));
    EXPECT_EQ(ae.options().pca_dim, 8);
    EXPECT_EQ(ae.scene_name(), "cloth");

    // The same command again resumes the (finished) checkpoint.
    r = run_cli(common + " --epochs 2");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("resuming from checkpoint"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("2 epochs"), std::string::npos) << r.output;

    // Other options: the checkpoint is set aside (saying why) and training starts afresh.
    r = run_cli(common + " --epochs 4");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output.find("resuming from checkpoint"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("epochs 2 → 4"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("4 epochs"), std::string::npos) << r.output;
    EXPECT_TRUE(fs::exists(ckpt + ".stale.1"));
    EXPECT_NE(r.output.find(ckpt + ".stale.1"), std::string::npos) << r.output;

    // A second set-aside never replaces the first: each gets the next free number, logged.
    r = run_cli(common + " --epochs 3");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("epochs 4 → 3"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(ckpt + ".stale.2"), std::string::npos) << r.output;
    const auto options_of = [](const std::string& path) {
        return h5::File::open(path).attribute_string("/", "fingerprint.options");
    };
    ASSERT_TRUE(fs::exists(ckpt + ".stale.1"));
    ASSERT_TRUE(fs::exists(ckpt + ".stale.2"));
    EXPECT_NE(options_of(ckpt + ".stale.1").find(";epochs=2;"), std::string::npos) << options_of(ckpt + ".stale.1");
    EXPECT_NE(options_of(ckpt + ".stale.2").find(";epochs=4;"), std::string::npos) << options_of(ckpt + ".stale.2");
    EXPECT_NE(options_of(ckpt).find(";epochs=3;"), std::string::npos) << options_of(ckpt);
}

// A checkpoint of the other trainer given as --checkpoint (the autoencoder's to `fit`, an
// integrator's to `train-ae`) is refused with exit 1, and the file stays where it is,
// unchanged: it used to be set aside as if it were a stale checkpoint of this trainer.
TEST(TrainAeCli, CheckpointOfTheOtherTrainerIsRefusedAndLeftInPlace)
{
    const std::string dir = fresh_dir("train_ae_cli_other_trainer");
    const std::string data = dir + "/cloth.h5", ae = dir + "/ae.h5";
    const std::string ae_ckpt = dir + "/ae.checkpoint.h5", fit_ckpt = dir + "/fit.checkpoint.h5";
    save_dataset(latent_test::small_cloth_prefix(40), data);
    const auto train_ae = [&](const std::string& out) {
        return "train-ae " + data + " -o " + out + " --hidden 8 --pca 4 --batch 16 --epochs 2";
    };
    auto r = run_cli(train_ae(ae) + " --checkpoint " + ae_ckpt);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::string fit = "fit --method latent_mlp " + data + " --ae " + ae + " -o " + dir +
                            "/mlp.h5 --set epochs=1 --set hidden=[8] --set batch=64";
    r = run_cli(fit + " --checkpoint " + fit_ckpt);
    ASSERT_EQ(r.exit_code, 0) << r.output;

    const auto bytes = [](const std::string& path) {
        std::ifstream in(path, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    struct Case {
        std::string args, checkpoint, output;
    };
    for (const Case& c : {Case{fit + " --checkpoint " + ae_ckpt, ae_ckpt, dir + "/mlp.h5"},
                          Case{train_ae(dir + "/ae2.h5") + " --checkpoint " + fit_ckpt, fit_ckpt, dir + "/ae2.h5"}}) {
        const std::string before = bytes(c.checkpoint);
        fs::remove(c.output);
        r = run_cli(c.args);
        EXPECT_EQ(r.exit_code, 1) << c.args << "\n" << r.output;
        EXPECT_NE(r.output.find("latentbench: error:"), std::string::npos) << r.output;
        EXPECT_NE(r.output.find(c.checkpoint), std::string::npos) << r.output;
        EXPECT_NE(r.output.find("trainer"), std::string::npos) << r.output;
        EXPECT_EQ(bytes(c.checkpoint), before) << c.checkpoint << " was changed";
        EXPECT_FALSE(fs::exists(c.checkpoint + ".stale.1")) << r.output;
        EXPECT_FALSE(fs::exists(c.checkpoint + ".stale")) << r.output;
        EXPECT_FALSE(fs::exists(c.output)) << c.args;
    }
    // A checkpoint written before the trainer was recorded: its fingerprint's parts tell.
    const std::string legacy = dir + "/legacy.checkpoint.h5";
    fs::copy_file(ae_ckpt, legacy);
    {
        const hid_t file = H5Fopen(legacy.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        ASSERT_GE(file, 0);
        EXPECT_GE(H5Adelete_by_name(file, "/", "trainer", H5P_DEFAULT), 0);
        H5Fclose(file);
    }
    const std::string before = bytes(legacy);
    r = run_cli(fit + " --checkpoint " + legacy);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("another trainer"), std::string::npos) << r.output;
    EXPECT_EQ(bytes(legacy), before);
    EXPECT_FALSE(fs::exists(legacy + ".stale.1"));
}

TEST(TrainAeCli, BadInputFailsCleanly)
{
    const std::string dir = fresh_dir("train_ae_cli_bad");
    const std::string data = dir + "/cloth.h5", out = dir + "/ae.h5";
    save_dataset(latent_test::small_cloth_prefix(20), data);

    struct Case {
        std::string args, expected;
    };
    const std::vector<Case> cases = {
        {"train-ae " + dir + "/missing.h5 -o " + out, "missing.h5"},
        {"train-ae " + data + " -o " + out + " --hidden 16,0", "--hidden"},
        {"train-ae " + data + " -o " + out + " --batch 1", "--batch"},
        {"train-ae " + data + " -o " + out + " --lr -1", "--lr: must lie in (0, ∞), got -1"},
    };
    for (const auto& c : cases) {
        const auto r = run_cli(c.args);
        EXPECT_EQ(r.exit_code, 1) << c.args << "\n" << r.output;
        EXPECT_NE(r.output.find("error"), std::string::npos) << r.output;
        EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.args << "\n" << r.output;
        EXPECT_FALSE(fs::exists(out)) << c.args;
    }
}

} // namespace
} // namespace lb
