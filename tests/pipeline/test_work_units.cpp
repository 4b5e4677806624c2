// Work units, sweeps and the merge (issue 15): `plan`, `run --unit`, `run --merge`.
#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>

#include <unistd.h>

#include "baselines/builtin_methods.hpp"
#include "baselines/linear_pca/linear_pca_method.hpp"
#include "core/error.hpp"
#include "core/hash.hpp"
#include "core/log.hpp"
#include "io/table.hpp"
#include "pipeline/experiment.hpp"
#include "methods/registry.hpp"
#include "pipeline/plan.hpp"
#include "support/cli_runner.hpp"

namespace lb {
namespace {

namespace fs = std::filesystem;
using testing::fresh_dir;
using testing::write_in_fresh_dir;
using testing::run_cli;
using testing::run_program;

/// A tiny suite: the self-supervised MLP and linear PCA on the small cantilever, with a
/// sweep of the training noise × two seeds (4 points).
const char* kSwept = R"(
name = "swept"
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
name = "pca"
method = "linear_pca"
[[scenes]]
scene = "experiments/scenes/cantilever.toml"
variant = "small"
[evaluation]
frames = 40
[outputs]
plots = false
[sweep]
"training.noise_fraction" = [0.0, 0.2]
seeds = [3, 4]
)";

std::string write_suite(const std::string& name, const std::string& text)
{
    return write_in_fresh_dir("units_" + name, "suite.toml", text);
}

std::string read_all(const std::string& path)
{
    std::ifstream in(path);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string replaced(std::string text, const std::string& from, const std::string& to)
{
    const size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
    return text;
}

TEST(WorkUnits, PlanExpandsTheSweepAndSharesWhatItDoesNotTouch)
{
    const std::string path = write_suite("plan", kSwept);
    const ExperimentConfig ex = load_experiment(path, builtin_methods());
    ASSERT_EQ(ex.sweep.size(), 2u);
    EXPECT_EQ(ex.sweep[0].key, "training.noise_fraction");  // the file's order, not the key order
    ASSERT_EQ(ex.points.size(), 4u);
    EXPECT_EQ(ex.points[1].point_label, "p01");
    EXPECT_EQ(ex.points[1].point_text, "training.noise_fraction=0.0, seeds=4");  // the first axis varies slowest
    EXPECT_EQ(ex.points[2].point_text, "training.noise_fraction=0.2, seeds=3");

    const ExperimentPlan plan = plan_experiment(ex, fresh_dir("units_plan_run"));
    // 1 scene; ours: 4 fits + 4 rollouts (one per point); pca (no seed, no training key):
    // 1 fit + 1 rollout shared by every point; full_space: 1 rollout.
    EXPECT_EQ(plan.points, 4u);
    ASSERT_EQ(plan.units.size(), 12u);
    EXPECT_EQ(plan.levels(), 3);
    const Unit* fit = plan.find("fit.cantilever_small.ours.p02.seed3");
    ASSERT_NE(fit, nullptr);
    EXPECT_EQ(fit->depends_on, std::vector<std::string>{"scene.cantilever_small"});
    EXPECT_EQ(fit->level, 1);
    const Unit* eval = plan.find("eval.cantilever_small.ours.p02.seed3");
    ASSERT_NE(eval, nullptr);
    EXPECT_EQ(eval->depends_on, std::vector<std::string>{fit->id});
    EXPECT_EQ(eval->level, 2);
    const Unit* pca = plan.find("eval.cantilever_small.pca");
    ASSERT_NE(pca, nullptr);
    EXPECT_TRUE(pca->point.empty());
    const Unit* reference = plan.find("eval.cantilever_small.full_space");
    ASSERT_NE(reference, nullptr);
    EXPECT_EQ(reference->level, 1);  // nothing to fit: right after the scene
    // Distinct points have distinct keys (the swept value reaches the method's options).
    EXPECT_NE(plan.find("fit.cantilever_small.ours.p00.seed3")->outputs[0].key,
              plan.find("fit.cantilever_small.ours.p02.seed3")->outputs[0].key);
    // Array indices number each level's units from 0.
    for (int level = 0; level < plan.levels(); ++level) {
        int next = 0;
        for (const Unit& u : plan.units) {
            if (u.level == level) {
                EXPECT_EQ(u.array_index, next++) << u.id;
            }
        }
    }

    // The CLI prints the count before anything runs and writes one JSON line per unit.
    const std::string run_dir = fresh_dir("units_plan_cli");
    const auto r = run_cli("plan " + path + " -o " + run_dir);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("4 sweep points, 12 work units (1 scene, 5 fit, 6 eval) in 3 levels"), std::string::npos)
        << r.output;
    const std::string manifest = read_all(run_dir + "/manifest.jsonl");
    std::istringstream lines(manifest);
    int count = 0;
    for (std::string line; std::getline(lines, line); ++count) {
        EXPECT_EQ(line.front(), '{');
        EXPECT_NE(line.find("\"depends_on\":["), std::string::npos) << line;
    }
    EXPECT_EQ(count, 12);
    EXPECT_NE(manifest.find("\"id\":\"eval.cantilever_small.ours.p03.seed4\",\"kind\":\"eval\",\"level\":2"),
              std::string::npos);
    EXPECT_NE(manifest.find("\"sweep\":{\"training.noise_fraction\":\"0.2\",\"seeds\":\"4\"}"), std::string::npos);
    EXPECT_FALSE(fs::exists(run_dir + "/cantilever_small"));  // nothing ran
}

TEST(WorkUnits, AutoencoderSweepPlansOneSceneUnitPerAutoencoder)
{
    std::string text = replaced(kSwept, "seeds = [3, 4]", "\"autoencoder.epochs\" = [10, 20]");
    const ExperimentPlan plan =
        plan_experiment(load_experiment(write_suite("ae_sweep", text), builtin_methods()), fresh_dir("units_ae_run"));
    ASSERT_NE(plan.find("scene.cantilever_small.p00"), nullptr);
    ASSERT_NE(plan.find("scene.cantilever_small.p01"), nullptr);
    EXPECT_EQ(plan.find("scene.cantilever_small.p02"), nullptr);  // p02 trains the autoencoder p00 trains
    EXPECT_EQ(plan.find("fit.cantilever_small.ours.p02")->depends_on,
              std::vector<std::string>{"scene.cantilever_small.p00"});
}

/// The index of a CSV table's column (a test failure if it has none).
size_t column_of(const Table& csv, const std::string& name)
{
    const auto at = std::find(csv.columns.begin(), csv.columns.end(), name);
    EXPECT_NE(at, csv.columns.end()) << name;
    return size_t(at - csv.columns.begin());
}

/// kSwept without its sweep, with fulton_full (no seed of its own, but it steps in the
/// autoencoder) and `[seeds] values = [3, 4]` of the given scope.
std::string seed_scope_suite(const std::string& scope)
{
    std::string text = replaced(kSwept, "[sweep]\n\"training.noise_fraction\" = [0.0, 0.2]\nseeds = [3, 4]\n",
                                "[seeds]\nvalues = [3, 4]\nscope = \"" + scope + "\"\n");
    return replaced(text, "[[scenes]]", "[[integrators]]\nname = \"exact\"\nmethod = \"fulton_full\"\n[[scenes]]");
}

TEST(WorkUnits, AutoencoderSeedScopePlansOneAutoencoderPerSeed)
{
    const ExperimentPlan plan = plan_experiment(
        load_experiment(write_suite("ae_scope", seed_scope_suite("autoencoder")), builtin_methods()),
        fresh_dir("units_ae_scope_run"));
    const Unit* s3 = plan.find("scene.cantilever_small.seed3");
    const Unit* s4 = plan.find("scene.cantilever_small.seed4");
    ASSERT_NE(s3, nullptr);
    ASSERT_NE(s4, nullptr);
    EXPECT_EQ(plan.find("scene.cantilever_small"), nullptr);
    EXPECT_EQ(s3->outputs[0].key, s4->outputs[0].key);  // one dataset
    EXPECT_NE(s3->outputs[1].key, s4->outputs[1].key);  // two autoencoders
    EXPECT_EQ(plan.find("fit.cantilever_small.ours.seed3")->depends_on, std::vector<std::string>{s3->id});
    EXPECT_EQ(plan.find("fit.cantilever_small.ours.seed4")->depends_on, std::vector<std::string>{s4->id});
    // a method without a seed of its own runs once per autoencoder if it uses one ...
    ASSERT_NE(plan.find("eval.cantilever_small.exact.seed3"), nullptr);
    EXPECT_EQ(plan.find("eval.cantilever_small.exact.seed4")->scene_unit, s4->id);
    // ... and once if it does not (linear PCA of the full-space data, the reference)
    ASSERT_NE(plan.find("eval.cantilever_small.pca"), nullptr);
    EXPECT_EQ(plan.find("eval.cantilever_small.pca.seed4"), nullptr);
    ASSERT_NE(plan.find("eval.cantilever_small.full_space"), nullptr);
    for (const PlannedRow& row : plan.rows) {
        if (row.name == "exact" || row.name == "ours") {
            EXPECT_EQ(row.seeds, (std::vector<std::uint64_t>{3, 4})) << row.name;
        }
        if (row.name == "pca" || row.name == "full_space") {
            EXPECT_TRUE(row.seeds.empty()) << row.name;
        }
    }

    const ExperimentPlan shared = plan_experiment(
        load_experiment(write_suite("int_scope", seed_scope_suite("integrator")), builtin_methods()),
        fresh_dir("units_int_scope_run"));
    ASSERT_NE(shared.find("scene.cantilever_small"), nullptr);
    EXPECT_EQ(shared.find("scene.cantilever_small.seed3"), nullptr);
    EXPECT_EQ(shared.find("fit.cantilever_small.ours.seed4")->depends_on,
              std::vector<std::string>{"scene.cantilever_small"});
    EXPECT_NE(shared.find("eval.cantilever_small.exact"), nullptr);  // one autoencoder: one exact step

    try {
        load_experiment(write_suite("bad_scope", seed_scope_suite("both")), builtin_methods());
        ADD_FAILURE() << "an unknown scope was accepted";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("seeds.scope"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("unknown scope 'both'"), std::string::npos) << e.what();
    }
}

TEST(WorkUnits, AutoencoderSeedScopeRunTrainsOneAutoencoderPerSeedAndSaysSo)
{
    const std::string path = write_suite("ae_scope_run", seed_scope_suite("autoencoder"));
    const std::string run_dir = fresh_dir("units_ae_scope_runs");
    const auto run = run_cli("run " + path + " -o " + run_dir);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    // the dataset is simulated once and copied; each seed has its own autoencoder
    EXPECT_NE(run.output.find("full-space dataset copied from scene.cantilever_small.seed3"), std::string::npos)
        << run.output;
    const std::string ae3 = run_dir + "/cantilever_small.seed3/ae.h5", ae4 = run_dir + "/cantilever_small.seed4/ae.h5";
    ASSERT_TRUE(fs::exists(ae3));
    ASSERT_TRUE(fs::exists(ae4));
    EXPECT_NE(read_all(ae3), read_all(ae4));
    EXPECT_EQ(read_all(run_dir + "/cantilever_small.seed3/data.h5"), read_all(run_dir + "/cantilever_small.seed4/data.h5"));
    const std::string md = read_all(run_dir + "/tables/methods_cantilever_small.md");
    EXPECT_NE(md.find("Seed scope autoencoder: each seed trained its own autoencoder"), std::string::npos);
    // fulton_full's row holds one run per autoencoder
    // (read as a parser would: the exact method's label holds a quoted comma)
    const Table csv = read_csv(run_dir + "/tables/methods_cantilever_small.csv");
    const auto column = [&](const std::string& name) { return column_of(csv, name); };
    const size_t method = column("method"), n_seeds = column("n_seeds");
    int exact_rows = 0;
    for (const auto& row : csv.rows) {
        if (row.at(method).text != "exact") continue;
        ++exact_rows;
        ASSERT_TRUE(row.at(n_seeds).value.has_value());
        EXPECT_EQ(*row.at(n_seeds).value, 2.0);
    }
    EXPECT_EQ(exact_rows, 2);  // training and test windows
    EXPECT_NE(read_all(run_dir + "/provenance.json").find("\"seed_scope\": \"autoencoder\""), std::string::npos);
}

/// kSwept without its sweep, plus `ours` again under other inference weights.
std::string weights_suite(const std::string& extra_entries)
{
    const std::string text = replaced(kSwept, "[sweep]\n\"training.noise_fraction\" = [0.0, 0.2]\nseeds = [3, 4]\n", "");
    return replaced(text, "[[scenes]]", extra_entries + "[[scenes]]");
}

const char* kWeightEntries = "[[integrators]]\nname = \"ours_f16\"\nweights = \"f16\"\n"
                             "[[integrators]]\nname = \"ours_int8\"\nweights = \"int8\"\n";

TEST(WorkUnits, WeightsEntryRollsOutTheSameFitUnderItsOwnKey)
{
    const ExperimentPlan plain = plan_experiment(
        load_experiment(write_suite("weights_plain", weights_suite("")), builtin_methods()), fresh_dir("units_weights_plain"));
    const ExperimentPlan plan = plan_experiment(
        load_experiment(write_suite("weights", weights_suite(kWeightEntries)), builtin_methods()), fresh_dir("units_weights"));
    ASSERT_NE(plan.find("fit.cantilever_small.ours"), nullptr);
    EXPECT_EQ(plan.find("fit.cantilever_small.ours_f16"), nullptr);  // no second training
    EXPECT_EQ(plan.find("fit.cantilever_small.ours_int8"), nullptr);
    const Unit* f32 = plan.find("eval.cantilever_small.ours");
    const Unit* f16 = plan.find("eval.cantilever_small.ours_f16");
    const Unit* int8 = plan.find("eval.cantilever_small.ours_int8");
    ASSERT_NE(f32, nullptr);
    ASSERT_NE(f16, nullptr);
    ASSERT_NE(int8, nullptr);
    EXPECT_EQ(f16->fit_unit, "fit.cantilever_small.ours");
    EXPECT_EQ(f16->depends_on, std::vector<std::string>{"fit.cantilever_small.ours"});
    EXPECT_EQ(f16->level, 2);
    EXPECT_NE(f16->outputs[0].key, f32->outputs[0].key);
    EXPECT_NE(int8->outputs[0].key, f16->outputs[0].key);
    EXPECT_NE(f16->outputs[0].file, f32->outputs[0].file);
    // f32 (the default) keeps the key it had before the weights key existed: caches stay valid
    EXPECT_EQ(f32->outputs[0].key, plain.find("eval.cantilever_small.ours")->outputs[0].key);

    const std::string run_dir = fresh_dir("units_weights_runs");
    const auto run = run_cli("run " + write_suite("weights_run", weights_suite(kWeightEntries)) + " -o " + run_dir);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const Table csv = read_csv(run_dir + "/tables/rollouts_cantilever_small.csv");
    const auto column = [&](const std::string& name) { return column_of(csv, name); };
    const size_t method = column("method"), window = column("window");
    std::map<std::string, int> test_rows;
    for (const auto& row : csv.rows)
        if (row.at(window).text == "test") ++test_rows[row.at(method).text];
    EXPECT_EQ(test_rows["ours"], 1);
    EXPECT_EQ(test_rows["ours_f16"], 1);
    EXPECT_EQ(test_rows["ours_int8"], 1);
    // The same artefact through other weights: a different rollout, not a different model
    // (how close it stays: LatentMlpIntegrator.ReducedWeightsStayNearFloat32; this 5-epoch
    // integrator is too crude to compare errors with).
    EXPECT_NE(read_all(run_dir + "/cantilever_small/rollouts/ours.h5"),
              read_all(run_dir + "/cantilever_small/rollouts/ours_f16.h5"));
    EXPECT_FALSE(fs::exists(run_dir + "/cantilever_small/integrators/ours_f16.h5"));
    EXPECT_NE(read_all(run_dir + "/tables/methods_cantilever_small.md").find("f16 inference weights"), std::string::npos);
    // The shared fit's loss curve appears once, under the row that owns the fit.
    const Table curves = read_csv(run_dir + "/tables/training_cantilever_small.csv");
    std::map<std::string, int> curve_rows;
    for (const auto& row : curves.rows) ++curve_rows[row.at(column_of(curves, "method")).text];
    EXPECT_GT(curve_rows["ours"], 0);
    EXPECT_EQ(curve_rows.count("ours_f16"), 0u);
    EXPECT_EQ(curve_rows.count("ours_int8"), 0u);
    EXPECT_NE(read_all(run_dir + "/tables/training_cantilever_small.csv").find("ours_f16 (ours), ours_int8 (ours)"),
              std::string::npos);

    struct Case {
        const char* entries;
        const char* says;
    } cases[] = {
        {"[[integrators]]\nname = \"ours_f64\"\nweights = \"f64\"\n", "unknown weight format 'f64'"},
        {"[[integrators]]\nname = \"pca_f16\"\nmethod = \"linear_pca\"\nweights = \"f16\"\n",
         "method 'linear_pca' does not roll out through the float inference network"},
    };
    for (const Case& c : cases) {
        const std::string path = write_suite("weights_bad", weights_suite(c.entries));
        try {
            load_experiment(path, builtin_methods());
            ADD_FAILURE() << "accepted: " << c.entries;
        } catch (const ConfigError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(path), std::string::npos) << what;
            EXPECT_NE(what.find("weights"), std::string::npos) << what;
            EXPECT_NE(what.find(c.says), std::string::npos) << what;
        }
    }
}

