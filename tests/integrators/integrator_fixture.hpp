#pragma once
// A tiny learning problem shared by the integrator tests: the small cantilever
// (few frames), a small PCA-initialised autoencoder, a small integrator; the scene, frame
// count and autoencoder widths can be chosen.
#include "lb_paths.hpp"
#include <memory>
#include <vector>

#include "core/log.hpp"
#include "integrators/trainer.hpp"
#include "scene/scene.hpp"
#include "support/small_scene.hpp"

namespace lb::testing {

struct TinyProblem {
    Dataset data;
    std::unique_ptr<PhysicsModel> model;
    std::shared_ptr<Autoencoder> ae;
    TrainingSamples samples;

    /// @param hidden, pca  the autoencoder's widths (the paper's decoder: {200, 200, 200}, 50)
    explicit TinyProblem(const std::string& scene = "cantilever", int frames = 24, Index latent = 3,
                         std::vector<Index> hidden = {16, 16}, Index pca = 8)
    {
        data = simulate_small_scene(scene, frames);
        model = std::make_unique<PhysicsModel>(data.physics);
        AutoencoderOptions ao;
        ao.latent_dim = latent;
        ao.hidden = std::move(hidden);
        ao.pca_dim = pca;
        ao.progress = false;
        ae = std::make_shared<Autoencoder>(data.physics, ao, 7);
        ae->initialize_pca(ae->encoding().to_features(training_frames(data).positions));
        samples = make_training_samples(*ae, data);
    }
};

} // namespace lb::testing
