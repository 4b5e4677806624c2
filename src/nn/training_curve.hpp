#pragma once
// The loss per epoch of a training run (its "curve"), kept by the shared training loop
// (nn/training_loop.hpp) in its summary and its checkpoint, and stored by every trainer
// in what it writes: the autoencoder file, a method's artefact.
//
// A file may hold several stages (the autoencoder's reconstruction training and its
// physics fine-tuning, Tan et al.'s three stages), in the order they ran:
//   attribute  <prefix>training_curve.stages  "autoencoder,physics" (comma-separated)
//   datasets   <prefix>training_curve/<stage>/train_loss       (epochs)
//              <prefix>training_curve/<stage>/validation_loss  (epochs; only with validation)
// An entry is NaN where the loss of that epoch is not known (a run resumed from a
// checkpoint written before curves were recorded). A file without the attribute (written
// before curves were recorded) has no curve: load_training_curves returns none.
#include <string>
#include <vector>

namespace lb::h5 {
class File;
}

namespace lb::nn {

struct TrainingCurve {
    std::string stage;                    ///< e.g. "autoencoder", "integrator", "stage1"
    std::vector<double> train_loss;       ///< one per epoch: the epoch's (training-mode) loss
    std::vector<double> validation_loss;  ///< empty (no validation) or one per epoch

    int epochs() const { return int(train_loss.size()); }
    bool has_validation() const { return !validation_loss.empty(); }
};

using TrainingCurves = std::vector<TrainingCurve>;

/// `<group>/train_loss` and, if any, `<group>/validation_loss` (nothing for 0 epochs).
void save_curve_data(h5::File& file, const std::string& group, const TrainingCurve& curve);
/// What save_curve_data wrote (an empty curve if `<group>/train_loss` is absent); IoError
/// naming the file and dataset if a dataset is not a vector or the lengths differ.
TrainingCurve load_curve_data(const h5::File& file, const std::string& group);

/// Every stage with at least one epoch, in order (layout above). Stage names are
/// letters, digits and '_' (std::invalid_argument otherwise: a programming error).
void save_training_curves(h5::File& file, const std::string& prefix, const TrainingCurves& curves);
/// The stages saved under `prefix`; none if the file has no curve. IoError naming the file
/// and the stage if one is listed but missing or malformed.
TrainingCurves load_training_curves(const h5::File& file, const std::string& prefix);

/// The last training loss of the last stage that has one (NaN if none): a file's
/// `final_loss` equals it.
double last_train_loss(const TrainingCurves& curves);

/// One line, e.g. "120 epochs; loss 3.1e-02 first, 2.2e-04 min (epoch 117), 2.3e-04 last;
/// validation 4.0e-04 min (epoch 110), 4.4e-04 last". Epochs are 1-based.
std::string describe_curve(const TrainingCurve& curve);

} // namespace lb::nn