TEST(WorkUnits, MalformedSweepIsRefusedNamingFileAndKey)
{
    struct Case {
        const char* sweep;
        const char* expected;
    };
    const Case cases[] = {
        {"\"training.noise_fractoin\" = [0.1]", "training.noise_fractoin"},
        {"\"physics.dt\" = [0.1]", "sweep.physics.dt': unknown sweep key"},
        {"\"training.noise_fraction\" = 0.1", "must be a list"},
        {"\"training.noise_fraction\" = []", "at least one value"},
        {"\"training.noise_fraction\" = [0.1, 0.1]", "duplicate value 0.1"},
        {"\"training.epochs\" = [\"many\"]", "training.epochs"},
        {"seeds = [-1]", "seeds are integers >= 0"},
        {"\"autoencoder.epochs\" = [1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,21,22,23,24,25,26,27,28,29,30,31,32]\n"
         "\"training.epochs\" = [1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,21,22,23,24,25,26,27,28,29,30,31,32]",
         "more than 1000 points"},
    };
    for (const Case& c : cases) {
        const std::string text = replaced(replaced(kSwept, "\"training.noise_fraction\" = [0.0, 0.2]\n", ""),
                                          "seeds = [3, 4]", c.sweep);
        const std::string path = write_suite("bad_sweep", text);
        try {
            load_experiment(path, builtin_methods());
            ADD_FAILURE() << "expected ConfigError for " << c.sweep;
        } catch (const ConfigError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(path), std::string::npos) << what;
            EXPECT_NE(what.find(c.expected), std::string::npos) << c.sweep << "\n" << what;
        }
    }
    // Seeds in two places; the CLI exits 1 with the message and writes no manifest.
    const std::string path = write_suite("bad_seeds", replaced(kSwept, "name = \"swept\"", "name = \"swept\"\nseeds = [1]"));
    const std::string run_dir = fresh_dir("units_bad_seeds_run");
    const auto r = run_cli("plan " + path + " -o " + run_dir);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("sweep.seeds"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(run_dir + "/manifest.jsonl"));
}

