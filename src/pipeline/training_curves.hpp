#pragma once
// The training curves of a suite's scene: every training run's loss per epoch (the
// scene's autoencoder, each learned method per seed, each stage), read from the
// autoencoder file and the artefacts (nn/training_curve.hpp), as
//   tables/training_<scene>.csv   long format, one row per method, seed, stage and epoch:
//                                 method, seed, stage, epoch, train_loss, validation_loss
//                                 (seed empty for a run without a seed list, validation
//                                 empty where the stage has none, "nan" where not recorded)
//   figures/<scene>/training_<method>.png   every seed in one plot, stages one after the
//                                 other, log-scale loss (scripts/plot_training.py)
// Files written before curves were recorded have none: their method has no rows (a note
// of the table names it) and no figure.
#include <string>
#include <vector>

#include "io/table.hpp"
#include "pipeline/report.hpp"

namespace lb {

/// The long table above; the autoencoder's rows come first, as method "autoencoder".
Table training_curves_table(const SceneResult& scene);

/// Write `<dir>/training_<label>.csv` (atomically) and return its path.
std::string write_training_curves(const SceneResult& scene, const std::string& dir);

struct TrainingPlotOptions {
    std::string csv;          ///< the table write_training_curves wrote
    std::string figures_dir;  ///< figures/<scene>: training_<method>.png go here
    std::string title;        ///< the scene's label
    std::string log_path;     ///< the script's messages are appended here
};

/// One PNG per method of the table (scripts/plot_training.py with Debian's /usr/bin/python3,
/// an argument vector, never a shell); returns their paths. Error naming the scene and the
/// log on failure.
std::vector<std::string> plot_training_curves(const TrainingPlotOptions& options);

} // namespace lb
