#include "lb_paths.hpp"
#include "pipeline/report.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <limits>

#include "core/build_info.hpp"
#include "core/hash.hpp"
#include "core/parallel.hpp"
#include "eval/summary_schema.hpp"
#include "io/atomic_file.hpp"
#include "io/json.hpp"
#include "io/table.hpp"
#include "io/table_data.hpp"
#include "paper/paper_numbers.hpp"
#include "pipeline/deviations.hpp"
#include "pipeline/plan.hpp"
#include "pipeline/training_curves.hpp"
#include "scene/scene.hpp"

namespace lb {

namespace fs = std::filesystem;

namespace {

TableCell number(double v, int digits = 3)
{
    return std::isfinite(v) ? TableCell::significant(v, digits) : TableCell::missing("nan");
}

/// How the rows of a method over several sequences were combined (item for captions).
std::string aggregation_text(const SceneResult& r)
{
    // summaries holds every seed's sequences: a row with seeds combines summaries / seeds.
    size_t most = 0;
    for (const auto& m : r.methods)
        most = std::max(most, m.seeds.empty() ? m.summaries.size() : m.summaries.size() / m.seeds.size());
    const bool seeded = std::any_of(r.methods.begin(), r.methods.end(), [](const MethodResult& m) { return m.seeds.size() > 1; });
    if (most <= 1) return seeded ? "One test sequence per run; a row with seeds aggregates its runs ('seeds')." : "One test sequence per row.";
    return std::string(seeded ? "Each run (one seed's fit, or the one fit of a method without seeds) combines "
                              : "Rows combine ") +
           std::to_string(most) +
           " sequences: horizons are the worst case (the earliest over the sequences), "
           "percentages, errors, KE ratios and times the mean over the sequences (each sequence's errors "
           "aggregated before its own horizon), the boundary violation the largest.";
}

/// A method's training budget in numbers: mean epochs run and seconds over its fits, the
/// largest epoch budget (0: unknown); `recorded` fits (0: nothing trained).
struct BudgetNumbers {
    int recorded = 0;
    double epochs = 0.0, seconds = 0.0;
    long long budget = 0;
};

BudgetNumbers budget_numbers(const std::vector<TrainingBudget>& budgets)
{
    BudgetNumbers n;
    for (const TrainingBudget& b : budgets) {
        if (!b.recorded) continue;
        ++n.recorded;
        n.epochs += double(b.epochs_run);
        n.seconds += b.seconds;
        n.budget = std::max(n.budget, b.epochs_budget);
    }
    if (n.recorded > 0) {
        n.epochs /= n.recorded;
        n.seconds /= n.recorded;
    }
    return n;
}

/// The training budget of a method and how its training ended, e.g.
/// "1500/1500 epochs, 212 s" or "812/1500 epochs, 600 s (time cap)"; means over seeds.
TableCell budget_cell(const std::vector<TrainingBudget>& budgets)
{
    double epochs = 0.0, seconds = 0.0;
    long long budget = 0;
    double cap = 0.0;
    int recorded = 0, capped = 0, early = 0;
    for (const TrainingBudget& b : budgets) {
        if (!b.recorded) continue;
        ++recorded;
        epochs += double(b.epochs_run);
        seconds += b.seconds;
        budget = std::max(budget, b.epochs_budget);
        cap = std::max(cap, b.max_seconds);
        capped += b.time_limited;
        early += b.stopped_early;
    }
    if (recorded == 0) return TableCell::missing();
    epochs /= recorded;
    seconds /= recorded;
    char text[160];
    std::snprintf(text, sizeof text, "%.0f/%s epochs, %.3g s%s", epochs, budget > 0 ? std::to_string(budget).c_str() : "?",
                  seconds, cap > 0.0 ? (" (cap " + std::to_string(int(cap)) + " s)").c_str() : "");
    std::string out = text;
    if (capped > 0) out += ", time cap hit" + (recorded > 1 ? " (" + std::to_string(capped) + "/" + std::to_string(recorded) + ")" : std::string());
    if (early > 0) out += ", stopped early" + (recorded > 1 ? " (" + std::to_string(early) + "/" + std::to_string(recorded) + ")" : std::string());
    return TableCell(out, epochs);
}

/// The provenance note's thread entry of tabulated rollout times: the thread counts of the
/// processes that rolled out (RolloutSummary::timing_threads), which need not be the table
/// writer's (a merge of work units, a cluster job). "" (the writer's) if nothing is tabulated.
std::string timing_threads_text(const std::vector<const MethodResult*>& methods)
{
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    bool unrecorded = false, any = false;
    for (const MethodResult* m : methods) {
        for (const RolloutSummary& s : m->summaries) {
            any = true;
            if (!(s.timing_threads >= 1.0)) {
                unrecorded = true;
                continue;
            }
            lo = std::min(lo, s.timing_threads);
            hi = std::max(hi, s.timing_threads);
        }
    }
    if (!any) return "";
    std::string text;
    if (lo <= hi) {
        text = std::to_string(int(lo)) + (hi > lo ? "–" + std::to_string(int(hi)) : "") +
               (hi > lo ? " (the rollouts were timed with different thread counts)" : " (as the rollouts were timed)");
    }
    if (unrecorded)
        text += std::string(text.empty() ? "" : "; ") + "not recorded for rollouts written before 2026-12-02";
    return text;
}

Table comparison_table(const SceneResult& r, const std::vector<std::string>& only, const std::string& title,
                       Table* csv = nullptr)
{
    Table t;
    t.title = title;
    t.caption =
        "Rollouts of every method on the evaluated sequences of " + r.label + " (" + std::to_string(r.dofs) +
        " DOF, latent " + std::to_string(r.latent) +
        "), from the first two ground-truth frames, one row per method and window: the training window (frames "
        "before train_frames = " + std::to_string(r.train_frames) +
        ") and the test window (the frames after it) are reported apart. RMSE is relative to the rest "
        "bounding-box diagonal. Stable = frames before the first blow-up (non-finite state or RMSE > 0.5); "
        "'first RMSE > 0.1 / 0.02' are the looser tiers' horizons and '% frames > x' the share of the "
        "window's frames above each tier. Errors are aggregated only over the window's frames before the "
        "stable horizon ('frames aggregated'); a window cut by a blow-up reads 'v (diverged @h)', one that "
        "starts after it 'diverged @h'. KE ratio = sum of the free DOFs' kinetic energy relative to the "
        "boundary's rigid motion, prediction over ground truth (n/a without ground-truth motion); residual = "
        "per-DOF RMS of the implicit-Euler gradient on free DOFs over m|g| (Tan et al.'s M_phys analogue); STED "
        "after Vasa & Skala 2011 with 1-ring neighbourhoods; times are medians per frame after warm-up. " +
        aggregation_text(r) +
        " 'training' is the budget and how it was used: epochs run of the epoch budget, wall-clock seconds, "
        "the wall-clock cap if the suite sets one (max_seconds) and whether it or early stopping ended the run.";
    size_t seeds = 0;
    for (const auto& m : r.methods) seeds = std::max(seeds, m.per_seed.size());
    if (seeds > 1)
        t.caption += " Methods trained once per seed (" + std::to_string(seeds) + " seeds) show " +
                     seed_statistics_text(seeds) + "; the others one run (no seed, or an entry that lists one seed)." +
                     (r.seed_scope == SeedScope::autoencoder
                          ? " Seed scope autoencoder: each seed trained its own autoencoder as well, and every "
                            "method that uses the autoencoder ran once per seed on that seed's autoencoder, so the "
                            "intervals include the autoencoder's variation."
                          : " Seed scope integrator: the seeds vary each method's initialisation and training "
                            "order over one autoencoder (seed " + std::to_string(r.autoencoder_seed) +
                            "), so the intervals leave out the autoencoder's variation.");
    // A [sweep]: one row per point, labelled; rows the sweep does not change are shared.
    const bool swept = std::any_of(r.methods.begin(), r.methods.end(), [](const MethodResult& m) { return !m.point.empty(); });
    if (swept)
        t.caption += " Rows are labelled with their [sweep] point; 'all points' rows do not depend on the swept keys "
                     "and ran once.";
    t.caption += " 'seeds' counts the runs a row aggregates (1 for a method without a seed).";
    t.columns = {"method", "configuration", "training", "window", "seeds"};
    if (swept) t.columns.insert(t.columns.begin() + 1, "sweep point");
    for (const auto& title : summary_table_columns()) t.columns.push_back(title);
    if (csv) {
        csv->title = t.title;
        csv->caption = "The machine-readable twin of methods_" + r.label +
                       ".md (read with pandas.read_csv(path, comment='#')): one row per method and window, with "
                       "n_seeds (runs the row aggregates), n_diverged (runs that blew up: non-finite state or RMSE > 0.5), "
                       "diverged_at (the earliest blow-up frame, nan if none) and window_diverged (runs whose blow-up cuts "
                       "or precedes the window); per metric the median, min and max over the runs that have a value, and "
                       "_n, how many do (an error is aggregated before the blow-up, so a run that blew up before the window "
                       "has none). training_epochs and training_seconds are means over the row's fits, training_epoch_budget "
                       "the epoch budget (nan: nothing trained). Per-run values: rollouts_" + r.label + ".csv.";
        csv->columns = {"method", "configuration", "training_epochs", "training_epoch_budget", "training_seconds", "window"};
        if (swept) csv->columns.insert(csv->columns.begin() + 1, "sweep point");
        for (const auto& c : summary_csv_columns()) csv->columns.push_back(c);
    }
    std::vector<const MethodResult*> shown;
    for (const auto& m : r.methods) {
        if (!only.empty() && std::find(only.begin(), only.end(), m.name) == only.end()) continue;
        shown.push_back(&m);
        const RolloutSummary s = aggregate(m.summaries);
        const std::vector<RolloutSummary> runs = m.per_seed.size() > 1 ? m.per_seed : std::vector<RolloutSummary>{s};
        const TableCell budget = budget_cell(m.budgets);
        for (const SummaryScope window : {SummaryScope::Train, SummaryScope::Test}) {
            std::vector<TableCell> cells{m.name, m.summary, budget, window_label(s, window),
                                         TableCell(std::to_string(runs.size()), double(runs.size()))};
            if (swept) cells.insert(cells.begin() + 1, TableCell(m.point.empty() ? "all points" : m.point));
            for (auto& c : m.per_seed.size() > 1 ? summary_table_cells_over_seeds(m.per_seed, window)
                                                 : summary_table_cells(s, window))
                cells.push_back(std::move(c));
            t.add_row(std::move(cells));
            if (csv) {
                const BudgetNumbers b = budget_numbers(m.budgets);
                const auto number_or_nan = [&](double v, bool known) {
                    return known ? TableCell(TableCell::significant(v, 6).text, v) : TableCell::missing("nan");
                };
                std::vector<TableCell> row{m.name, m.summary, number_or_nan(b.epochs, b.recorded > 0),
                                           number_or_nan(double(b.budget), b.recorded > 0 && b.budget > 0),
                                           number_or_nan(b.seconds, b.recorded > 0), window_label(s, window)};
                if (swept) row.insert(row.begin() + 1, TableCell(m.point.empty() ? "all points" : m.point));
                for (auto& c : summary_csv_cells(runs, window)) row.push_back(std::move(c));
                csv->add_row(std::move(row));
            }
        }
    }
    t.add_note("training horizon: " + std::to_string(r.train_frames) + " frames per sequence");
    for (const std::string& f : r.failed_rows) t.add_note("FAILED, no row: " + f);
    t.add_provenance(timing_threads_text(shown));
    if (csv) csv->notes = t.notes;
    return t;
}

/// Tan et al.'s embedding metrics (their Table I) of every autoencoder a method of the scene
/// measured: the shared one once, then each method's own. Empty if no method measured any.
Table embedding_table(const SceneResult& r)
{
    Table t;
    t.title = "Embeddings on " + r.label + " (Tan et al.'s metrics)";
    t.caption = "Reconstructions D(E(x_m)) of every ground-truth frame, measured with the rollout metrics: M_rms = RMS "
                "vertex error (m); M_STED = STED (1-ring) of the reconstructed sequence; M_phys = per-DOF RMS of the "
                "implicit-Euler gradient at x̂_m given x̂_{m−1}, x̂_{m−2} on free DOFs over m|g| (Tan et al.'s M_phys "
                "analogue). Frames m ≥ 2; training and test windows apart; several sequences averaged.";
    t.columns = {"autoencoder", "measured by", "window", "frames", "M_rms (m)", "M_STED", "M_phys"};
    bool shared_done = false;
    for (const MethodResult& m : r.methods) {
        for (const EmbeddingMetrics& e : m.embeddings) {
            const bool shared = e.label == "shared autoencoder";
            if (shared && shared_done) continue;
            shared_done = shared_done || shared;
            for (const bool train : {true, false}) {
                const EmbeddingWindow& w = train ? e.train : e.test;
                t.add_row({e.label, m.name, train ? "train" : "test", TableCell::integer(w.frames), number(w.m_rms),
                           number(w.sted), number(w.m_phys)});
            }
        }
    }
    t.add_provenance();
    return t;
}

TableCell paper_cell(const void* row, double v) { return row ? TableCell::significant(v, 4) : TableCell::missing(); }

/// Tables 1 and 2: the paper's own method (the first one registered as such) per scene.
void paper_tables(const std::vector<SceneResult>& scenes, Table& t1, Table& t2)
{
    t1.title = "Table 1: latent integration vs full-space simulation";
    t1.caption = "Per-frame times (median after warm-up), all measured the same way in the same run: 'ours' is the "
                 "first self-supervised integrator of the suite, float, batch 1, one thread; 'simulation' is the "
                 "full_space rollout of the same sequences (one Newton solve per frame; '—' if the suite does not "
                 "roll it out). 'dataset step' is the median Newton step recorded when the dataset was simulated: "
                 "that stage is cached, so it may come from another run, machine load or code version, and is shown "
                 "for reference only. Paper columns: " + std::string(kPaperCitation) + ", Table 1 (" +
                 kPaperTimingHardware + ").";
    t1.columns = {"example", "DOF", "latent", "simulation (ms)", "integration (ms)", "decoder (ms)", "total (ms)",
                  "dataset step (ms)", "paper DOF", "paper simulation (ms)", "paper integration (ms)",
                  "paper decoder (ms)", "paper total (ms)"};
    t2.title = "Table 2: our step vs one vertex's decoder JVP";
    t2.caption = "Computing JVP = the Jacobian rows of one vertex's three coordinates w.r.t. the latent through "
                 "the float decoder (the least an optimisation-based latent integrator such as Fulton et al. 2019 "
                 "needs per cubature point and iteration). 'fulton_cubature (ms)' is that method's measured step in "
                 "the same run (median per frame: L-BFGS over the latent with cubature, decoding, as rolled out; "
                 "'—' if the suite does not run it). Paper columns: " + std::string(kPaperCitation) + ", Table 2.";
    t2.columns = {"example", "DOF", "latent", "decoder layers", "integrator layers", "JVP (ms)", "ours (ms)",
                  "fulton_cubature (ms)", "paper decoder layers", "paper integrator layers", "paper JVP (ms)",
                  "paper ours (ms)"};
    std::vector<const MethodResult*> timed;  // the rollouts whose times the two tables show
    for (const SceneResult& r : scenes) {
        const auto ours = std::find_if(r.methods.begin(), r.methods.end(), [](const MethodResult& m) { return m.paper_method; });
        if (ours == r.methods.end()) continue;
        timed.push_back(&*ours);
        const RolloutSummary s = aggregate(ours->summaries);
        const auto reference = std::find_if(r.methods.begin(), r.methods.end(),
                                            [](const MethodResult& m) { return m.method == "full_space"; });
        const TableCell simulation = reference != r.methods.end() ? number(aggregate(reference->summaries).total_ms, 4)
                                                                  : TableCell::missing();
        const auto fulton = std::find_if(r.methods.begin(), r.methods.end(),
                                         [](const MethodResult& m) { return m.method == "fulton_cubature"; });
        const TableCell fulton_ms =
            fulton != r.methods.end() ? number(aggregate(fulton->summaries).total_ms) : TableCell::missing();
        if (reference != r.methods.end()) timed.push_back(&*reference);
        if (fulton != r.methods.end()) timed.push_back(&*fulton);
        const PaperTable1Row* p1 = find_paper_table1_row(r.scene_name);
        const PaperTable2Row* p2 = find_paper_table2_row(r.scene_name);
        t1.add_row({r.label, TableCell::integer(r.dofs), TableCell::integer(r.latent), simulation,
                    number(s.integrate_ms), number(s.decode_ms), number(s.total_ms), number(r.dataset_step_ms, 4),
                    p1 ? TableCell::integer(p1->full_dofs) : TableCell::missing(), paper_cell(p1, p1 ? p1->simulation_ms : 0),
                    paper_cell(p1, p1 ? p1->integration_ms : 0), paper_cell(p1, p1 ? p1->decoder_ms : 0),
                    paper_cell(p1, p1 ? p1->total_ms : 0)});
        t2.add_row({r.label, TableCell::integer(r.dofs), TableCell::integer(r.latent), r.decoder_layers, ours->layers,
                    number(r.jvp_ms), number(s.total_ms), fulton_ms,
                    p2 ? TableCell(format_layers(p2->decoder_layers)) : TableCell::missing(),
                    p2 ? TableCell(format_layers(p2->integrator_layers)) : TableCell::missing(),
                    paper_cell(p2, p2 ? p2->jvp_ms : 0), paper_cell(p2, p2 ? p2->ours_ms : 0)});
    }
    t1.add_provenance(timing_threads_text(timed));
    t2.add_provenance(timing_threads_text(timed));
}

} // namespace

Table observations_table(const SceneResult& r)
{
    Table t;
    t.title = "Rollouts on " + r.label;
    t.caption = "One row per method, sweep point, seed, sequence and window (the tidy data behind methods_" + r.label +
                "): every summary metric by its field name (README, Metrics), window metrics of the row's window; "
                "diverged = the rollout blew up (stable_horizon < frames), diverged_at its stable horizon. seed is "
                "nan for a method trained without one. Read with pandas.read_csv(path, comment='#').";
    const bool swept = std::any_of(r.methods.begin(), r.methods.end(), [](const MethodResult& m) { return !m.point.empty(); });
    t.columns = {"scene", "method", "sweep point", "seed", "sequence", "window"};
    std::vector<const SummaryMetric*> metrics;  // rollout metrics and the training window's (named by field)
    for (const SummaryMetric& m : summary_metrics()) {
        if (m.scope == SummaryScope::Test) continue;
        metrics.push_back(&m);
        t.columns.push_back(m.field);
    }
    t.columns.push_back("diverged");
    t.columns.push_back("diverged_at");
    for (const MethodResult& m : r.methods) {
        for (size_t k = 0; k < m.summaries.size(); ++k) {
            const RolloutSummary& s = m.summaries[k];
            const long long seed = k < m.summary_seeds.size() ? m.summary_seeds[k] : -1;
            const bool diverged = s.stable_horizon < s.frames;
            for (const SummaryScope window : {SummaryScope::Train, SummaryScope::Test}) {
                std::vector<TableCell> cells{r.label, m.name, swept ? (m.point.empty() ? "all points" : m.point) : "",
                                             seed >= 0 ? TableCell(std::to_string(seed), double(seed)) : TableCell::missing("nan"),
                                             k < m.sequences.size() ? m.sequences[k] : "",
                                             window == SummaryScope::Train ? "train" : "test"};
                for (const SummaryMetric* metric : metrics) {
                    const SummaryMetric* w = metric;
                    if (metric->scope == SummaryScope::Train && window == SummaryScope::Test) {
                        // the same field's test-window entry follows the training one's in the list
                        const auto& all = summary_metrics();
                        const auto twin = std::find_if(all.begin(), all.end(), [&](const SummaryMetric& x) {
                            return x.scope == SummaryScope::Test && std::string(x.field) == metric->field;
                        });
                        assert(twin != all.end());
                        w = &*twin;
                    }
                    const double v = w->get(s);
                    cells.push_back(TableCell(std::isfinite(v) ? TableCell::significant(v, 6).text : "nan", v));
                }
                cells.push_back(TableCell(diverged ? "1" : "0", diverged ? 1.0 : 0.0));
                cells.push_back(diverged ? TableCell(std::to_string(s.stable_horizon), double(s.stable_horizon))
                                         : TableCell::missing("nan"));
                t.add_row(std::move(cells));
            }
        }
    }
    t.add_note("training horizon: " + std::to_string(r.train_frames) + " frames per sequence");
    t.add_provenance();
    return t;
}

std::vector<std::string> write_tables(const ExperimentConfig& ex, const std::vector<SceneResult>& scenes,
                                      const std::string& dir)
{
    std::filesystem::create_directories(dir);
    std::vector<std::string> written;
    const std::string suite_note = suite_provenance_note(ex, scenes);
    // Markdown and LaTeX show `t`; the CSV is `csv` where a table has a machine-readable twin.
    auto emit = [&](Table t, const std::string& stem, Table* csv = nullptr) {
        t.add_note(suite_note);
        const std::string path = dir + "/" + stem;
        write_markdown(t, path + ".md");
        if (csv) csv->add_note(suite_note);
        write_csv(csv ? *csv : t, path + ".csv");
        write_latex(t, path + ".tex");
        write_table_data(t, path);  // the suite page's source (pipeline/html_page.hpp)
        written.push_back(path + ".md");
    };
    for (const SceneResult& r : scenes) {
        // The deviations from the paper's recipe, from the resolved settings (issue 39).
        for (const SceneSpec& spec : ex.scenes) {
            if (spec.label != r.label) continue;
            const Scene scene = load_scene(spec.scene_path, {spec.variant});
            emit(deviations_table(ex, spec, scene.name, resolved_autoencoder(spec, scene)), "deviations_" + r.label);
        }
        Table methods_csv;
        Table methods = comparison_table(r, {}, "Methods on " + r.label, &methods_csv);
        const Table embeddings = embedding_table(r);
        if (!embeddings.rows.empty()) {
            methods.add_note("embedding metrics (M_rms, M_STED, M_phys) of the shared and the methods' own "
                             "autoencoders: embedding_" + r.label);
        }
        emit(methods, "methods_" + r.label, &methods_csv);
        Table rollouts = observations_table(r);
        rollouts.add_note(suite_note);
        write_csv(rollouts, dir + "/rollouts_" + r.label + ".csv");
        write_training_curves(r, dir);
        if (!embeddings.rows.empty()) emit(embeddings, "embedding_" + r.label);
        for (const AblationSpec& ab : ex.ablations) {
            // Only on scenes that ran every method of the ablation (a scene may run a subset).
            const bool complete = std::all_of(ab.methods.begin(), ab.methods.end(), [&](const std::string& name) {
                return std::any_of(r.methods.begin(), r.methods.end(),
                                   [&](const MethodResult& m) { return m.name == name; });
            });
            if (complete) {
                Table ablation_csv;
                emit(comparison_table(r, ab.methods, ab.title + " (" + r.label + ")", &ablation_csv),
                     "ablation_" + ab.name + "_" + r.label, &ablation_csv);
            }
        }
    }
    if (ex.paper_tables) {
        Table t1, t2;
        paper_tables(scenes, t1, t2);
        if (!t1.rows.empty()) emit(t1, "table1_timings");
        if (!t2.rows.empty()) emit(t2, "table2_jvp");
    }
    return written;
}

std::string suite_file_hash(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) return "";
    std::ostringstream text;
    text << in.rdbuf();
    return "fnv1a64:" + fnv1a64_hex(text.str());
}

