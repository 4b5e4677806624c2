#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "core/error.hpp"
#include "core/log.hpp"
#include "io/hdf5.hpp"
#include "baselines/builtin_methods.hpp"
#include "pipeline/experiment.hpp"
#include "pipeline/plan.hpp"
#include "support/cli_runner.hpp"

namespace lb {
namespace {

namespace fs = std::filesystem;

std::string write_experiment(const std::string& name, const std::string& text)
{
    return testing::write_in_fresh_dir("experiment_" + name, "suite.toml", text);
}

const char* kTiny = R"(
name = "tiny"
[autoencoder]
hidden = [16]
pca = 8
epochs = 20
batch = 16
learning_rate = 1.0e-3
[training]
epochs = 5
hidden = [16]
learning_rate = 1.0e-3
[[integrators]]
name = "ours"
[[integrators]]
name = "sup"
loss = "supervised_l2"
[[integrators]]
name = "pca"
method = "linear_pca"
[[scenes]]
scene = "experiments/scenes/cantilever.toml"
variant = "small"
[evaluation]
frames = 50
[outputs]
plots = false
[[ablations]]
name = "supervision"
methods = ["ours", "sup"]
)";

TEST(Experiment, EveryShippedSuiteIsValid)
{
    // experiments/ and the users' examples (tolerances/ and scenes/ hold no suites)
    int count = 0, examples = 0;
    for (const char* folder : {"experiments", "experiments/examples"}) {
        for (const auto& entry : fs::directory_iterator(fs::path(LB_SOURCE_DIR) / folder)) {
            if (entry.path().extension() != ".toml") continue;
            const ExperimentConfig ex = load_experiment(entry.path().string(), builtin_methods());
            EXPECT_FALSE(ex.scenes.empty()) << entry.path();
            EXPECT_FALSE(ex.scenes.front().methods.empty()) << entry.path();
            ++count;
            examples += std::string(folder) == "experiments/examples";
        }
    }
    EXPECT_GE(count, 9);
    EXPECT_GE(examples, 1);
}

TEST(Experiment, RejectsBadKeysByName)
{
    std::string text = kTiny;
    text.replace(text.find("epochs = 5"), 10, "epoch = 5");
    try {
        load_experiment(write_experiment("bad_key", text), builtin_methods());
        FAIL() << "expected ConfigError";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("training.epoch"), std::string::npos) << e.what();
    }
    text = kTiny;
    text.replace(text.find("\"ours\", \"sup\""), 13, "\"ours\", \"nope\"");
    try {
        load_experiment(write_experiment("bad_ablation", text), builtin_methods());
        FAIL() << "expected ConfigError";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("nope"), std::string::npos) << e.what();
    }
    // A linear PCA entry takes no training keys; an unknown method is named.
    text = kTiny;
    text.replace(text.find("method = \"linear_pca\""), 21, "method = \"linear_pca\"\nepochs = 3");
    try {
        load_experiment(write_experiment("pca_training_key", text), builtin_methods());
        FAIL() << "expected ConfigError";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("epochs"), std::string::npos) << e.what();
    }
    // Names and labels become file names: a path or a shell fragment is refused by name.
    for (const std::string& bad : {std::string("../escaped"), std::string("x';touch PWNED;echo '"), std::string(".hidden")}) {
        text = kTiny;
        text.replace(text.find("variant = \"small\""), 17, "variant = \"small\"\nlabel = \"" + bad + "\"");
        try {
            load_experiment(write_experiment("bad_label", text), builtin_methods());
            FAIL() << "expected ConfigError for label " << bad;
        } catch (const ConfigError& e) {
            EXPECT_NE(std::string(e.what()).find("scenes[0].label"), std::string::npos) << e.what();
        }
    }
    text = kTiny;
    text.replace(text.find("name = \"sup\""), 12, "name = \"a/b\"");
    EXPECT_THROW(load_experiment(write_experiment("bad_name", text), builtin_methods()), ConfigError);
    // A scene may run a subset of the integrators; a name that no entry has is refused.
    text = kTiny;
    text.replace(text.find("variant = \"small\""), 17, "variant = \"small\"\nintegrators = [\"ours\", \"pca\"]");
    {
        const ExperimentConfig subset = load_experiment(write_experiment("scene_subset", text), builtin_methods());
        ASSERT_EQ(subset.scenes[0].methods.size(), 2u);
        EXPECT_EQ(subset.scenes[0].methods[0].name, "ours");
        EXPECT_EQ(subset.scenes[0].methods[1].name, "pca");
    }
    text = kTiny;
    text.replace(text.find("variant = \"small\""), 17, "variant = \"small\"\nintegrators = [\"ours\", \"nope\"]");
    try {
        load_experiment(write_experiment("scene_subset_bad", text), builtin_methods());
        FAIL() << "expected ConfigError";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("nope"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("integrators"), std::string::npos) << e.what();
    }
    // The autoencoder's frame (issue 14): "translation" or "rigid", anything else named.
    text = kTiny;
    text.replace(text.find("pca = 8"), 7, "pca = 8\nframe = \"rigid\"");
    EXPECT_EQ(load_experiment(write_experiment("rigid_frame", text), builtin_methods()).scenes[0].autoencoder.frame,
              EncodingFrame::rigid);
    text = kTiny;
    text.replace(text.find("pca = 8"), 7, "pca = 8\nframe = \"rotation\"");
    try {
        load_experiment(write_experiment("bad_frame", text), builtin_methods());
        FAIL() << "expected ConfigError";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("autoencoder.frame"), std::string::npos) << e.what();
    }
    // Physics fine-tuning of the autoencoder (issue 14): keys read, range-checked, named.
    text = kTiny;
    text.replace(text.find("pca = 8"), 7, "pca = 8\nphysics_epochs = 20\nphysics_weight = 0.25");
    {
        const AutoencoderOptions ao =
            load_experiment(write_experiment("physics_ae", text), builtin_methods()).scenes[0].autoencoder;
        EXPECT_EQ(ao.physics_epochs, 20);
        EXPECT_EQ(ao.physics_weight, 0.25);
        // In the stage key only when on, so every earlier autoencoder stays cached.
        AutoencoderOptions off = ao;
        off.physics_epochs = 0;
        AutoencoderOptions off_weight = off;
        off_weight.physics_weight = 0.5;
        EXPECT_NE(autoencoder_stage_key("sim", ao), autoencoder_stage_key("sim", off));
        EXPECT_EQ(autoencoder_stage_key("sim", off), autoencoder_stage_key("sim", off_weight));
        AutoencoderOptions heavier = ao;
        heavier.physics_weight = 1.0;
        EXPECT_NE(autoencoder_stage_key("sim", ao), autoencoder_stage_key("sim", heavier));
    }
    for (const char* bad : {"physics_epochs = -3", "physics_weight = -1.0", "physics_learning_rate = 0.0",
                            "physics_weight = inf"}) {
        text = kTiny;
        text.replace(text.find("pca = 8"), 7, std::string("pca = 8\n") + bad);
        try {
            load_experiment(write_experiment("bad_physics_ae", text), builtin_methods());
            ADD_FAILURE() << "expected ConfigError for " << bad;
        } catch (const ConfigError& e) {
            const std::string key = std::string(bad).substr(0, std::string(bad).find(' '));
            EXPECT_NE(std::string(e.what()).find("autoencoder." + key), std::string::npos) << e.what();
        }
    }
    text = kTiny;
    text.replace(text.find("method = \"linear_pca\""), 21, "method = \"cubature\"");
    try {
        load_experiment(write_experiment("bad_method", text), builtin_methods());
        FAIL() << "expected ConfigError";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("cubature"), std::string::npos) << e.what();
    }
}

