#pragma once
// A small scene with a briefly trained autoencoder, shared by the fulton_cubature tests.
#include "lb_paths.hpp"
#include <memory>

#include "core/log.hpp"
#include "latent/autoencoder.hpp"
#include "scene/scene.hpp"
#include "support/small_scene.hpp"

namespace lb::testing {

struct FultonProblem {
    Dataset data;
    std::unique_ptr<PhysicsModel> model;
    std::shared_ptr<Autoencoder> ae;

    /// The first `frames` frames of the scene's small variant, the first `train_frames`
    /// of them for training; an autoencoder (latent 3, hidden 32-32, PCA 12) trained for
    /// `epochs` epochs on those (hidden widths and PCA size overridable).
    FultonProblem(const std::string& scene, int frames, int train_frames, int epochs = 300, Index hidden = 32,
                  Index pca = 12)
    {
        data = simulate_small_scene(scene, frames, train_frames);
        model = std::make_unique<PhysicsModel>(data.physics);
        AutoencoderOptions ao;
        ao.latent_dim = 3;
        ao.hidden = {hidden, hidden};
        ao.pca_dim = pca;
        ao.epochs = epochs;
        ao.batch_size = 64;
        ao.learning_rate = 1e-3;
        ao.patience = 0;
        ao.progress = false;
        ae = std::make_shared<Autoencoder>(data.physics, ao, 3);
        train_autoencoder(*ae, data, ao);
    }

    /// Reconstructions decode(encode(x)) of frames [begin, end) of the first sequence (3N × S).
    MatrixXd reconstructions(Index begin, Index end)
    {
        const SequenceData& seq = data.sequences[0];
        MatrixXd X = seq.positions.middleRows(begin, end - begin).transpose();
        MatrixXd T(3 * Index(data.physics.bc_indices.size()), X.cols());
        for (Index j = 0; j < X.cols(); ++j) T.col(j) = seq.bc_positions.row(begin + j).transpose();
        return ae->decode(ae->encode(X), T);
    }
};

} // namespace lb::testing