namespace {

/// Every seed a suite's rows ran with ("0, 1, 2"), or "none (each method's own)".
std::string seeds_text(const ExperimentConfig& ex)
{
    std::string text;
    for (const std::uint64_t s : ex.seeds) text += (text.empty() ? "" : ", ") + std::to_string(s);
    if (text.empty()) return "none (each method's own)";
    return text + (ex.seed_scope == SeedScope::autoencoder ? " (scope autoencoder: each seed trains its own autoencoder)"
                                                           : " (scope integrator: one autoencoder per scene)");
}

/// "ours 3, supervised_l2 1": the fit_version of each row's method (learned ones; others 1).
std::vector<std::pair<std::string, int>> fit_versions(const std::vector<SceneResult>& scenes)
{
    std::vector<std::pair<std::string, int>> out;
    for (const SceneResult& r : scenes) {
        for (const MethodResult& m : r.methods) {
            const bool known = std::any_of(out.begin(), out.end(), [&](const auto& p) { return p.first == m.name; });
            if (!known) out.emplace_back(m.name, m.fit_version);
        }
    }
    return out;
}

/// The suite file as provenance names it: relative to the working directory when it is
/// inside it (no absolute path of this machine in a published folder), else its file name.
std::string suite_file_name(const std::string& source)
{
    std::error_code ec;
    const fs::path absolute = fs::absolute(source, ec);
    const fs::path relative = fs::relative(absolute, fs::current_path(ec), ec);
    if (!ec && !relative.empty() && *relative.begin() != "..") return relative.generic_string();
    return fs::path(source).filename().string();
}

} // namespace