TEST(Experiment, SecondRunReusesEveryStageAndForceRedoesOne)
{
    set_log_level(LogLevel::Quiet);
    const std::string path = write_experiment("cache", kTiny);
    const ExperimentConfig ex = load_experiment(path, builtin_methods());
    RunOptions options;
    options.output_dir = fs::path(path).parent_path().string() + "/run";
    const RunResult first = run_experiment(ex, options);
    // simulate, autoencoder, 2 integrators + 1 PCA subspace, 4 rollouts (3 + full space)
    EXPECT_EQ(first.stages_run, 9);
    EXPECT_EQ(first.stages_cached, 0);
    EXPECT_TRUE(fs::exists(options.output_dir + "/tables/methods_cantilever_small.md"));
    EXPECT_TRUE(fs::exists(options.output_dir + "/tables/ablation_supervision_cantilever_small.tex"));
    EXPECT_TRUE(fs::exists(options.output_dir + "/tables/table1_timings.csv"));
    EXPECT_TRUE(fs::exists(options.output_dir + "/run.log"));
    {
        std::ifstream in(options.output_dir + "/tables/methods_cantilever_small.md");
        const std::string table((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        EXPECT_NE(table.find("| pca "), std::string::npos) << table;
        EXPECT_NE(table.find("linear PCA, d = 4"), std::string::npos) << table;
        // Training and test windows apart (issue 10).
        EXPECT_NE(table.find("| train (frames 2-"), std::string::npos) << table;
        EXPECT_NE(table.find("| test (frames >= "), std::string::npos) << table;
    }

    const RunResult second = run_experiment(ex, options);
    EXPECT_EQ(second.stages_run, 0);
    EXPECT_EQ(second.stages_cached, 9);

    options.force = {"rollouts"};
    const RunResult forced = run_experiment(ex, options);
    EXPECT_EQ(forced.stages_run, 4);
    EXPECT_EQ(forced.stages_cached, 5);

    options.force = {"everything"};
    EXPECT_THROW(run_experiment(ex, options), ConfigError);
}

// Videos (issue 16): `[outputs] videos = true` writes one MP4 per scene into videos/,
// cached like a stage keyed on the rollouts; off by default; bad video_frames refused.
TEST(Experiment, VideosSwitchWritesOneMp4PerSceneAndCachesIt)
{
    if (!fs::exists("/usr/bin/ffmpeg")) GTEST_SKIP() << "ffmpeg not installed (Debian package ffmpeg)";
    set_log_level(LogLevel::Quiet);
    std::string text = kTiny;
    text.replace(text.find("plots = false"), 13, "plots = false\nvideos = true\nvideo_frames = 12");
    const std::string path = write_experiment("videos", text);
    const ExperimentConfig ex = load_experiment(path, builtin_methods());
    EXPECT_TRUE(ex.videos);
    EXPECT_EQ(ex.video_frames, 12);
    EXPECT_FALSE(load_experiment(write_experiment("videos_default", kTiny), builtin_methods()).videos);
    RunOptions options;
    options.output_dir = fs::path(path).parent_path().string() + "/run";
    const RunResult first = run_experiment(ex, options);
    EXPECT_EQ(first.stages_run, 10);  // the 9 of the tiny suite and one video
    ASSERT_EQ(first.videos.size(), 1u);
    EXPECT_EQ(first.videos[0], options.output_dir + "/videos/cantilever_small.mp4");
    EXPECT_GT(fs::file_size(first.videos[0]), 1000u);

    const RunResult second = run_experiment(ex, options);
    EXPECT_EQ(second.stages_run, 0);
    EXPECT_EQ(second.stages_cached, 10);
    options.force = {"videos"};
    EXPECT_EQ(run_experiment(ex, options).stages_run, 1);

    for (const char* bad : {"video_frames = 1", "video_frames = 0", "videos = 1"}) {
        std::string t = kTiny;
        t.replace(t.find("plots = false"), 13, std::string("plots = false\n") + bad);
        EXPECT_THROW(load_experiment(write_experiment("bad_videos", t), builtin_methods()), ConfigError) << bad;
    }
}

std::string read_all(const std::string& path);

// The error decomposition in a suite (issue 14): `[outputs] diagnose = true` writes
// tables/diagnose_<scene>.{md,csv,tex} with the autoencoder's rows, fulton_full as the
// manifold-optimal step, every other latent method's one step and rollout (the full-space
// reference left out); cached like a stage; bad strides refused.
TEST(Experiment, DiagnoseSwitchWritesTheErrorDecompositionPerScene)
{
    set_log_level(LogLevel::Quiet);
    std::string text = kTiny;
    text.replace(text.find("plots = false"), 13, "plots = false\ndiagnose = true\ndiagnose_stride = 25");
    text.replace(text.find("[[scenes]]"), 10, "[[integrators]]\nname = \"oracle\"\nmethod = \"fulton_full\"\n[[scenes]]");
    const std::string path = write_experiment("diagnose", text);
    const ExperimentConfig ex = load_experiment(path, builtin_methods());
    EXPECT_TRUE(ex.diagnose);
    EXPECT_EQ(ex.diagnose_stride, 25);
    EXPECT_FALSE(load_experiment(write_experiment("diagnose_default", kTiny), builtin_methods()).diagnose);
    RunOptions options;
    options.output_dir = fs::path(path).parent_path().string() + "/run";
    const RunResult first = run_experiment(ex, options);
    const std::string table = options.output_dir + "/tables/diagnose_cantilever_small";
    for (const char* ext : {".md", ".csv", ".tex"}) EXPECT_TRUE(fs::exists(table + ext)) << ext;
    EXPECT_NE(std::find(first.tables.begin(), first.tables.end(), table + ".md"), first.tables.end());
    const std::string md = read_all(table + ".md");
    // one Markdown row with this stage and this method (columns are padded)
    auto has_row = [&](const std::string& stage, const std::string& method) {
        std::istringstream lines(md);
        for (std::string line; std::getline(lines, line);) {
            if (line.rfind("| " + stage, 0) == 0 && line.find("| " + method + " ") != std::string::npos) return true;
        }
        return false;
    };
    EXPECT_TRUE(has_row("(a, b) projection", "—")) << md;
    EXPECT_TRUE(has_row("(c) manifold-optimal step", "oracle")) << md;
    for (const char* m : {"ours", "sup", "pca"}) EXPECT_TRUE(has_row("(d) one step", m)) << m << "\n" << md;
    for (const char* m : {"ours", "oracle"}) EXPECT_TRUE(has_row("(e) rollout", m)) << m << "\n" << md;
    // the manifold-optimal step comes before the one steps it bounds
    EXPECT_LT(md.find("(c) manifold-optimal step"), md.find("(d) one step")) << md;
    EXPECT_EQ(md.find("full_space"), std::string::npos) << md;

    EXPECT_EQ(run_experiment(ex, options).stages_run, 0);
    options.force = {"diagnose"};
    EXPECT_EQ(run_experiment(ex, options).stages_run, 1);

    for (const char* bad : {"diagnose_stride = 0", "diagnose = 1"}) {
        std::string t = kTiny;
        t.replace(t.find("plots = false"), 13, std::string("plots = false\n") + bad);
        EXPECT_THROW(load_experiment(write_experiment("bad_diagnose", t), builtin_methods()), ConfigError) << bad;
    }
}


// Seeds (issue 10): every learned method is fitted and rolled out once per seed, methods
// without a seed once; the tables give statistics over the seeds.
TEST(Experiment, SeedsFitEveryLearnedMethodOncePerSeed)
{
    set_log_level(LogLevel::Quiet);
    std::string text = kTiny;
    text.replace(text.find("name = \"tiny\"\n"), 14, "name = \"tiny\"\nseeds = [0, 7]\n");
    // An entry may run a subset of the suite's seeds (a budget for an expensive baseline).
    text.replace(text.find("loss = \"supervised_l2\""), 22, "loss = \"supervised_l2\"\nseeds = [7]");
    const std::string path = write_experiment("seeds", text);
    const ExperimentConfig ex = load_experiment(path, builtin_methods());
    ASSERT_EQ(ex.seeds.size(), 2u);
    ASSERT_EQ(ex.scenes[0].methods[1].seeds, std::vector<std::uint64_t>{7});
    RunOptions options;
    options.output_dir = fs::path(path).parent_path().string() + "/run";
    const RunResult run = run_experiment(ex, options);
    // simulate, autoencoder, ours × 2 seeds + sup × 1 + pca, their 4 rollouts + full space
    EXPECT_EQ(run.stages_run, 11);
    const std::string dir = options.output_dir + "/cantilever_small";
    for (const char* f : {"/integrators/ours.seed0.h5", "/integrators/ours.seed7.h5", "/integrators/sup.seed7.h5",
                          "/integrators/pca.h5", "/rollouts/ours.seed7.h5", "/rollouts/pca.h5"}) {
        EXPECT_TRUE(fs::exists(dir + f)) << f;
    }
    EXPECT_FALSE(fs::exists(dir + "/integrators/pca.seed0.h5"));
    EXPECT_FALSE(fs::exists(dir + "/integrators/sup.seed0.h5"));
    const std::string table = read_all(options.output_dir + "/tables/methods_cantilever_small.md");
    EXPECT_NE(table.find("median [min, max] over the 2 seeds"), std::string::npos) << table;
    EXPECT_NE(table.find("| ours "), std::string::npos) << table;
    EXPECT_NE(table.find(" epochs, "), std::string::npos) << table;  // the training budget column

    for (const char* bad : {"seeds = [-1]\n", "seeds = [1, 1]\n", "seeds = []\n"}) {
        std::string t = kTiny;
        t.replace(t.find("name = \"tiny\"\n"), 14, std::string("name = \"tiny\"\n") + bad);
        EXPECT_THROW(load_experiment(write_experiment("bad_seeds", t), builtin_methods()), ConfigError) << bad;
    }
    // An entry's seeds must be the suite's (and the suite must have some).
    for (const char* suite : {"seeds = [0, 7]\n", ""}) {
        for (const char* entry : {"seeds = [3]", "seeds = [7, 7]", "seeds = []"}) {
            std::string t = kTiny;
            t.replace(t.find("name = \"tiny\"\n"), 14, std::string("name = \"tiny\"\n") + suite);
            t.replace(t.find("loss = \"supervised_l2\""), 22, std::string("loss = \"supervised_l2\"\n") + entry);
            try {
                load_experiment(write_experiment("bad_entry_seeds", t), builtin_methods());
                ADD_FAILURE() << "expected ConfigError for " << suite << entry;
            } catch (const ConfigError& e) {
                EXPECT_NE(std::string(e.what()).find("integrators[1].seeds"), std::string::npos) << e.what();
            }
        }
    }
}

// A subset of a suite (`run --scene/--integrator`) shares the suite's run directory and
// cache: the paper's method first, the rest later, nothing computed twice.
TEST(Experiment, SubsetRunSharesTheCacheWithTheWholeSuite)
{
    set_log_level(LogLevel::Quiet);
    const std::string path = write_experiment("subset", kTiny);
    const ExperimentConfig ex = load_experiment(path, builtin_methods());
    const ExperimentConfig only_ours = select_subset(ex, {}, {"ours"});
    ASSERT_EQ(only_ours.scenes.size(), 1u);
    ASSERT_EQ(only_ours.scenes[0].methods.size(), 1u);
    EXPECT_EQ(only_ours.scenes[0].methods[0].name, "ours");
    EXPECT_TRUE(only_ours.ablations.empty());  // "supervision" needs sup
    EXPECT_EQ(select_subset(ex, {}, {"ours", "sup"}).ablations.size(), 1u);
    EXPECT_NE(only_ours.toml_text.find("# subset run: integrators ours;"), std::string::npos);
    RunOptions options;
    options.output_dir = fs::path(path).parent_path().string() + "/run";
    // simulate, autoencoder, ours, its rollout, full space
    EXPECT_EQ(run_experiment(only_ours, options).stages_run, 5);
    const RunResult whole = run_experiment(ex, options);
    EXPECT_EQ(whole.stages_run, 4);  // sup and pca, fitted and rolled out
    EXPECT_GE(whole.stages_cached, 5);
    for (const auto& bad : std::vector<std::pair<std::vector<std::string>, std::vector<std::string>>>{
             {{"cloth_small"}, {}}, {{}, {"nope"}}}) {
        try {
            select_subset(ex, bad.first, bad.second);
            ADD_FAILURE() << "expected ConfigError";
        } catch (const ConfigError& e) {
            const std::string what = e.what();
            EXPECT_TRUE(what.find("cloth_small") != std::string::npos || what.find("nope") != std::string::npos) << what;
        }
    }
}

long long artefact_flag(const std::string& file, const char* key) { return h5::File::open(file).attribute_int("/", key); }

std::string read_all(const std::string& path)
{
    std::ifstream in(path);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// The stale-checkpoint bug: a finished integrator's checkpoint used to be resumed
// whenever its option string matched, so retraining the autoencoder or forcing the
// integrators stage trained zero epochs and saved the old network. Now a changed
// autoencoder sets the checkpoint aside, and --force trains from scratch.
TEST(Experiment, ChangedAutoencoderOrForceNeverResumesAFinishedCheckpoint)
{
    set_log_level(LogLevel::Quiet);
    std::string text = kTiny;
    text.replace(text.find("[[integrators]]\nname = \"pca\""), std::string::npos,
                 "[[scenes]]\nscene = \"experiments/scenes/cantilever.toml\"\nvariant = \"small\"\n[evaluation]\nframes = 20\n"
                 "full_space = false\n[outputs]\nplots = false\npaper_tables = false\n");
    const std::string path = write_experiment("stale", text);
    RunOptions options;
    options.output_dir = fs::path(path).parent_path().string() + "/run";
    const std::string ours = options.output_dir + "/cantilever_small/integrators/ours.h5";
    run_experiment(load_experiment(path, builtin_methods()), options);
    EXPECT_EQ(artefact_flag(ours, "resumed"), 0);
    EXPECT_TRUE(fs::exists(options.output_dir + "/cantilever_small/integrators/ours.checkpoint.h5"));

    // The autoencoder is retrained with another seed: every integrator retrains from
    // scratch. (Training it longer is not enough here: early stopping restores the same
    // best weights on this tiny problem, and then resuming is right.)
    std::string reseeded = text;
    reseeded.replace(reseeded.find("epochs = 20"), 11, "epochs = 20\nseed = 3");
    std::ofstream(path) << reseeded;
    const RunResult changed = run_experiment(load_experiment(path, builtin_methods()), options);
    EXPECT_EQ(changed.stages_run, 5);  // autoencoder, 2 integrators, 2 rollouts
    EXPECT_EQ(artefact_flag(ours, "resumed"), 0);
    EXPECT_EQ(artefact_flag(ours, "epochs_run"), 5);
    EXPECT_GT(h5::File::open(ours).attribute_double("/", "final_loss"), 0.0);
    EXPECT_TRUE(fs::exists(options.output_dir + "/cantilever_small/integrators/ours.checkpoint.h5.stale.1"));
    EXPECT_NE(read_all(options.output_dir + "/run.log").find("autoencoder differs"), std::string::npos);

    // --force integrators: trains again from scratch, although the checkpoint matches.
    options.force = {"integrators"};
    run_experiment(load_experiment(path, builtin_methods()), options);
    EXPECT_EQ(artefact_flag(ours, "resumed"), 0);
    EXPECT_EQ(artefact_flag(ours, "epochs_run"), 5);
    // The second set-aside gets a name of its own: the first is kept.
    EXPECT_TRUE(fs::exists(options.output_dir + "/cantilever_small/integrators/ours.checkpoint.h5.stale.1"));
    EXPECT_TRUE(fs::exists(options.output_dir + "/cantilever_small/integrators/ours.checkpoint.h5.stale.2"));

    // Unforced and unchanged: nothing runs.
    options.force.clear();
    EXPECT_EQ(run_experiment(load_experiment(path, builtin_methods()), options).stages_run, 0);
}

} // namespace
} // namespace lb
