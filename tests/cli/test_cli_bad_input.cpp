// Bad input through the CLI: a message naming the problem, a non-zero exit,
// and no output file left behind.
#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include <filesystem>

#include "support/cli_runner.hpp"
#include "support/tiny_scene.hpp"

namespace lb {
namespace {

using testing::fresh_dir;
using testing::run_cli;
using testing::write_file;
namespace fs = std::filesystem;

const char* const kScene = testing::kTinySceneToml;

struct BadCase {
    std::string name;
    std::string text;
    std::string expected;  // substring of the error message
};

void expect_rejected(const BadCase& c)
{
    const std::string dir = fresh_dir("cli_" + c.name);
    const std::string scene = dir + "/scene.toml";
    const std::string out = dir + "/out.h5";
    write_file(scene, c.text);
    const auto result = run_cli("simulate " + scene + " -o " + out);
    EXPECT_NE(result.exit_code, 0) << c.name << ": " << result.output;
    EXPECT_NE(result.output.find(c.expected), std::string::npos) << c.name << ": " << result.output;
    EXPECT_FALSE(fs::exists(out)) << c.name;
    for (const auto& entry : fs::directory_iterator(dir)) {
        EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos)
            << "temporary file left behind: " << entry.path();
    }
}

std::string with(std::string text, const std::string& from, const std::string& to)
{
    text.replace(text.find(from), from.size(), to);
    return text;
}

TEST(CliBadInput, MalformedToml) { expect_rejected({"malformed", "name = \"tiny\n[mesh", "malformed TOML"}); }

TEST(CliBadInput, UnknownKey)
{
    expect_rejected({"unknown_key", with(kScene, "nz = 1", "nz = 1\ncells = 3"), "unknown key 'mesh.cells'"});
}

TEST(CliBadInput, MissingMeshFile)
{
    expect_rejected({"missing_mesh",
                     with(kScene, "generator = \"tet_beam\"", "generator = \"tetgen\"\nnode = \"no/such.node\"\nele = \"no/such.ele\"")
                         .replace(0, 0, ""),
                     "no/such.node"});
}

TEST(CliBadInput, NaNInConfigValue)
{
    expect_rejected({"nan_value", with(kScene, "1e5", "nan"), "material.youngs_modulus"});
}

TEST(CliBadInput, MissingSceneFile)
{
    const std::string dir = fresh_dir("cli_missing_scene");
    const auto result = run_cli("simulate " + dir + "/none.toml -o " + dir + "/out.h5");
    EXPECT_NE(result.exit_code, 0);
    EXPECT_NE(result.output.find("none.toml"), std::string::npos) << result.output;
    EXPECT_FALSE(fs::exists(dir + "/out.h5"));
}

TEST(CliBadInput, CorruptDataset)
{
    const std::string dir = fresh_dir("cli_corrupt");
    write_file(dir + "/bad.h5", "this is not HDF5");
    auto result = run_cli("info " + dir + "/bad.h5");
    EXPECT_NE(result.exit_code, 0);
    EXPECT_NE(result.output.find("not an HDF5 file"), std::string::npos) << result.output;
    result = run_cli("info " + dir + "/missing.h5");
    EXPECT_NE(result.exit_code, 0);
    EXPECT_NE(result.output.find("does not exist"), std::string::npos) << result.output;
}

// Usage errors (an unknown option, a missing argument, a non-numeric value) exit 1 with
// the same `latentbench: error:` line as bad input; --help still exits 0.
TEST(Cli, UsageErrorsExitOneWithTheErrorPrefix)
{
    for (const char* args : {"simulate --no-such-option", "simulate", "rollout x.h5 -o y.h5 --frames many", "frobnicate"}) {
        const auto r = run_cli(args);
        EXPECT_EQ(r.exit_code, 1) << args << ": " << r.output;
        EXPECT_NE(r.output.find("latentbench: error:"), std::string::npos) << args << ": " << r.output;
    }
    EXPECT_EQ(run_cli("--help").exit_code, 0);
    EXPECT_EQ(run_cli("simulate --help").exit_code, 0);
}

TEST(Cli, SimulateWritesReadableDataset)
{
    const std::string dir = fresh_dir("cli_ok");
    write_file(dir + "/scene.toml", kScene);
    const auto result = run_cli("simulate " + dir + "/scene.toml -o " + dir + "/out.h5");
    ASSERT_EQ(result.exit_code, 0) << result.output;
    EXPECT_TRUE(fs::exists(dir + "/out.h5"));
    const auto info = run_cli("info " + dir + "/out.h5");
    EXPECT_EQ(info.exit_code, 0) << info.output;
    EXPECT_NE(info.output.find("tiny"), std::string::npos) << info.output;
}


// `run --check` prints the autoencoder each scene will train: the per-scene latent default
// (armadillo 12, cantilever 4) when the suite leaves `latent` unset, the suite's value when set.
TEST(Cli, RunCheckPrintsTheResolvedLatent)
{
    const std::string dir = fresh_dir("cli_run_check");
    const std::string scenes = std::string(LB_SOURCE_DIR) + "/experiments/scenes/";
    const std::string suite = "name = \"x\"\n[[integrators]]\nname = \"pca\"\nmethod = \"linear_pca\"\n"
                              "[[scenes]]\nscene = \"" + scenes + "armadillo.toml\"\nvariant = \"small\"\n"
                              "[[scenes]]\nscene = \"" + scenes + "cantilever.toml\"\nvariant = \"small\"\n"
                              "[[scenes]]\nscene = \"" + scenes + "cantilever.toml\"\nvariant = \"small\"\n"
                              "label = \"cantilever_6\"\n[scenes.autoencoder]\nlatent = 6\n";
    write_file(dir + "/suite.toml", suite);
    const auto r = run_cli("run " + dir + "/suite.toml -o " + dir + "/run --check");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    for (const char* line : {"armadillo_small: ", "cantilever_small: ", "cantilever_6: "}) EXPECT_NE(r.output.find(line), std::string::npos) << r.output;
    const auto latent_of = [&](const std::string& label) {
        const std::size_t at = r.output.find("  " + label + ": ");
        const std::size_t l = r.output.find("autoencoder latent ", at);
        return std::stoi(r.output.substr(l + 19));
    };
    EXPECT_EQ(latent_of("armadillo_small"), 12);
    EXPECT_EQ(latent_of("cantilever_small"), 4);
    EXPECT_EQ(latent_of("cantilever_6"), 6);
    EXPECT_FALSE(fs::exists(dir + "/run"));
}
// Methods from the command line through the registry: `fit --method linear_pca`, then
// `rollout` rebuilds the method from the artefact alone (no --ae needed); a bad option,
// an unknown method or key, a latent method without --ae and a non-artefact file are
// refused, naming the problem, with no output left behind.
TEST(Cli, FitThenRolloutThroughTheRegistry)
{
    const std::string dir = fresh_dir("cli_fit");
    write_file(dir + "/scene.toml", kScene);
    ASSERT_EQ(run_cli("simulate " + dir + "/scene.toml -o " + dir + "/data.h5").exit_code, 0);
    const auto fit = run_cli("fit --method linear_pca " + dir + "/data.h5 -o " + dir + "/pca.h5 --set dim=2");
    ASSERT_EQ(fit.exit_code, 0) << fit.output;
    EXPECT_NE(fit.output.find("d = 2"), std::string::npos) << fit.output;
    const auto roll = run_cli("rollout " + dir + "/data.h5 --integrator " + dir + "/pca.h5 --sequences all -o " + dir +
                              "/roll.h5");
    ASSERT_EQ(roll.exit_code, 0) << roll.output;
    EXPECT_NE(roll.output.find("linear_pca"), std::string::npos) << roll.output;
    EXPECT_TRUE(fs::exists(dir + "/roll.h5"));
    const auto reference = run_cli("rollout " + dir + "/data.h5 --method full_space --sequences all --frames 5 -o " +
                                   dir + "/ref.h5");
    ASSERT_EQ(reference.exit_code, 0) << reference.output;
    // --weights: an unknown format exits 1 naming it and the valid ones; a method whose rollout
    // runs no float inference network refuses a reduced one; f32 (the default) is accepted.
    const auto bad_weights = run_cli("rollout " + dir + "/data.h5 --integrator " + dir + "/pca.h5 --weights fp8 -o " +
                                     dir + "/w.h5");
    EXPECT_EQ(bad_weights.exit_code, 1) << bad_weights.output;
    EXPECT_NE(bad_weights.output.find("--weights: unknown weight format 'fp8' (expected f32, f16 or int8)"),
              std::string::npos) << bad_weights.output;
    EXPECT_FALSE(fs::exists(dir + "/w.h5"));
    const auto pca_f16 = run_cli("rollout " + dir + "/data.h5 --integrator " + dir + "/pca.h5 --weights f16 -o " + dir +
                                 "/w.h5");
    EXPECT_EQ(pca_f16.exit_code, 1) << pca_f16.output;
    EXPECT_NE(pca_f16.output.find("does not roll out through the float inference network"), std::string::npos)
        << pca_f16.output;
    EXPECT_FALSE(fs::exists(dir + "/w.h5"));
    const auto pca_f32 = run_cli("rollout " + dir + "/data.h5 --integrator " + dir + "/pca.h5 --weights f32 --frames 5 -o " +
                                 dir + "/w.h5");
    EXPECT_EQ(pca_f32.exit_code, 0) << pca_f32.output;

    const auto methods = run_cli("methods");
    ASSERT_EQ(methods.exit_code, 0) << methods.output;
    for (const char* name : {"latent_mlp", "linear_pca", "full_space"})
        EXPECT_NE(methods.output.find(name), std::string::npos) << methods.output;

    const auto bad_dim = run_cli("fit --method linear_pca " + dir + "/data.h5 -o " + dir + "/bad.h5 --set dim=-1");
    EXPECT_NE(bad_dim.exit_code, 0);
    EXPECT_NE(bad_dim.output.find("dim"), std::string::npos) << bad_dim.output;
    EXPECT_FALSE(fs::exists(dir + "/bad.h5"));
    const auto bad_key = run_cli("fit --method linear_pca " + dir + "/data.h5 -o " + dir + "/bad.h5 --set dimm=2");
    EXPECT_NE(bad_key.exit_code, 0);
    EXPECT_NE(bad_key.output.find("dimm"), std::string::npos) << bad_key.output;
    EXPECT_FALSE(fs::exists(dir + "/bad.h5"));
    const auto bad_method = run_cli("fit --method cubature " + dir + "/data.h5 -o " + dir + "/bad.h5");
    EXPECT_NE(bad_method.exit_code, 0);
    EXPECT_NE(bad_method.output.find("cubature"), std::string::npos) << bad_method.output;
    const auto no_ae = run_cli("fit --method latent_mlp " + dir + "/data.h5 -o " + dir + "/bad.h5");
    EXPECT_NE(no_ae.exit_code, 0);
    EXPECT_NE(no_ae.output.find("--ae is required"), std::string::npos) << no_ae.output;
    EXPECT_FALSE(fs::exists(dir + "/bad.h5"));
    const auto not_artefact = run_cli("rollout " + dir + "/data.h5 --integrator " + dir + "/data.h5 -o " + dir + "/x.h5");
    EXPECT_NE(not_artefact.exit_code, 0);
    EXPECT_NE(not_artefact.output.find("not a method artefact"), std::string::npos) << not_artefact.output;
    EXPECT_FALSE(fs::exists(dir + "/x.h5"));
}

} // namespace
} // namespace lb
