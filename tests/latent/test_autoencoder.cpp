// The autoencoder: architecture, PCA initialisation, derivatives, save/load,
// reproducible training with checkpoints, and reconstruction accuracy on the small cloth.
#include "paper/scene_defaults.hpp"
#include "lb_paths.hpp"
#include <gtest/gtest.h>
#include <limits>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>

#include "core/error.hpp"
#include "core/process.hpp"
#include "core/log.hpp"
#include "io/hdf5.hpp"
#include "latent/autoencoder.hpp"
#include "latent/latent_test_support.hpp"
#include "nn/linear.hpp"
#include "support/finite_difference.hpp"

namespace lb {
namespace {

using latent_test::random_matrix;
using latent_test::targets_of;
namespace fs = std::filesystem;

std::string tmp_path(const std::string& name)
{
    const fs::path dir = fs::path(LB_TEST_TMP_DIR) / "latent";
    fs::create_directories(dir);
    return (dir / name).string();
}

/// Every parameter and buffer of both networks, in order (for bitwise comparisons).
std::vector<MatrixXd> state_of(Autoencoder& ae)
{
    std::vector<MatrixXd> out;
    for (nn::Sequential* net : {&ae.encoder(), &ae.decoder()}) {
        for (const auto& p : net->parameters()) out.emplace_back(p.value);
        for (const auto& b : net->buffers()) out.emplace_back(b.value);
    }
    return out;
}

bool same_state(Autoencoder& a, Autoencoder& b)
{
    const auto sa = state_of(a), sb = state_of(b);
    if (sa.size() != sb.size()) return false;
    for (std::size_t i = 0; i < sa.size(); ++i)
        if (sa[i].rows() != sb[i].rows() || sa[i].cols() != sb[i].cols() || sa[i] != sb[i]) return false;
    return true;
}

AutoencoderOptions tiny_options()
{
    AutoencoderOptions o;
    o.latent_dim = 3;
    o.hidden = {8, 8};
    o.pca_dim = 6;
    o.batch_size = 32;
    o.learning_rate = 1e-3;
    o.epochs = 4;
    o.patience = 0;
    o.progress = false;
    return o;
}

/// Make BatchNorm's eval-mode affine maps non-trivial (fresh layers have mean 0, var 1).
void randomize_batch_norm(Autoencoder& ae, Rng& rng)
{
    for (nn::Sequential* net : {&ae.encoder(), &ae.decoder()}) {
        for (auto& b : net->buffers()) {
            if (b.name.find("running_mean") != std::string::npos) b.value = random_matrix(b.value.rows(), 1, rng, -0.5, 0.5);
            if (b.name.find("running_var") != std::string::npos) b.value = random_matrix(b.value.rows(), 1, rng, 0.5, 2.0);
        }
    }
}

// ---- architecture and PCA ----------------------------------------------------------

TEST(Autoencoder, ArchitectureFollowsTheOptions)
{
    const PhysicsSpec p = latent_test::cloth_physics();  // 20 vertices: F = 60
    AutoencoderOptions o = tiny_options();
    o.hidden = {16, 8};
    o.pca_dim = 10;
    Autoencoder ae(p, o, 0);
    EXPECT_EQ(ae.num_features(), 60);
    EXPECT_EQ(ae.encoder().in_features(), 60);
    EXPECT_EQ(ae.encoder().out_features(), 3);
    EXPECT_EQ(ae.decoder().in_features(), 3);
    EXPECT_EQ(ae.decoder().out_features(), 60);
    // Encoder: PCA Linear(60 → 10), res(10 → 8), res(8 → 16), Linear(16 → 3) (hidden mirrored).
    ASSERT_EQ(ae.encoder().size(), 4);
    auto* first = dynamic_cast<nn::Linear*>(&ae.encoder().layer(0));
    ASSERT_NE(first, nullptr);
    EXPECT_EQ(first->weight().rows(), 10);
    EXPECT_EQ(ae.encoder().layer(1).out_features(), 8);
    EXPECT_EQ(ae.encoder().layer(2).out_features(), 16);
    // Decoder: res(3 → 16), res(16 → 8), Linear(8 → 10), PCA Linear(10 → 60).
    ASSERT_EQ(ae.decoder().size(), 4);
    EXPECT_EQ(ae.decoder().layer(0).out_features(), 16);
    EXPECT_EQ(ae.decoder().layer(1).out_features(), 8);
    auto* last = dynamic_cast<nn::Linear*>(&ae.decoder().layer(3));
    ASSERT_NE(last, nullptr);
    EXPECT_EQ(last->weight().cols(), 10);

    o.pca_dim = 500;  // clamped to the feature count
    EXPECT_EQ(Autoencoder(p, o, 0).options().pca_dim, 60);
    o.latent_dim = 0;
    EXPECT_THROW(Autoencoder(p, o, 0), ConfigError);
}

TEST(Autoencoder, PcaLayersReproduceDataOfRankAtMostPcaDim)
{
    // Frames x = rest + Σ_{k<4} a_k(s) m_k: the centred features have rank ≤ 4 < pca_dim 6,
    // so the encoder's first and the decoder's last layer alone (the body of the network
    // skipped) must reproduce every frame: U(Uᵀ(f − μ)) + μ = f, and then x exactly.
    const PhysicsSpec p = latent_test::cloth_physics();
    Autoencoder ae(p, tiny_options(), 0);
    Rng rng(11);
    const VectorXd rest = flatten(p.mesh.rest_positions);
    const MatrixXd modes = random_matrix(rest.size(), 4, rng, -0.2, 0.2);
    const MatrixXd X = (modes * random_matrix(4, 30, rng)).colwise() + rest;
    const MatrixXd F = ae.encoding().to_features(X);
    EXPECT_NEAR(ae.initialize_pca(F), 1.0, 1e-12);  // explained variance
    EXPECT_EQ(ae.options().pca_dim, 4);  // clamped to the data's rank (issue 39)

    auto& enc_pca = ae.encoder().layer(0);
    auto& dec_pca = ae.decoder().layer(ae.decoder().size() - 1);
    const MatrixXd F_back = dec_pca.forward(enc_pca.forward(F, false), false);
    EXPECT_LE((F_back - F).cwiseAbs().maxCoeff(), 1e-12);
    const MatrixXd X_back = ae.encoding().to_positions(F_back, targets_of(X, p.bc_indices));
    EXPECT_LE((X_back - X).cwiseAbs().maxCoeff(), 1e-12);

    // The PCA coordinates are Uᵀ(f − μ) with orthonormal U: W_enc = W_decᵀ.
    const auto& W_enc = dynamic_cast<nn::Linear&>(enc_pca).weight();
    const auto& W_dec = dynamic_cast<nn::Linear&>(dec_pca).weight();
    EXPECT_EQ(MatrixXd(W_enc.transpose()), W_dec);
    EXPECT_LE((W_enc * W_dec - MatrixXd::Identity(4, 4)).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Autoencoder, PcaLayerNeverWiderThanTheDataSoConstantOffsetsStayExact)
{
    // Issue 39: frames whose Dirichlet corners translate rigidly together (their offsets
    // from the Dirichlet centroid are constant) plus 3 modes that vanish on them. The
    // features have rank 3 < pca_dim 6: the PCA layer must be 3 wide, and then any latent,
    // through the untrained (random) network, decodes the Dirichlet vertices exactly onto
    // their targets. With zero-variance completion columns (the old layer) the random
    // network's output reaches them and moves the corners by centimetres.
    const PhysicsSpec p = latent_test::cloth_physics();
    Autoencoder ae(p, tiny_options(), 0);  // pca_dim 6
    Rng rng(21);
    const VectorXd rest = flatten(p.mesh.rest_positions);
    MatrixXd modes = random_matrix(rest.size(), 3, rng, -0.2, 0.2);
    for (int b : p.bc_indices) modes.middleRows<3>(3 * Index(b)).setZero();
    MatrixXd X = (modes * random_matrix(3, 40, rng)).colwise() + rest;
    for (Index s = 0; s < X.cols(); ++s) {
        const Vector3d shift = random_matrix(3, 1, rng, -1.0, 1.0).col(0);
        for (Index v = 0; v < X.rows() / 3; ++v) X.block<3, 1>(3 * v, s) += shift;
    }
    ae.initialize_pca(ae.encoding().to_features(X));
    EXPECT_EQ(ae.options().pca_dim, 3);
    EXPECT_EQ(ae.decoder().layer(ae.decoder().size() - 1).in_features(), 3);

    const MatrixXd Z = random_matrix(3, 25, rng, -50.0, 50.0);  // far outside any data
    const MatrixXd targets = targets_of(X.leftCols(25), p.bc_indices);
    const MatrixXd decoded = ae.decode(Z, targets);
    double worst = 0.0;
    for (size_t b = 0; b < p.bc_indices.size(); ++b)
        worst = std::max(worst, (decoded.middleRows<3>(3 * Index(p.bc_indices[b])) - targets.middleRows<3>(3 * Index(b)))
                                    .cwiseAbs()
                                    .maxCoeff());
    EXPECT_LE(worst, 1e-9) << "decoded Dirichlet vertices off their targets by " << worst << " m";
}

TEST(Autoencoder, PcaDimIsClampedToFramesMinusOne)
{
    const PhysicsSpec p = latent_test::cloth_physics();
    Autoencoder ae(p, tiny_options(), 0);  // pca_dim 6
    Rng rng(12);
    const MatrixXd X = random_matrix(ae.encoding().num_dofs(), 4, rng);  // 4 frames: rank ≤ 3
    ae.initialize_pca(ae.encoding().to_features(X));
    EXPECT_EQ(ae.options().pca_dim, 3);
    EXPECT_EQ(ae.encoder().layer(0).out_features(), 3);
    EXPECT_EQ(ae.decoder().layer(ae.decoder().size() - 1).in_features(), 3);
    EXPECT_THROW(ae.initialize_pca(ae.encoding().to_features(X.leftCols(1))), ConfigError);
}

// ---- derivatives and consistency -------------------------------------------------------

class DecoderVjp : public ::testing::TestWithParam<int> { };

TEST_P(DecoderVjp, MatchesFiniteDifferencesOfDecode)
{
    // L(z) = φ(decode(z, targets)), φ(x) = Σ w_i sin(x_i) + ½ c_i x_i², eval mode:
    // ∂L/∂z = decoder_vjp(z, ∇φ(x)), column by column.
    // 0 cloth, 1 rods (translation frame), 2 solid, 3 rods in the boundary's rigid frame
    const int param = GetParam();
    const PhysicsSpec p = param == 0 ? latent_test::cloth_physics()
                          : param == 2 ? latent_test::solid_physics()
                                       : latent_test::rod_physics();
    AutoencoderOptions options = tiny_options();
    if (param >= 2) options.frame = EncodingFrame::rigid;
    Autoencoder ae(p, options, 3);
    Rng rng(13);
    const VectorXd rest = flatten(p.mesh.rest_positions);
    const MatrixXd X = random_matrix(rest.size(), 20, rng, -0.1, 0.1).colwise() + rest;
    ae.initialize_pca(ae.encoding().to_features(X));
    randomize_batch_norm(ae, rng);

    const Index n = ae.encoding().num_dofs();
    const VectorXd w = random_matrix(n, 1, rng), c = random_matrix(n, 1, rng, 0.5, 2.0);
    auto grad_phi = [&](const MatrixXd& x) -> MatrixXd {
        return (w.replicate(1, x.cols()).array() * x.array().cos() + c.replicate(1, x.cols()).array() * x.array()).matrix();
    };
    auto phi = [&](const VectorXd& x) { return (w.array() * x.array().sin() + 0.5 * c.array() * x.array().square()).sum(); };

    const MatrixXd Z = random_matrix(3, 3, rng);
    const MatrixXd T = targets_of(X.leftCols(3), p.bc_indices);
    const MatrixXd G = ae.decoder_vjp(Z, grad_phi(ae.decode(Z, T)), T);
    ASSERT_EQ(G.rows(), 3);
    ASSERT_EQ(G.cols(), 3);
    for (Index s = 0; s < 3; ++s) {
        const MatrixXd T_s = T.col(s);
        EXPECT_TRUE(lb::testing::check_gradient(
            [&](const VectorXd& z) { return phi(ae.decode(z, T_s).col(0)); },
            [&](const VectorXd&) -> VectorXd { return G.col(s); }, Z.col(s), {1e-6, 1e-6, 1.0},
            "decoder_vjp column " + std::to_string(s)));
    }
}

std::string decoder_vjp_case_name(const ::testing::TestParamInfo<int>& info)
{
    static const char* const names[] = {"cloth", "rods", "solid_rigid", "rods_rigid"};
    return names[info.param];
}

INSTANTIATE_TEST_SUITE_P(Physics, DecoderVjp, ::testing::Values(0, 1, 2, 3), decoder_vjp_case_name);

TEST(Autoencoder, EncodeAndDecodeComposeTheEncodingAndTheNetworks)
{
    const PhysicsSpec p = latent_test::rod_physics();
    Autoencoder ae(p, tiny_options(), 4);
    Rng rng(14);
    const MatrixXd X = random_matrix(ae.encoding().num_dofs(), 5, rng);
    const MatrixXd T = targets_of(X, p.bc_indices);
    const MatrixXd Z = ae.encode(X);
    EXPECT_EQ(Z, ae.encoder().forward(ae.encoding().to_features(X), false));
    EXPECT_EQ(ae.decode(Z, T), ae.encoding().to_positions(ae.decoder().forward(Z, false), T));
    EXPECT_EQ(ae.decode_features(Z), ae.decoder().forward(Z, false));
    // Rods: decoded roots sit exactly on their targets.
    const MatrixXd Y = ae.decode(Z, T);
    for (std::size_t b = 0; b < p.bc_indices.size(); ++b)
        EXPECT_EQ(Y.middleRows<3>(3 * p.bc_indices[b]), T.middleRows<3>(3 * Index(b)));
}

// ---- save / load -------------------------------------------------------------------------

TEST(Autoencoder, SaveLoadRoundTripIsExact)
{
    const Dataset data = latent_test::small_cloth_prefix(120);
    AutoencoderOptions o = tiny_options();
    o.epochs = 2;
    Autoencoder ae(data.physics, o, 5);
    train_autoencoder(ae, data, o);  // non-trivial BatchNorm statistics
    const std::string path = tmp_path("roundtrip_ae.h5");
    ae.save(path);

    Autoencoder loaded = Autoencoder::load(path, data.physics);
    EXPECT_EQ(loaded.latent_dim(), ae.latent_dim());
    EXPECT_EQ(loaded.options().pca_dim, ae.options().pca_dim);
    EXPECT_EQ(loaded.options().hidden, ae.options().hidden);
    EXPECT_EQ(loaded.options().batch_norm, ae.options().batch_norm);
    EXPECT_EQ(loaded.options().residual, ae.options().residual);
    EXPECT_EQ(loaded.scene_name(), "cloth");
    EXPECT_EQ(loaded.seed(), 5u);
    EXPECT_TRUE(same_state(ae, loaded));

    const FrameSet frames = training_frames(data);
    const MatrixXd Z = ae.encode(frames.positions);
    EXPECT_EQ(loaded.encode(frames.positions), Z);
    EXPECT_EQ(loaded.decode(Z, frames.bc_targets), ae.decode(Z, frames.bc_targets));

    h5::File f = h5::File::open(path);
    for (const char* key : {"latent_dim", "pca_dim", "hidden", "batch_norm", "residual", "encoding", "scene"})
        EXPECT_TRUE(f.has_attribute("/", key)) << key;
    EXPECT_EQ(f.attribute_string("/", "encoding"), "dirichlet_mean");
    EXPECT_EQ(f.attribute_string("/", "hidden"), "8,8");
}

// The rigid frame (issue 14) is stored as the encoding kind and restored by load.
TEST(Autoencoder, SaveLoadKeepsTheRigidFrame)
{
    const PhysicsSpec p = latent_test::solid_physics();
    AutoencoderOptions o = tiny_options();
    o.frame = EncodingFrame::rigid;
    Autoencoder ae(p, o, 7);
    Rng rng(17);
    const VectorXd rest = flatten(p.mesh.rest_positions);
    const MatrixXd X = random_matrix(rest.size(), 12, rng, -0.02, 0.02).colwise() + rest;
    ae.initialize_pca(ae.encoding().to_features(X));
    const std::string path = tmp_path("rigid_ae.h5");
    ae.save(path);
    EXPECT_EQ(h5::File::open(path).attribute_string("/", "encoding"), "dirichlet_rigid");
    Autoencoder loaded = Autoencoder::load(path, p);
    EXPECT_EQ(loaded.encoding().frame(), EncodingFrame::rigid);
    EXPECT_EQ(loaded.options().frame, EncodingFrame::rigid);
    const MatrixXd T = targets_of(X, p.bc_indices);
    const MatrixXd Z = ae.encode(X);
    EXPECT_EQ(loaded.encode(X), Z);
    EXPECT_EQ(loaded.decode(Z, T), ae.decode(Z, T));
    // the same networks read in the translation frame would decode differently: the
    // kind is what tells them apart
    Autoencoder translation(p, tiny_options(), 7);
    EXPECT_STREQ(translation.encoding().kind_name(), "dirichlet_mean");
}

TEST(Autoencoder, LoadRejectsMismatchedPhysicsAndForeignFiles)
{
    const PhysicsSpec cloth = latent_test::cloth_physics();
    Autoencoder ae(cloth, tiny_options(), 0);
    const std::string path = tmp_path("mismatch_ae.h5");
    ae.save(path);

    PhysicsSpec bigger = cloth;
    bigger.mesh = make_cloth_grid({6, 4, 1.0, 0.75, Vector3d::Zero()});
    try {
        Autoencoder::load(path, bigger);
        FAIL() << "expected IoError";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("60 features"), std::string::npos) << e.what();
    }
    EXPECT_THROW(Autoencoder::load(path, latent_test::rod_physics()), IoError);

    const std::string dataset_path = tmp_path("not_an_ae.h5");
    save_dataset(latent_test::small_cloth_prefix(5), dataset_path);
    EXPECT_THROW(Autoencoder::load(dataset_path, cloth), IoError);
    EXPECT_THROW(Autoencoder::load(tmp_path("missing.h5"), cloth), IoError);
}

// ---- training ---------------------------------------------------------------------------

TEST(AutoencoderTraining, SameSeedGivesBitwiseIdenticalWeights)
{
    const Dataset data = latent_test::small_cloth_prefix(150);
    AutoencoderOptions o = tiny_options();
    o.epochs = 3;
    Autoencoder a(data.physics, o, 1), b(data.physics, o, 1);
    const auto sa = train_autoencoder(a, data, o);
    const auto sb = train_autoencoder(b, data, o);
    EXPECT_TRUE(same_state(a, b));
    EXPECT_EQ(sa.best_validation, sb.best_validation);

    AutoencoderOptions other = o;
    other.seed = 2;  // different shuffling only
    Autoencoder c(data.physics, other, 1);
    train_autoencoder(c, data, other);
    EXPECT_FALSE(same_state(a, c));
}

TEST(AutoencoderTraining, ResumingFromACheckpointEqualsTrainingStraight)
{
    const Dataset data = latent_test::small_cloth_prefix(150);
    AutoencoderOptions o = tiny_options();
    o.epochs = 6;
    o.checkpoint_every = 3;
    Autoencoder straight(data.physics, o, 7);
    const auto s_straight = train_autoencoder(straight, data, o);

    // A run killed after epoch 3 (its checkpoint written), then the same run again.
    const std::string ckpt = tmp_path("resume_checkpoint.h5");
    fs::remove(ckpt);
    AutoencoderOptions killed = o;
    killed.checkpoint_path = ckpt;
    killed.interrupt = [](int epochs_done) { return epochs_done == 3; };
    Autoencoder part(data.physics, killed, 7);
    const auto s_part = train_autoencoder(part, data, killed);
    EXPECT_FALSE(s_part.resumed);
    EXPECT_TRUE(s_part.interrupted);
    EXPECT_EQ(s_part.epochs_run, 3);
    ASSERT_TRUE(fs::exists(ckpt));

    AutoencoderOptions second = o;
    second.checkpoint_path = ckpt;
    Autoencoder resumed(data.physics, second, 7);
    const auto s_resumed = train_autoencoder(resumed, data, second);
    EXPECT_TRUE(s_resumed.resumed);
    EXPECT_EQ(s_resumed.epochs_run, 6);
    EXPECT_EQ(s_resumed.best_epoch, s_straight.best_epoch);
    EXPECT_EQ(s_resumed.best_validation, s_straight.best_validation);
    EXPECT_EQ(s_resumed.final_loss, s_straight.final_loss);
    EXPECT_TRUE(same_state(straight, resumed)) << "N + resume N epochs differs from 2N straight";
}

// ---- checkpoints made from other inputs are set aside, never resumed -------------------

struct AeChange {
    const char* name;
    const char* reason;  ///< the fingerprint part named in the refusal
    std::function<void(AutoencoderOptions&, std::uint64_t&, int&)> apply;  ///< options, init seed, frames
};

void PrintTo(const AeChange& c, std::ostream* os) { *os << c.name; }

class AeChangedInput : public ::testing::TestWithParam<AeChange> { };

TEST_P(AeChangedInput, IsNotResumed)
{
    const AeChange& change = GetParam();
    const std::string ckpt = tmp_path(std::string("changed_") + change.name + ".h5");
    fs::remove(ckpt);
    for (int n = 1; fs::remove(ckpt + ".stale." + std::to_string(n)); ++n) { }
    AutoencoderOptions o = tiny_options();
    o.epochs = 3;
    o.checkpoint_every = 2;
    o.checkpoint_path = ckpt;
    const Dataset data = latent_test::small_cloth_prefix(150);
    Autoencoder first(data.physics, o, 7);
    ASSERT_FALSE(train_autoencoder(first, data, o).resumed);
    ASSERT_TRUE(fs::exists(ckpt));

    std::uint64_t init_seed = 7;
    int frames = 150;
    change.apply(o, init_seed, frames);
    const Dataset other = frames == 150 ? data : latent_test::small_cloth_prefix(frames);
    Autoencoder second(other.physics, o, init_seed);
    const auto s = train_autoencoder(second, other, o);
    EXPECT_FALSE(s.resumed);
    EXPECT_EQ(s.epochs_run, o.epochs);
    EXPECT_GT(s.final_loss, 0.0);
    EXPECT_NE(s.checkpoint_refused.find(change.reason), std::string::npos)
        << "reason '" << s.checkpoint_refused << "' does not mention '" << change.reason << "'";
    EXPECT_TRUE(fs::exists(ckpt + ".stale.1"));
}

INSTANTIATE_TEST_SUITE_P(
    EveryInput, AeChangedInput,
    ::testing::Values(
        AeChange{"epochs", "options", [](auto& o, auto&, auto&) { o.epochs = 4; }},
        AeChange{"learning_rate", "options", [](auto& o, auto&, auto&) { o.learning_rate = 2e-3; }},
        AeChange{"batch_size", "options", [](auto& o, auto&, auto&) { o.batch_size = 64; }},
        AeChange{"validation_fraction", "options", [](auto& o, auto&, auto&) { o.validation_fraction = 0.2; }},
        AeChange{"patience", "options", [](auto& o, auto&, auto&) { o.patience = 5; }},
        AeChange{"seed", "options", [](auto& o, auto&, auto&) { o.seed = 3; }},
        AeChange{"hidden", "options", [](auto& o, auto&, auto&) { o.hidden = {6, 6}; }},
        AeChange{"latent_dim", "options", [](auto& o, auto&, auto&) { o.latent_dim = 4; }},
        AeChange{"init_seed", "options", [](auto&, auto& seed, auto&) { seed = 8; }},
        AeChange{"data", "data", [](auto&, auto&, auto& frames) { frames = 151; }},
        AeChange{"resume_off", "resume is off", [](auto& o, auto&, auto&) { o.resume = false; }}),
    [](const auto& info) { return std::string(info.param.name); });

// A checkpoint whose fingerprint claims to match but whose tensors have other shapes is
// refused by the shape checks, before anything is copied, instead of crashing.
TEST(AutoencoderTraining, CheckpointOfOtherShapesIsRefused)
{
    const Dataset data = latent_test::small_cloth_prefix(150);
    const std::string real = tmp_path("shape_real.h5"), narrow = tmp_path("shape_narrow.h5");
    for (const auto& f : {real, narrow}) fs::remove(f);
    for (int n = 1; fs::remove(real + ".stale." + std::to_string(n)); ++n) { }
    AutoencoderOptions o = tiny_options();
    o.epochs = 2;
    o.checkpoint_path = real;
    Autoencoder a(data.physics, o, 7);
    train_autoencoder(a, data, o);
    AutoencoderOptions n = o;
    n.hidden = {6, 6};
    n.checkpoint_path = narrow;
    Autoencoder b(data.physics, n, 7);
    train_autoencoder(b, data, n);
    {
        const h5::File from = h5::File::open(real);
        h5::File forged = h5::File::open(narrow, true);
        for (const char* key : {"fingerprint.parts", "fingerprint.options", "fingerprint.data", "fingerprint.network"})
            forged.set_attribute("/", key, from.attribute_string("/", key));
    }
    fs::copy_file(narrow, real, fs::copy_options::overwrite_existing);
    Autoencoder c(data.physics, o, 7);
    const auto s = train_autoencoder(c, data, o);
    EXPECT_FALSE(s.resumed);
    EXPECT_NE(s.checkpoint_refused.find("shapes differ"), std::string::npos) << s.checkpoint_refused;
    EXPECT_TRUE(fs::exists(real + ".stale.1"));
    EXPECT_TRUE(same_state(a, c)) << "a refused checkpoint left traces in the weights";
}

TEST(AutoencoderTraining, SmallClothReconstructsWithinOnePercentOfTheDiagonal)
{
    // Acceptance: the small cloth (8 × 6 vertices, 144 features), its 300 training frames
    // (every 10th held out for validation: 270 / 30), latent 4, the paper's architecture
    // shape (BatchNorm, residual blocks, Swish, PCA 50) with narrower hidden layers {64, 64}
    // and a larger step (lr 1e-3, batch 64) so that it trains in seconds. A correct
    // implementation reaches 5–6e-3 of the bounding-box diagonal in 800 epochs (≈ 8 s on
    // one core; seeds 0–3 at 600 epochs gave 6.1–7.4e-3; linear PCA with 4 components
    // gives 1.9e-3 on these frames, the network gets there with longer training).
    // Threshold: 1e-2.
    const Dataset data = latent_test::small_cloth_prefix(300);
    ASSERT_EQ(data.sequences.at(0).train_frames, 300);
    AutoencoderOptions o;
    o.latent_dim = 4;
    o.hidden = {64, 64};
    o.pca_dim = 50;
    o.learning_rate = 1e-3;
    o.batch_size = 64;
    o.epochs = 800;
    o.patience = 0;
    o.seed = 0;
    o.progress = false;
    Autoencoder ae(data.physics, o, 0);
    const auto s = train_autoencoder(ae, data, o);
    RecordProperty("validation_relative_rmse", std::to_string(s.validation_relative_rmse));
    RecordProperty("seconds", std::to_string(s.seconds));
    EXPECT_EQ(s.epochs_run, 800);
    EXPECT_LT(s.validation_relative_rmse, 1e-2);
    EXPECT_GT(s.best_epoch, 0);

    // The best-validation weights are the ones kept: recompute the validation MSE.
    const FrameSet frames = training_frames(data);
    MatrixXd val_x(frames.positions.rows(), 0), val_t(frames.bc_targets.rows(), 0);
    std::vector<Index> idx;
    for (Index j = 0; j < frames.positions.cols(); ++j)
        if (j % 10 == 9) idx.push_back(j);
    val_x.resize(frames.positions.rows(), Index(idx.size()));
    val_t.resize(frames.bc_targets.rows(), Index(idx.size()));
    for (std::size_t i = 0; i < idx.size(); ++i) {
        val_x.col(Index(i)) = frames.positions.col(idx[i]);
        val_t.col(Index(i)) = frames.bc_targets.col(idx[i]);
    }
    const MatrixXd x_hat = ae.decode(ae.encode(val_x), val_t);
    EXPECT_NEAR((x_hat - val_x).squaredNorm() / double(val_x.size()), s.best_validation,
                1e-9 * s.best_validation);
    EXPECT_NEAR(ae.relative_rmse(val_x, val_t), s.validation_relative_rmse, 1e-12);
}

TEST(AutoencoderTraining, EarlyStoppingKeepsTheBestWeights)
{
    // A step far too large for this net (lr 0.05) makes the validation error wander, so
    // two epochs without improvement come quickly; the weights kept are the best epoch's.
    const Dataset data = latent_test::small_cloth_prefix(100);
    AutoencoderOptions o = tiny_options();
    o.learning_rate = 0.05;
    o.epochs = 300;
    o.patience = 2;
    Autoencoder ae(data.physics, o, 8);
    const auto s = train_autoencoder(ae, data, o);
    ASSERT_TRUE(s.stopped_early) << "ran all " << s.epochs_run << " epochs";
    EXPECT_EQ(s.epochs_run, s.best_epoch + o.patience);
    FrameSet frames = training_frames(data);
    MatrixXd val_x(frames.positions.rows(), 10), val_t(frames.bc_targets.rows(), 10);
    for (Index i = 0; i < 10; ++i) {  // frames 9, 19, ..., 99
        val_x.col(i) = frames.positions.col(10 * i + 9);
        val_t.col(i) = frames.bc_targets.col(10 * i + 9);
    }
    const MatrixXd x_hat = ae.decode(ae.encode(val_x), val_t);
    EXPECT_NEAR((x_hat - val_x).squaredNorm() / double(val_x.size()), s.best_validation,
                1e-9 * s.best_validation);
}

TEST(AutoencoderTraining, HandlesAHandfulOfFrames)
{
    // 3 frames, no validation split (every 10th frame would be the 10th), batch 2: one batch
    // of 3 (never a single-frame batch for BatchNorm), pca_dim clamped to 2.
    const Dataset data = latent_test::small_cloth_prefix(3);
    AutoencoderOptions o = tiny_options();
    o.batch_size = 2;
    o.epochs = 2;
    Autoencoder ae(data.physics, o, 0);
    const auto s = train_autoencoder(ae, data, o);
    EXPECT_EQ(s.epochs_run, 2);
    EXPECT_EQ(ae.options().pca_dim, 2);
    EXPECT_TRUE(std::isfinite(s.validation_relative_rmse));
}

TEST(AutoencoderTraining, FramesSeenAreTheTrainingWindowOrEveryFrame)
{
    // Issue 39's autoencoder_frames: "train" (default) takes the frames before each sequence's
    // train_frames, "all" every frame, in order.
    Dataset data = latent_test::small_cloth_prefix(20);
    data.sequences.front().train_frames = 12;
    const FrameSet train = training_frames(data), all = training_frames(data, AutoencoderFrames::all);
    ASSERT_EQ(train.positions.cols(), 12);
    ASSERT_EQ(all.positions.cols(), 20);
    EXPECT_EQ(all.positions.leftCols(12), train.positions);
    EXPECT_EQ(all.positions.col(19), data.sequences.front().positions.row(19).transpose());
    EXPECT_EQ(autoencoder_frames_from_string("all"), AutoencoderFrames::all);
    EXPECT_THROW(autoencoder_frames_from_string("test"), ConfigError);
}

TEST(AutoencoderTraining, RejectsBadOptionsAndMismatchedData)
{
    const Dataset data = latent_test::small_cloth_prefix(20);
    AutoencoderOptions o = tiny_options();
    Autoencoder ae(data.physics, o, 0);
    AutoencoderOptions bad = o;
    bad.batch_size = 1;
    EXPECT_THROW(train_autoencoder(ae, data, bad), ConfigError);
    bad = o;
    bad.learning_rate = -1.0;
    EXPECT_THROW(train_autoencoder(ae, data, bad), ConfigError);
    Autoencoder rods(latent_test::rod_physics(), o, 0);
    EXPECT_THROW(train_autoencoder(rods, data, o), ConfigError);
}

TEST(AutoencoderTraining, PhysicsFineTuningLowersTheEnergyItsReconstructionsStore)
{
    // physics_epochs (issue 14, Tan et al.'s L_ephys as an autoencoder option): the small
    // cloth's first 80 frames, an autoencoder trained briefly, then fine-tuned on
    // L_recon + 0.5 L_ephys. The same training without the option is the reference: its
    // weights equal the fine-tuning's starting point (same seed), so the fine-tuning's
    // "before" is the reference's value. Measured (2026-12-01): L_ephys 0.0209 -> 0.00258 in
    // 40 epochs (L_recon 2.5e-4 -> 1.4e-4); asserted: below 0.8 of its start.
    const Dataset data = latent_test::small_cloth_prefix(80);
    AutoencoderOptions o = tiny_options();
    o.epochs = 60;
    Autoencoder plain(data.physics, o, 0);
    const AutoencoderTrainSummary s0 = train_autoencoder(plain, data, o);
    EXPECT_FALSE(s0.physics_ran);
    EXPECT_EQ(s0.physics_epochs_run, 0);

    o.physics_epochs = 40;
    o.physics_learning_rate = 1e-4;
    Autoencoder tuned(data.physics, o, 0);
    const AutoencoderTrainSummary s = train_autoencoder(tuned, data, o);
    ASSERT_TRUE(s.physics_ran);
    EXPECT_EQ(s.physics_epochs_run, 40);
    RecordProperty("ephys_before", std::to_string(s.physics_ephys_before));
    RecordProperty("ephys_after", std::to_string(s.physics_ephys_after));
    EXPECT_LT(s.physics_ephys_after, 0.8 * s.physics_ephys_before)
        << "L_ephys " << s.physics_ephys_before << " -> " << s.physics_ephys_after;
    EXPECT_TRUE(std::isfinite(s.physics_recon_after));
    EXPECT_TRUE(std::isfinite(s.validation_relative_rmse));
    // The held-out validation error is the one before the fine-tuning: the plain run's.
    EXPECT_EQ(s.validation_relative_rmse_held_out, s0.validation_relative_rmse);
    EXPECT_NE(s.validation_relative_rmse, s.validation_relative_rmse_held_out);
    // The reconstruction training before it is the plain one: same best validation MSE.
    EXPECT_EQ(s.best_validation, s0.best_validation);
    // The fine-tuning changed the networks the rollouts decode with.
    const FrameSet frames = training_frames(data);
    EXPECT_GT((tuned.decode(tuned.encode(frames.positions), frames.bc_targets) -
               plain.decode(plain.encode(frames.positions), frames.bc_targets))
                  .norm(),
              0.0);

    AutoencoderOptions bad = o;
    bad.physics_epochs = -1;
    EXPECT_THROW(train_autoencoder(tuned, data, bad), ConfigError);
    bad = o;
    bad.physics_learning_rate = 0.0;
    EXPECT_THROW(train_autoencoder(tuned, data, bad), ConfigError);
    bad = o;
    bad.physics_weight = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(train_autoencoder(tuned, data, bad), ConfigError);
}

TEST(AutoencoderTraining, PhysicsFineTuningResumesFromItsCheckpoint)
{
    // A run killed during the fine-tuning resumes it (the reconstruction training's
    // checkpoint is complete) and ends bitwise where an uninterrupted run ends.
    const Dataset data = latent_test::small_cloth_prefix(40);
    AutoencoderOptions o = tiny_options();
    o.epochs = 10;
    o.physics_epochs = 12;
    o.physics_learning_rate = 1e-4;
    Autoencoder straight(data.physics, o, 0);
    train_autoencoder(straight, data, o);

    const std::string dir = ::testing::TempDir() + "/ae_physics_resume";
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    AutoencoderOptions part = o;
    part.checkpoint_path = dir + "/ae.checkpoint.h5";
    part.checkpoint_every = 1;
    part.interrupt = [](int epoch) { return epoch == 5; };
    {
        // Killed in the reconstruction loop's epoch 5: no fine-tuning starts.
        Autoencoder first(data.physics, part, 0);
        EXPECT_FALSE(train_autoencoder(first, data, part).physics_ran);
    }
    {
        // Resumed: the reconstruction loop finishes (epochs 6–10), the fine-tuning is
        // killed in its epoch 5.
        Autoencoder second(data.physics, part, 0);
        const AutoencoderTrainSummary s = train_autoencoder(second, data, part);
        EXPECT_TRUE(s.interrupted);
        EXPECT_EQ(s.physics_epochs_run, 5);
    }
    ASSERT_TRUE(std::filesystem::exists(part.checkpoint_path + ".physics"));
    part.interrupt = {};
    Autoencoder resumed(data.physics, part, 0);
    const AutoencoderTrainSummary s = train_autoencoder(resumed, data, part);
    EXPECT_TRUE(s.physics_ran);
    EXPECT_EQ(s.physics_epochs_run, 12);
    EXPECT_EQ(resumed.content_hash(), straight.content_hash());
    std::filesystem::remove_all(dir);
}

TEST(AutoencoderTraining, DefaultLatentSizesPerScene)
{
    EXPECT_EQ(default_latent_dim("rods_translate"), 4);
    EXPECT_EQ(default_latent_dim("rods_rotate"), 4);
    EXPECT_EQ(default_latent_dim("cloth"), 4);
    EXPECT_EQ(default_latent_dim("armadillo"), 12);
    EXPECT_EQ(default_latent_dim("bunny_ears"), 8);
    EXPECT_EQ(default_latent_dim("cantilever"), 4);
}

// ---- NumPy reference -----------------------------------------------------------------

TEST(Autoencoder, NumpyReferenceDecoderMatches)
{
    if (run_process({"/usr/bin/python3", "-c", "import numpy, h5py"}, {"/dev/null", "/dev/null"}) != 0)
        GTEST_SKIP() << "/usr/bin/python3 lacks numpy or h5py";
    const Dataset data = latent_test::small_cloth_prefix(120);
    AutoencoderOptions o = tiny_options();
    o.epochs = 2;
    Autoencoder ae(data.physics, o, 6);
    train_autoencoder(ae, data, o);
    const std::string model = tmp_path("numpy_ae.h5"), in = tmp_path("numpy_z.h5"), out = tmp_path("numpy_f.h5");
    ae.save(model);
    Rng rng(15);
    const MatrixXd Z = random_matrix(ae.latent_dim(), 7, rng, -2.0, 2.0);
    {
        h5::File f = h5::File::create(in);
        f.write("inputs", Z);  // latent × 7: one sample per column
    }
    fs::remove(out);
    const std::vector<std::string> argv{"/usr/bin/python3", std::string(LB_SOURCE_DIR) + "/scripts/nn_reference.py",
                                        model, "--prefix", "decoder.", "--input", in, "--dataset", "inputs",
                                        "--columns", "--output", out};
    ASSERT_EQ(run_process(argv), 0) << "scripts/nn_reference.py " << model;
    const MatrixXd F_numpy = h5::File::open(out).read_matrix("output");
    const MatrixXd F_cpp = ae.decode_features(Z);
    ASSERT_EQ(F_numpy.rows(), F_cpp.rows());
    ASSERT_EQ(F_numpy.cols(), F_cpp.cols());
    EXPECT_LE((F_numpy - F_cpp).cwiseAbs().maxCoeff(), 1e-12 * std::max(1.0, F_cpp.cwiseAbs().maxCoeff()));
}

} // namespace
} // namespace lb
