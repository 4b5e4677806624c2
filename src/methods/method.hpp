#pragma once
// A method is everything latentbench compares: the paper's latent MLP, every
// baseline, the full-space reference, and a researcher's own integrator. Each is
// one folder (src/methods/<name>/ or baselines/<name>/) holding a `Method`
// subclass and a `MethodFactory`, registered with one line in
// baselines/builtin_methods.cpp (README, "Adding an integrator").
//
// Life of a method in a suite (src/pipeline/) or on the command line (`fit`,
// `rollout`):
//   1. parse    the factory reads its own options from an [[integrators]] entry
//               (or `fit --set key=value`), rejecting unknown keys by name;
//   2. resolve  scene-dependent defaults (widths, subspace size) are filled in once
//               the scene and its autoencoder are known; options_text() then
//               describes the resolved options completely and is part of every
//               cache key and stored in the artefact;
//   3. fit      train or precompute on the dataset's training frames and write the
//               artefact (an HDF5 file; the framework adds the method name and the
//               resolved options as attributes and commits it atomically);
//   4. load     build an `Integrator` (integrators/integrator.hpp) from the artefact;
//               rollouts, metrics and timings treat every method alike from there.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "integrators/integrator.hpp"
#include "io/toml_config.hpp"
#include "nn/weight_format.hpp"
#include "solver/newton.hpp"

namespace lb {

class Autoencoder;
struct Dataset;
class PhysicsModel;
namespace h5 {
class File;
}

/// What a method is fitted on and run with, for one scene.
struct MethodInputs {
    const Dataset* data = nullptr;
    const PhysicsModel* model = nullptr;
    /// The scene's autoencoder; set only for methods whose needs_autoencoder() is true.
    std::shared_ptr<Autoencoder> autoencoder;
    /// Where a learned method keeps its training checkpoint ("" : none).
    std::string checkpoint_path;
    /// False: train from scratch even if a matching checkpoint exists (`--force`).
    bool resume = true;
    bool progress = false;
    /// The scene's Newton settings (the ground truth was simulated with them).
    NewtonOptions newton;
    /// The files the dataset and autoencoder were read from ("" if they were built in
    /// memory), for methods that run in another process (method = "python").
    std::string dataset_path;
    std::string autoencoder_path;
    /// Weights the loaded integrator's batch-1 float inference networks stream in rollouts
    /// (`rollout --weights`); only methods whose uses_weight_format() is true read it. Not
    /// part of any fit's options: one artefact is rolled out at several precisions.
    nn::WeightFormat weights = nn::WeightFormat::f32;
};

/// Scene facts a method may take defaults from (step 2 above).
struct MethodScene {
    std::string scene_name;  ///< e.g. "cloth", "rods_translate"
    Index latent_dim = 0;    ///< of the scene's autoencoder
};

class Method {
public:
    virtual ~Method() = default;

    /// The registered method name, e.g. "latent_mlp".
    virtual std::string method_name() const = 0;
    /// Fill scene-dependent defaults (called once before options_text(), fit and load).
    virtual void resolve(const MethodScene& scene) = 0;
    /// The resolved options, canonical TOML (parsable by the factory): part of the cache
    /// key of the method's artefact and rollouts, and stored in the artefact.
    virtual std::string options_text() const = 0;
    /// The version of fit(): bumped when a code change makes fit() produce different
    /// artefacts from the same options, so that cached artefacts (their stage key includes
    /// it from version 2 on) are refitted, never reused.
    virtual int fit_version() const { return 1; }
    /// One phrase for table rows, e.g. "self_supervised, noise on, balancing on".
    virtual std::string summary() const = 0;
    /// Hidden widths of the integrator network for Table 2 ("" if it has none).
    virtual std::string layers() const { return ""; }

    virtual bool needs_autoencoder() const { return false; }
    /// True if load() honours MethodInputs::weights (its rollouts run nn::InferenceNetwork).
    virtual bool uses_weight_format() const { return false; }
    /// False for methods with nothing to fit (the full-space reference): no artefact.
    virtual bool has_artefact() const { return true; }
    /// True for the paper's own method: it supplies the rows of Tables 1 and 2.
    virtual bool is_paper_method() const { return false; }
    /// True for a method that runs user code (method = "python"): an Error in its fit or
    /// rollout fails its own units only; the suite's other methods still finish, and the
    /// tables leave its row out with a note saying why (the run then exits 1).
    virtual bool failures_contained() const { return false; }
    /// Set the seed of a learned method's training (random initialisation, shuffles,
    /// noise) before fit; part of options_text(). Returns false, changing nothing, for a
    /// method whose fit does not depend on a seed (it is then fitted once for a suite's
    /// `seeds`).
    virtual bool set_seed(std::uint64_t seed)
    {
        (void)seed;
        return false;
    }

    /// Fit on the training frames of `in.data` and write the artefact's datasets into
    /// `out` (already created; the caller adds the common attributes and commits).
    virtual void fit(const MethodInputs& in, h5::File& out) const = 0;
    /// The integrator for rollouts, from the artefact (nullptr if !has_artefact()).
    /// @param label  the name it carries in tables and rollout files
    virtual std::unique_ptr<Integrator> load(const MethodInputs& in, const h5::File* artefact,
                                             const std::string& label) const = 0;
    /// A line for the log after a rollout (e.g. solver statistics); "" for none.
    virtual std::string after_rollout(const Integrator& integrator) const
    {
        (void)integrator;
        return "";
    }
};

/// How a method is created from configuration.
struct MethodFactory {
    std::string name;         ///< `method = "..."` in experiment files, `fit --method`
    std::string description;  ///< one line for `latentbench methods`
    /// Read the method's options from `entry` (its own keys only: `name` and `method`
    /// are consumed already) over `defaults` (the suite's [training] and the scene's
    /// [scenes.training], merged; a method without training options leaves it alone).
    /// Must call entry.finish(), so unknown keys are ConfigErrors naming the key; keys of
    /// `defaults` that no method of the suite reads are rejected by the pipeline.
    std::function<std::unique_ptr<Method>(ConfigTable& entry, ConfigTable& defaults)> parse;
    /// TOML options that make the method fit in seconds on a small scene: used by the
    /// conformance test (tests/methods/) that every registered method must pass.
    std::string quick_options;
};

} // namespace lb