/// The swept suite loaded from a fresh directory, its run directory and its plan.
struct SweptRun {
    explicit SweptRun(const std::string& name)
        : ex((set_log_level(LogLevel::Quiet), load_experiment(write_suite(name, kSwept), builtin_methods())))
    {
        options.output_dir = fresh_dir("units_" + name + "_run");
        plan = plan_experiment(ex, options.output_dir);
    }
    ExperimentConfig ex;
    RunOptions options;
    ExperimentPlan plan;
};

TEST(WorkUnits, UnitRunsOnceAndOnlyAfterItsDependencies)
{
    SweptRun run("idempotent");
    const ExperimentConfig& ex = run.ex;
    RunOptions& options = run.options;
    const ExperimentPlan& plan = run.plan;

    // A unit whose dependency has not run is refused, naming the dependency.
    try {
        run_unit(ex, "fit.cantilever_small.ours.p00.seed3", options);
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("'scene.cantilever_small', which has not completed"), std::string::npos)
            << e.what();
    }
    EXPECT_THROW(run_unit(ex, "fit.nothing", options), ConfigError);

    for (const Unit& u : plan.units) {
        const RunResult first = run_unit(ex, u.id, options);
        EXPECT_EQ(first.stages_run, u.kind == UnitKind::Scene ? 2 : 1) << u.id;
        EXPECT_TRUE(unit_complete(u)) << u.id;
        const RunResult again = run_unit(ex, u.id, options);
        EXPECT_EQ(again.stages_run, 0) << u.id;
        EXPECT_EQ(again.stages_cached, first.stages_run) << u.id;
        EXPECT_NE(read_all(options.output_dir + "/units/" + u.id + ".status").find("done"), std::string::npos);
        EXPECT_TRUE(fs::exists(options.output_dir + "/units/" + u.id + ".log")) << u.id;
    }
    // The local run of the same suite into the same directory finds every unit done.
    const RunResult local = run_experiment(ex, options);
    EXPECT_EQ(local.stages_run, 0);
    const std::string table = read_all(options.output_dir + "/tables/methods_cantilever_small.md");
    EXPECT_NE(table.find("| sweep point "), std::string::npos) << table;
    EXPECT_NE(table.find("training.noise_fraction=0.2, seeds=4"), std::string::npos) << table;
    EXPECT_NE(table.find("all points"), std::string::npos) << table;  // pca and full_space
}

