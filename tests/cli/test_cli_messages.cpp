// Messages that name the problem (issue 44, item 6): each case below used to print a
// message that named the wrong thing or nothing (a variant "missing" that exists, a
// rollout file blamed on an older version, a range that excluded the value it quoted, a
// raw `filesystem error:`). Each now exits 1 with a `latentbench: error:` line naming the
// file or option and what is wrong with it.
#include "lb_paths.hpp"
#include <gtest/gtest.h>
#include <hdf5.h>

#include <filesystem>
#include <string>
#include <vector>

#include "eval/summary_schema.hpp"
#include "io/hdf5.hpp"
#include "support/cli_runner.hpp"
#include "support/tiny_scene.hpp"

namespace lb {
namespace {

using testing::fresh_dir;
using testing::run_cli;
using testing::write_file;
namespace fs = std::filesystem;

/// The `latentbench: error:` line of `args`, after checking that it exits 1.
std::string error_line(const std::string& args)
{
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 1) << args << "\n" << r.output;
    const size_t at = r.output.find("latentbench: error:");
    if (at == std::string::npos) {
        ADD_FAILURE() << args << ": no error line\n" << r.output;
        return {};
    }
    return r.output.substr(at, r.output.find('\n', at) - at);
}

void expect_parts(const std::string& line, const std::vector<std::string>& parts)
{
    for (const std::string& p : parts) EXPECT_NE(line.find(p), std::string::npos) << "'" << p << "' missing: " << line;
}

// `no variant 'small' (available: small zz)`: the variant exists but is not a table.
TEST(CliMessages, VariantThatIsNotATable)
{
    const std::string dir = fresh_dir("cli_messages_variant");
    write_file(dir + "/scene.toml", std::string(testing::kTinySceneToml) +
                                        "[variants]\nsmall = 3\n[variants.zz]\nmesh = { nx = 1 }\n");
    const std::string line = error_line("simulate " + dir + "/scene.toml --variant small --check");
    expect_parts(line, {"scene.toml", "variant 'small'", "an integer, not a table"});
    EXPECT_EQ(line.find("no variant"), std::string::npos) << line;
    // A variant that does not exist is still reported as such, with the ones that do.
    expect_parts(error_line("simulate " + dir + "/scene.toml --variant big --check"),
                 {"no variant 'big'", "small", "zz"});
    const auto ok = run_cli("simulate " + dir + "/scene.toml --variant zz --check");
    EXPECT_EQ(ok.exit_code, 0) << ok.output;
}

// A missing tetgen file named only the repository-root path, not the path beside the
// scene file that was tried first.
TEST(CliMessages, MissingMeshFileNamesBothPathsTried)
{
    const std::string dir = fresh_dir("cli_messages_mesh");
    std::string scene = testing::kTinySceneToml;
    const std::string beam = "generator = \"tet_beam\"";
    scene.replace(scene.find(beam), beam.size(), "generator = \"tetgen\"\nnode = \"meshes/x.node\"\nele = \"meshes/x.ele\"");
    write_file(dir + "/scene.toml", scene);
    const std::string line = error_line("simulate " + dir + "/scene.toml --check");
    expect_parts(line, {"'meshes/x.node' does not exist", "'" + dir + "/meshes/x.node' (beside the scene file)",
                        "'" + std::string(LB_SOURCE_DIR) + "/meshes/x.node' (in the repository)"});
}

// The rollout-summary error named no file and blamed an older latentbench for a damaged
// file; a file from before the training/test windows (no counters at all) still says so.
TEST(CliMessages, DamagedRolloutSummaryIsNotBlamedOnAnOlderVersion)
{
    const std::string dir = fresh_dir("cli_messages_rollout");
    write_file(dir + "/scene.toml", testing::kTinySceneToml);
    ASSERT_EQ(run_cli("simulate " + dir + "/scene.toml -o " + dir + "/data.h5").exit_code, 0);
    const auto roll = run_cli("rollout " + dir + "/data.h5 --method full_space --sequences all --frames 4 -o " + dir +
                              "/roll.h5");
    ASSERT_EQ(roll.exit_code, 0) << roll.output;
    ASSERT_EQ(run_cli("evaluate " + dir + "/roll.h5").exit_code, 0);

    std::vector<std::string> counters;
    for (const SummaryMetric& m : summary_metrics())
        if (m.integer) counters.push_back(m.name);
    ASSERT_GE(counters.size(), 2u);
    const auto without = [&](const std::string& name, size_t count) {
        const std::string path = dir + "/" + name + ".h5";
        fs::copy_file(dir + "/roll.h5", path, fs::copy_options::overwrite_existing);
        const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        EXPECT_GE(file, 0);
        for (size_t k = 0; k < count; ++k) EXPECT_GE(H5Adelete_by_name(file, "rollouts/0", counters[k].c_str(), H5P_DEFAULT), 0);
        H5Fclose(file);
        return path;
    };
    const std::string damaged = without("damaged", 1);
    std::string line = error_line("evaluate " + damaged);
    expect_parts(line, {damaged, "'rollouts/0'", "'" + counters[0] + "'", "damaged"});
    EXPECT_EQ(line.find("older"), std::string::npos) << line;
    const std::string old = without("old", counters.size());
    line = error_line("evaluate " + old);
    expect_parts(line, {old, "'rollouts/0'", "older"});
}

// `non-finite incremental potential in the training batch` named no file, epoch or sample.
// An autoencoder whose decoder overflows (a weight scaled by 1e200) makes it happen.
TEST(CliMessages, NonFiniteTrainingPotentialNamesFilesEpochAndSample)
{
    const std::string dir = fresh_dir("cli_messages_nonfinite");
    write_file(dir + "/scene.toml", testing::kTinySceneToml);
    ASSERT_EQ(run_cli("simulate " + dir + "/scene.toml -o " + dir + "/data.h5").exit_code, 0);
    const auto train = run_cli("train-ae " + dir + "/data.h5 -o " + dir + "/ae.h5 --epochs 2 --hidden 8 --pca 4 --latent 2");
    ASSERT_EQ(train.exit_code, 0) << train.output;
    const std::string huge = dir + "/ae_overflowing.h5";
    fs::copy_file(dir + "/ae.h5", huge, fs::copy_options::overwrite_existing);
    {
        h5::File f = h5::File::open(huge, /*writable=*/true);
        std::string last;  // the decoder's last weight: its outputs scale with it
        for (const std::string& name : f.list("/"))
            if (name.rfind("decoder.", 0) == 0 && name.find("weight") != std::string::npos) last = name;
        ASSERT_FALSE(last.empty());
        f.write(last, MatrixXd(f.read_matrix(last) * 1e200));
    }
    const std::string out = dir + "/mlp.h5";
    const std::string line = error_line("fit --method latent_mlp " + dir + "/data.h5 --ae " + huge + " -o " + out +
                                        " --set epochs=2");
    expect_parts(line, {"'" + dir + "/data.h5'", "'" + huge + "'", "epoch 1 of 2", "training sample",
                        "non-finite incremental potential"});
    EXPECT_FALSE(fs::exists(out));
}

// `--set epochs=-5` was told the range [0, 10000000], but 0 is refused too.
TEST(CliMessages, EpochsRangeIsTheOneEnforced)
{
    const std::string dir = fresh_dir("cli_messages_epochs");
    for (const char* epochs : {"-5", "0"}) {
        const std::string line = error_line("fit --method latent_mlp " + dir + "/none.h5 -o " + dir +
                                            "/out.h5 --set epochs=" + epochs);
        expect_parts(line, {"epochs", "[1, 10000000]", std::string("got ") + epochs});
        EXPECT_EQ(line.find("[0,"), std::string::npos) << line;
    }
}

// `run -o FILE` printed a raw `filesystem error:` that never mentioned -o.
TEST(CliMessages, RunOutputThatIsAFile)
{
    const std::string dir = fresh_dir("cli_messages_run_output");
    write_file(dir + "/suite.toml", "name = \"x\"\n[[integrators]]\nname = \"pca\"\nmethod = \"linear_pca\"\n"
                                    "[[scenes]]\nscene = \"" + std::string(LB_SOURCE_DIR) +
                                        "/experiments/scenes/cantilever.toml\"\nvariant = \"small\"\n");
    write_file(dir + "/file", "not a directory\n");
    for (const std::string& out : {dir + "/file", dir + "/file/run"}) {
        const std::string line = error_line("run " + dir + "/suite.toml -o " + out);
        expect_parts(line, {"-o '" + out + "'", "not a directory"});
        EXPECT_EQ(line.find("filesystem error"), std::string::npos) << line;
    }
    EXPECT_EQ(run_cli("run " + dir + "/suite.toml -o " + dir + "/file --check").exit_code, 1);
}

} // namespace
} // namespace lb
