// fulton_cubature, part 1: the decoder split at its PCA layer and the greedy cubature
// (An et al. 2008) on the small cloth and small cantilever.
#include <gtest/gtest.h>

#include <filesystem>

#include "baselines/fulton_cubature/cubature.hpp"
#include "baselines/fulton_cubature/pca_split_decoder.hpp"
#include "core/error.hpp"
#include "io/hdf5.hpp"
#include "fulton_fixture.hpp"

namespace lb {
namespace {

using testing::FultonProblem;

/// The split decoder x = U g(z) + c(t) equals the autoencoder's decode.
TEST(PcaSplitDecoder, ReproducesTheDecoder)
{
    FultonProblem p("cloth", 40, 30, 20);
    PcaSplitDecoder split(*p.ae, *p.model);
    const SequenceData& seq = p.data.sequences[0];
    for (Index t : {Index(3), Index(17), Index(35)}) {
        const VectorXd x = seq.positions.row(t).transpose();
        const VectorXd targets = seq.bc_positions.row(t).transpose();
        const VectorXd z = p.ae->encode(MatrixXd(x)).col(0);
        const VectorXd expected = p.ae->decode(MatrixXd(z), MatrixXd(targets)).col(0);
        VectorXd c(x.size());
        split.offset_into(targets, c);
        const VectorXd got = split.basis() * split.inner(z) + c;
        EXPECT_LT((got - expected).lpNorm<Eigen::Infinity>(), 1e-12) << "frame " << t;
    }
}

/// An autoencoder in the boundary's rigid frame decodes x = R(t) U g(z) + c(t): the split's
/// precomputed PCA coordinates would be wrong, so it is refused by name, not used.
TEST(PcaSplitDecoder, RefusesTheRigidFrame)
{
    FultonProblem p("cantilever", 40, 30, 20);
    AutoencoderOptions o = p.ae->options();
    o.frame = EncodingFrame::rigid;
    Autoencoder rigid(p.data.physics, o, 1);
    try {
        PcaSplitDecoder split(rigid, *p.model);
        FAIL() << "expected ConfigError";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("rigid frame"), std::string::npos) << e.what();
    }
}

/// The greedy cubature reaches its tolerance on the training reconstructions and
/// matches the exact reduced force and energy on held-out reconstructions.
void check_cubature(const std::string& scene, int frames, int train_frames, double tolerance,
                    double heldout_force_tolerance, double heldout_energy_tolerance)
{
    FultonProblem p(scene, frames, train_frames);
    PcaSplitDecoder split(*p.ae, *p.model);
    const MatrixXd train = p.reconstructions(2, train_frames);
    const MatrixXd heldout = p.reconstructions(train_frames, frames);
    CubatureOptions o;
    o.tolerance = tolerance;
    o.max_elements = 150;
    o.max_poses = 1000;  // every training pose, so the recomputed error below is the same sum
    o.candidates = 200;
    const Cubature c = train_cubature(*p.model, split, train, o);
    Index total = 0;
    for (const auto& term : p.model->elastic_terms()) total += term->num_elements();
    EXPECT_TRUE(c.reached_tolerance) << scene << ": training error " << c.training_error << " with "
                                     << c.elements.size() << " elements";
    EXPECT_LE(c.training_error, tolerance);
    EXPECT_EQ(c.stop_reason, "tolerance");
    EXPECT_LT(Index(c.elements.size()), total / 2) << "the cubature should be much smaller than the mesh";
    for (const CubatureElement& e : c.elements) EXPECT_GT(e.weight, 0.0);
    // Training error recomputed independently of the greedy loop's residual.
    EXPECT_NEAR(cubature_accuracy(*p.model, split, c, train).force_error, c.training_error, 1e-9);
    const CubatureAccuracy held = cubature_accuracy(*p.model, split, c, heldout);
    EXPECT_LT(held.force_error, heldout_force_tolerance) << scene;
    EXPECT_LT(held.energy_error, heldout_energy_tolerance) << scene;
    std::printf("[ figures  ] %s: %zu of %ld elements, %d poses, training force error %.4f, held-out force %.4f, "
                "energy %.4f, %.2f s\n",
                scene.c_str(), c.elements.size(), long(total), c.training_poses, c.training_error, held.force_error,
                held.energy_error, c.seconds);
    // All elements at unit weight are exact.
    const CubatureAccuracy exact = cubature_accuracy(*p.model, split, Cubature::all_elements(*p.model), heldout);
    EXPECT_LT(exact.force_error, 1e-10);
    EXPECT_LT(exact.energy_error, 1e-10);
}

TEST(Cubature, ReachesToleranceOnSmallCloth) { check_cubature("cloth", 400, 300, 0.02, 0.1, 0.1); }
TEST(Cubature, ReachesToleranceOnSmallCantilever) { check_cubature("cantilever", 160, 100, 0.02, 0.1, 0.1); }

TEST(Cubature, SaveLoadRoundTripAndBadFiles)
{
    FultonProblem p("cantilever", 30, 20, 5);
    PcaSplitDecoder split(*p.ae, *p.model);
    CubatureOptions o;
    o.max_elements = 10;
    const Cubature c = train_cubature(*p.model, split, p.reconstructions(2, 20), o);
    const std::string dir = std::string(LB_TEST_TMP_DIR) + "/fulton_cubature";
    std::filesystem::create_directories(dir);
    {
        h5::File f = h5::File::create(dir + "/cubature.h5");
        c.save(f);
    }
    const Cubature back = Cubature::load(h5::File::open(dir + "/cubature.h5"), *p.model);
    ASSERT_EQ(back.elements.size(), c.elements.size());
    for (size_t i = 0; i < c.elements.size(); ++i) {
        EXPECT_EQ(back.elements[i].term, c.elements[i].term);
        EXPECT_EQ(back.elements[i].element, c.elements[i].element);
        EXPECT_EQ(back.elements[i].weight, c.elements[i].weight);
    }
    EXPECT_EQ(back.training_error, c.training_error);
    EXPECT_EQ(back.stop_reason, c.stop_reason);
    EXPECT_FALSE(c.stop_reason.empty());
    {
        h5::File other = h5::File::create(dir + "/other.h5");
        other.write("x", VectorXd(VectorXd::Zero(3)));
    }
    EXPECT_THROW(Cubature::load(h5::File::open(dir + "/other.h5"), *p.model), IoError);
    o.tolerance = 0.0;
    EXPECT_THROW(train_cubature(*p.model, split, p.reconstructions(2, 20), o), ConfigError);
}

} // namespace
} // namespace lb