// A fit or eval unit makes the directory it writes to: after `integrators/` and `rollouts/`
// are removed (to redo them, or a scene's files copied in by hand) the units still run.
TEST(WorkUnits, FitAndEvalUnitsMakeTheirDirectories)
{
    SweptRun run("directories");
    const ExperimentConfig& ex = run.ex;
    RunOptions& options = run.options;
    const ExperimentPlan& plan = run.plan;
    const Unit* fit = nullptr;
    const Unit* eval = nullptr;
    for (const Unit& u : plan.units) {
        if (!fit && u.kind == UnitKind::Fit) fit = &u;
    }
    ASSERT_NE(fit, nullptr);
    for (const Unit& u : plan.units) {
        if (u.kind == UnitKind::Eval && std::find(u.depends_on.begin(), u.depends_on.end(), fit->id) != u.depends_on.end())
            eval = &u;
    }
    ASSERT_NE(eval, nullptr);
    run_unit(ex, fit->scene_unit, options);
    const fs::path integrators = fs::path(fit->outputs[0].file).parent_path();
    const fs::path rollouts = fs::path(eval->outputs[0].file).parent_path();
    fs::remove_all(integrators);
    fs::remove_all(rollouts);
    ASSERT_FALSE(fs::exists(integrators));
    EXPECT_EQ(run_unit(ex, fit->id, options).stages_run, 1);
    EXPECT_TRUE(fs::exists(fit->outputs[0].file));
    EXPECT_EQ(run_unit(ex, eval->id, options).stages_run, 1);
    EXPECT_TRUE(fs::exists(eval->outputs[0].file));
}

