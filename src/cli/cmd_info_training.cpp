// `latentbench info` on what training writes: a method's artefact or an autoencoder file,
// with a summary of each training stage's loss curve (nn/training_curve.hpp).
#include <cmath>
#include <cstdio>

#include "cli/commands.hpp"
#include "io/hdf5.hpp"
#include "methods/artefact.hpp"
#include "nn/training_curve.hpp"

namespace lb::cli {

namespace {

constexpr const char* kAutoencoderFormat = "latentbench.autoencoder/1";

std::string text_attribute(const h5::File& f, const std::string& key)
{
    return f.has_attribute("/", key) ? f.attribute_string("/", key) : std::string("?");
}

std::string int_attribute(const h5::File& f, const std::string& key)
{
    return f.has_attribute("/", key) ? std::to_string(f.attribute_int("/", key)) : std::string("?");
}

void print_curves(const h5::File& f, bool trains)
{
    const nn::TrainingCurves curves = nn::load_training_curves(f, "");
    if (curves.empty()) {
        std::printf("  training curve: %s\n", trains ? "none recorded (written before curves were stored)"
                                                     : "none (this method trains nothing)");
        return;
    }
    for (const nn::TrainingCurve& c : curves)
        std::printf("  training curve, %s: %s\n", c.stage.c_str(), nn::describe_curve(c).c_str());
    if (f.has_attribute("/", "final_loss")) {
        const double final_loss = f.attribute_double("/", "final_loss");
        const double last = nn::last_train_loss(curves);
        std::printf("  final_loss %.6g%s\n", final_loss,
                    last == final_loss ? " (the curve's last value)" : " (differs from the curve's last value!)");
    }
}

} // namespace

bool describe_training_file(const std::string& path)
{
    const h5::File f = h5::File::open(path);
    if (!f.has_attribute("/", "format")) return false;
    const std::string format = f.attribute_string("/", "format");
    if (format == kAutoencoderFormat) {
        std::printf("autoencoder of scene %s: latent %s, pca %s, hidden %s, encoding %s, seed %s\n",
                    text_attribute(f, "scene").c_str(), int_attribute(f, "latent_dim").c_str(),
                    int_attribute(f, "pca_dim").c_str(), text_attribute(f, "hidden").c_str(),
                    text_attribute(f, "encoding").c_str(), text_attribute(f, "seed").c_str());
        print_curves(f, true);
        return true;
    }
    if (!is_artefact(f)) return false;
    const ArtefactInfo info = read_artefact_info(f);
    std::printf("artefact of method %s on scene %s", info.method.c_str(), info.scene.c_str());
    const bool trains = f.has_attribute("/", "epochs_run");
    if (trains) {
        std::printf(": %lld epochs", f.attribute_int("/", "epochs_run"));
        if (f.has_attribute("/", "epochs_budget")) std::printf(" of %lld", f.attribute_int("/", "epochs_budget"));
        if (f.has_attribute("/", "train_seconds")) std::printf(", %.1f s", f.attribute_double("/", "train_seconds"));
    }
    std::printf("\n");
    print_curves(f, trains);
    return true;
}

} // namespace lb::cli