std::string suite_provenance_note(const ExperimentConfig& ex, const std::vector<SceneResult>& scenes)
{
    std::string versions;
    for (const auto& [name, version] : fit_versions(scenes))
        versions += (versions.empty() ? "" : ", ") + name + " " + std::to_string(version);
    const std::string command = command_line_text();
    return "suite: " + ex.name + " (" + suite_file_name(ex.source) + ", " + suite_file_hash(ex.source) +
           "); seeds: " + seeds_text(ex) + "; fit versions: " + versions +
           "; command: " + (command.empty() ? "(not recorded)" : command);
}

void write_provenance(const ExperimentConfig& ex, const std::vector<SceneResult>& scenes, const std::string& run_dir)
{
    std::string versions;
    for (const auto& [name, version] : fit_versions(scenes))
        versions += std::string(versions.empty() ? "" : ", ") + json_quote(name) + ": " + std::to_string(version);
    std::string seeds;
    for (const std::uint64_t s : ex.seeds) seeds += (seeds.empty() ? "" : ", ") + std::to_string(s);
    std::string command;
    for (const std::string& a : command_line()) command += (command.empty() ? "" : ", ") + json_quote(a);
    const std::string text =
        "{\n"
        "  \"format\": \"latentbench.provenance/1\",\n"
        "  \"suite\": " + json_quote(ex.name) + ",\n"
        "  \"suite_file\": " + json_quote(suite_file_name(ex.source)) + ",\n"
        "  \"suite_hash\": " + json_quote(suite_file_hash(ex.source)) + ",\n"
        "  \"commit\": " + json_quote(build_commit()) + ",\n"
        "  \"dirty\": " + (build_dirty() ? "true" : "false") + ",\n"
        "  \"build\": " + json_quote(LB_BUILD_TYPE) + ",\n"
        "  \"seeds\": [" + seeds + "],\n"
        "  \"seed_scope\": " + json_quote(seed_scope_name(ex.seed_scope)) + ",\n"
        "  \"threads\": " + std::to_string(ex.threads > 0 ? ex.threads : num_threads()) + ",\n"
        "  \"fit_versions\": {" + versions + "},\n"
        "  \"command\": [" + command + "],\n"
        "  \"machine\": " + json_quote(machine_description()) + ",\n"
        "  \"date\": " + json_quote(utc_now()) + "\n"
        "}\n";
    write_text_atomically(run_dir + "/provenance.json", text);
}

} // namespace lb