TEST(WorkUnits, MergeNamesEveryMissingOrFailedUnitAndWritesNothing)
{
    const std::string path = write_suite("merge_missing", kSwept);
    const std::string run_dir = fresh_dir("units_merge_missing_run");
    const std::string prefix = "-q run " + path + " -o " + run_dir;
    ASSERT_EQ(run_cli(prefix + " --unit scene.cantilever_small").exit_code, 0);
    ASSERT_EQ(run_cli(prefix + " --unit fit.cantilever_small.pca").exit_code, 0);
    // A damaged artefact: its eval unit fails, and says so in its status.
    const std::string artefact = run_dir + "/cantilever_small/integrators/pca.h5";
    fs::resize_file(artefact, 100);
    const auto failed = run_cli(prefix + " --unit eval.cantilever_small.pca");
    EXPECT_EQ(failed.exit_code, 1) << failed.output;

    const auto merge = run_cli(prefix + " --merge");
    EXPECT_EQ(merge.exit_code, 1) << merge.output;
    EXPECT_NE(merge.output.find("10 of 12 work units"), std::string::npos) << merge.output;
    EXPECT_NE(merge.output.find("eval.cantilever_small.full_space: not run"), std::string::npos) << merge.output;
    EXPECT_NE(merge.output.find("fit.cantilever_small.ours.p03.seed4: not run"), std::string::npos) << merge.output;
    EXPECT_NE(merge.output.find("eval.cantilever_small.pca: failed on "), std::string::npos) << merge.output;
    EXPECT_EQ(merge.output.find("scene.cantilever_small:"), std::string::npos) << merge.output;  // complete
    EXPECT_FALSE(fs::exists(run_dir + "/tables"));
}

