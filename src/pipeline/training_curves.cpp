#include "lb_paths.hpp"

#include "pipeline/training_curves.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "core/process.hpp"

namespace lb {

namespace {

constexpr const char* kPython = "/usr/bin/python3";  // Debian's: it sees python3-matplotlib

TableCell loss_cell(double v) { return std::isnan(v) ? TableCell::missing("nan") : TableCell::significant(v, 6); }

void add_rows(Table& t, const std::string& method, const TableCell& seed, const nn::TrainingCurves& curves)
{
    for (const nn::TrainingCurve& c : curves) {
        for (std::size_t e = 0; e < c.train_loss.size(); ++e) {
            t.add_row({method, seed, c.stage, TableCell::integer((long long)e + 1), loss_cell(c.train_loss[e]),
                       c.has_validation() ? loss_cell(c.validation_loss[e]) : TableCell("")});
        }
    }
}

} // namespace

Table training_curves_table(const SceneResult& r)
{
    Table t;
    t.title = "Training curves on " + r.label;
    t.caption = "Loss per epoch of every training run: the scene's autoencoder and each learned method per seed, "
                "each stage (epochs counted from 1 within a stage). The loss is each trainer's own (the "
                "autoencoder's reconstruction MSE in m², an integrator's training objective): compare a method "
                "with itself across seeds, not methods with each other.";
    t.columns = {"method", "seed", "stage", "epoch", "train_loss", "validation_loss"};
    add_rows(t, "autoencoder", TableCell::integer((long long)r.autoencoder_seed), r.autoencoder_curves);
    std::string without, shared;
    for (const MethodResult& m : r.methods) {
        const std::string name = m.point.empty() ? m.name : m.name + " [" + m.point + "]";
        if (!m.fit_of.empty()) {  // another row's fits: their curves are listed under that row
            shared += (shared.empty() ? "" : ", ") + name + " (" + m.fit_of + ")";
            continue;
        }
        bool missing = false;
        for (std::size_t k = 0; k < m.curves.size(); ++k) {
            const TableCell seed = m.seeds.size() == m.curves.size() ? TableCell::integer((long long)m.seeds[k])
                                                                     : TableCell("");
            add_rows(t, name, seed, m.curves[k]);
            // Trained (it records epochs) but no curve: an artefact from before curves were recorded.
            missing = missing || (m.curves[k].empty() && k < m.budgets.size() && m.budgets[k].recorded &&
                                  m.budgets[k].epochs_run > 0);
        }
        if (missing) without += (without.empty() ? "" : ", ") + name;
    }
    if (r.autoencoder_curves.empty()) without = "the autoencoder" + (without.empty() ? "" : ", " + without);
    if (!without.empty())
        t.add_note("no curve recorded (files made before curves were stored; refit with --force to get one): " +
                   without);
    if (!shared.empty())
        t.add_note("rows that roll out another row's fits, whose curves are that row's (listed once): " + shared);
    t.add_note("seed empty: the method ran once with its own seed (no `seeds` list); validation_loss empty: the "
               "stage has no validation split; nan: an epoch of a run resumed from a checkpoint that recorded no "
               "curve");
    return t;
}

std::string write_training_curves(const SceneResult& r, const std::string& dir)
{
    std::filesystem::create_directories(dir);
    const std::string path = dir + "/training_" + r.label + ".csv";
    write_csv(training_curves_table(r), path);
    return path;
}

std::vector<std::string> plot_training_curves(const TrainingPlotOptions& o)
{
    if (!std::filesystem::exists(kPython))
        throw Error(std::string("plots need ") + kPython + " with matplotlib and numpy (scripts/run setup installs them)");
    std::filesystem::create_directories(o.figures_dir);
    // plot_training.py prints the paths it wrote, one per line.
    const std::string list = o.figures_dir + "/training.txt";
    const std::vector<std::string> argv{kPython, std::string(LB_SOURCE_DIR) + "/scripts/plot_training.py", o.csv,
                                        "-o", o.figures_dir, "--title", o.title};
    const int status = run_process(argv, {list, o.log_path, false});
    if (status != 0) {
        std::filesystem::remove(list);
        throw Error("plotting the training curves of " + o.title + " failed with status " + std::to_string(status) +
                    " (see " + o.log_path + ")");
    }
    std::vector<std::string> figures;
    {
        std::ifstream in(list);
        for (std::string line; std::getline(in, line);) {
            if (line.size() > 4 && line.compare(line.size() - 4, 4, ".png") == 0) figures.push_back(line);
        }
    }
    std::filesystem::remove(list);
    return figures;
}

} // namespace lb