TEST(WorkUnits, MergedUnitsGiveTheLocalRunsTables)
{
    const std::string path = write_suite("merge_equal", kSwept);
    const std::string local = fresh_dir("units_merge_equal_local"), units = fresh_dir("units_merge_equal_units");
    const auto run = run_cli("-q run " + path + " -o " + local);
    ASSERT_EQ(run.exit_code, 0) << run.output;

    // Each unit in its own process, the levels in reverse order of their listing within a
    // level (any order that respects the dependencies must do), then the merge.
    const ExperimentPlan plan = plan_experiment(load_experiment(path, builtin_methods()), units);
    for (int level = 0; level < plan.levels(); ++level) {
        for (auto u = plan.units.rbegin(); u != plan.units.rend(); ++u) {
            if (u->level != level) continue;
            const auto r = run_cli("-q run " + path + " -o " + units + " --unit " + u->id);
            ASSERT_EQ(r.exit_code, 0) << u->id << "\n" << r.output;
        }
    }
    const auto merge = run_cli("-q run " + path + " -o " + units + " --merge");
    ASSERT_EQ(merge.exit_code, 0) << merge.output;
    const auto compare = run_program({"/usr/bin/python3", std::string(LB_SOURCE_DIR) + "/scripts/compare_tables.py",
                                      local + "/tables", units + "/tables"});
    EXPECT_EQ(compare.exit_code, 0) << compare.output;
    // methods_, table1_, table2_, deviations_, the tidy rollouts_cantilever_small.csv and
    // the training curves training_cantilever_small.csv
    EXPECT_NE(compare.output.find("tables equal: 6 CSV files"), std::string::npos) << compare.output;

    // The comparison can fail: one changed value is found.
    const std::string csv = units + "/tables/methods_cantilever_small.csv";
    std::string text = read_all(csv);
    const size_t row = text.find("\nours,");
    ASSERT_NE(row, std::string::npos);
    text.replace(row, 6, "\nOURS,");
    std::ofstream(csv) << text;
    const auto differs = run_program({"/usr/bin/python3", std::string(LB_SOURCE_DIR) + "/scripts/compare_tables.py",
                                      local + "/tables", units + "/tables"});
    EXPECT_EQ(differs.exit_code, 1) << differs.output;
    EXPECT_NE(differs.output.find("'method': 'ours' vs 'OURS'"), std::string::npos) << differs.output;
}

} // namespace
} // namespace lb

namespace lb {
namespace {

/// linear_pca, except that its first fit leaves the disk "full" for what the unit writes
/// next, its cache key and its status: their temporaries (`<final>.tmp-<pid>`) are made
/// links to /dev/full, where every write fails with ENOSPC, as on a full disk.
class FullDiskAfterFit final : public Method {
public:
    explicit FullDiskAfterFit(std::unique_ptr<Method> inner) : m_inner(std::move(inner)) { }
    static bool& armed()
    {
        static bool on = true;
        return on;
    }
    std::string method_name() const override { return "linear_pca_full_disk"; }
    void resolve(const MethodScene& scene) override { m_inner->resolve(scene); }
    std::string options_text() const override { return m_inner->options_text(); }
    std::string summary() const override { return m_inner->summary(); }
    void fit(const MethodInputs& in, h5::File& out) const override
    {
        m_inner->fit(in, out);
        if (!armed()) return;
        armed() = false;
        const std::string pid = std::to_string(::getpid());
        const fs::path checkpoint(in.checkpoint_path);  // <run>/<scene>/integrators/<stem>.checkpoint.h5
        const std::string stem = checkpoint.filename().string().substr(0, checkpoint.filename().string().find('.'));
        fs::create_symlink("/dev/full", (checkpoint.parent_path() / (stem + ".h5.key.tmp-" + pid)));
        const fs::path units = checkpoint.parent_path().parent_path().parent_path() / "units";
        for (const auto& e : fs::directory_iterator(units)) {
            const std::string name = e.path().filename().string();
            if (name.rfind("fit.", 0) == 0 && name.size() > 7 && name.compare(name.size() - 7, 7, ".status") == 0)
                fs::create_symlink("/dev/full", e.path().string() + ".tmp-" + pid);
        }
    }
    std::unique_ptr<Integrator> load(const MethodInputs& in, const h5::File* artefact,
                                     const std::string& label) const override
    {
        return m_inner->load(in, artefact, label);
    }

private:
    std::unique_ptr<Method> m_inner;
};

// A full disk at the end of a fit unit: the artefact is committed, but neither its cache
// key nor the unit's status can be written. The status used to keep saying "running", so
// the merge reported the unit as "killed, pre-empted or still running"; now the failed
// status write is recorded without needing space (a rename), and the merge says so.
TEST(WorkUnits, MergeSaysTheLastStatusWriteFailed)
{
    if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full to simulate a full disk";
    MethodRegistry registry = builtin_methods();
    MethodFactory factory = linear_pca_method();
    const auto parse = factory.parse;
    factory.name = "linear_pca_full_disk";
    factory.parse = [parse](ConfigTable& entry, ConfigTable& defaults) -> std::unique_ptr<Method> {
        return std::make_unique<FullDiskAfterFit>(parse(entry, defaults));
    };
    registry.add(factory);
    set_log_level(LogLevel::Quiet);
    const std::string suite = "name = \"full\"\n[autoencoder]\nhidden = [16]\npca = 8\nepochs = 20\nbatch = 16\n"
                              "learning_rate = 1.0e-3\n[[integrators]]\nname = \"pca\"\nmethod = \"linear_pca_full_disk\"\n"
                              "[[scenes]]\nscene = \"experiments/scenes/cantilever.toml\"\nvariant = \"small\"\n"
                              "[evaluation]\nframes = 20\nfull_space = false\n[outputs]\nplots = false\n";
    const ExperimentConfig ex = load_experiment(write_suite("full_disk", suite), registry);
    RunOptions options;
    options.output_dir = fresh_dir("units_full_disk_run");
    const ExperimentPlan plan = plan_experiment(ex, options.output_dir);
    const Unit* fit = plan.find("fit.cantilever_small.pca");
    ASSERT_NE(fit, nullptr);
    run_unit(ex, fit->scene_unit, options);

    FullDiskAfterFit::armed() = true;
    try {
        run_unit(ex, fit->id, options);
        FAIL() << "expected the full disk to fail the unit";
    } catch (const Error& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(fit->outputs[0].file + ".key"), std::string::npos) << what;
        EXPECT_NE(what.find("status could not be written"), std::string::npos) << what;
    }
    EXPECT_TRUE(fs::exists(fit->outputs[0].file));   // committed
    EXPECT_FALSE(unit_complete(*fit));               // without its key
    const std::string status = options.output_dir + "/units/" + fit->id + ".status";
    EXPECT_TRUE(fs::exists(status + ".unwritten-failed"));
    for (const auto& e : fs::directory_iterator(options.output_dir + "/units"))
        EXPECT_EQ(e.path().string().find(".tmp-"), std::string::npos) << e.path();
    try {
        merge_units(ex, options);
        FAIL() << "expected the merge to refuse";
    } catch (const Error& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(fit->id + ": its last status write failed"), std::string::npos) << what;
        EXPECT_NE(what.find("could not record 'failed'"), std::string::npos) << what;
        EXPECT_EQ(what.find("killed, pre-empted"), std::string::npos) << what;
    }
    // Space again: the unit runs, its status says done and the mark is gone.
    EXPECT_EQ(run_unit(ex, fit->id, options).stages_run, 1);
    EXPECT_TRUE(unit_complete(*fit));
    EXPECT_NE(read_all(status).find("done"), std::string::npos);
    EXPECT_FALSE(fs::exists(status + ".unwritten-failed"));
}

/// A method whose fit changed (fit_version() > 1) gets a new stage key, so its cached
/// artefacts are refitted; version-1 methods keep the key they always had.
TEST(WorkUnits, FitVersionIsPartOfTheStageKey)
{
    const MethodRegistry& registry = builtin_methods();
    const std::unique_ptr<Method> latent = registry.parse_text("latent_mlp", "", "test");
    const std::unique_ptr<Method> pca = registry.parse_text("linear_pca", "", "test");
    latent->resolve({"cloth", 4});
    pca->resolve({"cloth", 4});
    ASSERT_GE(latent->fit_version(), 2);
    EXPECT_NE(method_stage_key(*latent, "sim", "ae"),
              fnv1a64_hex("ae|" + latent->method_name() + "|" + latent->options_text()));
    ASSERT_EQ(pca->fit_version(), 1);
    EXPECT_EQ(method_stage_key(*pca, "sim", "ae"), fnv1a64_hex("sim|" + pca->method_name() + "|" + pca->options_text()));
}

} // namespace
} // namespace lb

namespace lb {
namespace {

/// Two suites of one scene: `b` has `a`'s autoencoder and `ours`, plus an entry of its own.
const char* kReuseA = R"(
name = "reuse_a"
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
[[scenes]]
scene = "experiments/scenes/cantilever.toml"
variant = "small"
[evaluation]
frames = 40
full_space = false
[outputs]
plots = false
)";

bool same_bytes(const std::string& a, const std::string& b) { return read_all(a) == read_all(b) && !read_all(a).empty(); }

TEST(WorkUnits, ReuseCopiesOutputsWithTheSameKeyFromAnotherRunDirectory)
{
    const std::string a = write_suite("reuse_a", kReuseA);
    const std::string a_run = fresh_dir("units_reuse_a_run");
    ASSERT_EQ(run_cli("-q run " + a + " -o " + a_run).exit_code, 0);

    std::string b_text = replaced(kReuseA, "name = \"reuse_a\"", "name = \"reuse_b\"");
    b_text = replaced(b_text, "[[scenes]]", "[[integrators]]\nname = \"wide\"\nhidden = [24]\n[[scenes]]");
    const std::string b = write_suite("reuse_b", b_text);
    const std::string b_run = fresh_dir("units_reuse_b_run");
    const auto reused = run_cli("run " + b + " -o " + b_run + " --reuse " + a_run);
    ASSERT_EQ(reused.exit_code, 0) << reused.output;
    EXPECT_NE(reused.output.find("unit 'scene.cantilever_small': 2 outputs reused from"), std::string::npos)
        << reused.output;
    EXPECT_NE(reused.output.find("unit 'fit.cantilever_small.ours': 1 output reused from"), std::string::npos);
    EXPECT_NE(reused.output.find("unit 'eval.cantilever_small.ours': 1 output reused from"), std::string::npos);
    EXPECT_EQ(reused.output.find("'fit.cantilever_small.wide': 1 output reused"), std::string::npos);  // b's own
    const std::string sa = a_run + "/cantilever_small/", sb = b_run + "/cantilever_small/";
    EXPECT_TRUE(same_bytes(sa + "data.h5", sb + "data.h5"));
    EXPECT_TRUE(same_bytes(sa + "ae.h5", sb + "ae.h5"));
    EXPECT_TRUE(same_bytes(sa + "integrators/ours.h5", sb + "integrators/ours.h5"));
    EXPECT_TRUE(fs::exists(sb + "integrators/wide.h5"));
    // The reused units are complete under b's own keys: a rerun runs nothing.
    const auto again = run_cli("-q run " + b + " -o " + b_run);
    EXPECT_NE(again.output.find("0 stages run"), std::string::npos) << again.output;

    // Another autoencoder: its dataset is the same, the autoencoder and everything after it is not.
    const std::string c = write_suite("reuse_c", replaced(replaced(kReuseA, "name = \"reuse_a\"", "name = \"reuse_c\""),
                                                          "epochs = 20", "epochs = 21"));
    const std::string c_run = fresh_dir("units_reuse_c_run");
    const auto partly = run_cli("run " + c + " -o " + c_run + " --reuse " + a_run);
    ASSERT_EQ(partly.exit_code, 0) << partly.output;
    EXPECT_NE(partly.output.find("unit 'scene.cantilever_small': 1 output reused from"), std::string::npos)
        << partly.output;
    EXPECT_EQ(partly.output.find("unit 'fit.cantilever_small.ours': 1 output reused"), std::string::npos);
    EXPECT_FALSE(same_bytes(sa + "ae.h5", c_run + "/cantilever_small/ae.h5"));

    // A forced stage is recomputed, not copied.
    const std::string d_run = fresh_dir("units_reuse_d_run");
    const auto forced = run_cli("run " + b + " -o " + d_run + " --reuse " + a_run + " --force integrators");
    ASSERT_EQ(forced.exit_code, 0) << forced.output;
    EXPECT_NE(forced.output.find("unit 'scene.cantilever_small': 2 outputs reused"), std::string::npos);
    EXPECT_EQ(forced.output.find("unit 'fit.cantilever_small.ours': 1 output reused"), std::string::npos);

    // Not a directory: exit 1 naming the option and the path, nothing run.
    const std::string e_run = fresh_dir("units_reuse_e_run");
    const auto bad = run_cli("-q run " + b + " -o " + e_run + " --reuse " + e_run + "/missing");
    EXPECT_EQ(bad.exit_code, 1);
    EXPECT_NE(bad.output.find("--reuse '" + e_run + "/missing': not a directory"), std::string::npos) << bad.output;
    EXPECT_FALSE(fs::exists(e_run + "/cantilever_small/data.h5"));
}

} // namespace
} // namespace lb
