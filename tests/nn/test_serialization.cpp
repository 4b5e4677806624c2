#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "core/process.hpp"
#include "lb_paths.hpp"
#include "io/hdf5.hpp"
#include "nn/architecture.hpp"
#include "nn/batch_norm.hpp"
#include "nn/linear.hpp"
#include "nn/residual_block.hpp"
#include "nn/mlp_spec.hpp"
#include "nn/serialization.hpp"
#include "nn_test_support.hpp"

namespace lb::nn {
namespace {

std::string tmp_path(const std::string& name)
{
    std::filesystem::create_directories(LB_TEST_TMP_DIR);
    return std::string(LB_TEST_TMP_DIR) + "/nn_" + name;
}

Sequential trained_decoder(Rng& rng)
{
    MlpSpec s;
    s.in_dim = 4;
    s.hidden = {10, 10};
    s.out_dim = 21;
    s.pca_dim = 6;
    s.pca_placement = PcaPlacement::output;
    s.batch_norm = true;
    s.residual = true;
    Sequential net = make_mlp(s, rng);
    for (int i = 0; i < 3; ++i) net.forward(test::random_matrix(4, 16, rng, -2, 2), true);  // running stats
    return net;
}

Sequential encoder(Rng& rng)
{
    MlpSpec s;
    s.in_dim = 21;
    s.hidden = {8};
    s.out_dim = 4;
    s.pca_dim = 6;
    s.pca_placement = PcaPlacement::input;
    s.batch_norm = true;
    s.activation = ActivationKind::tanh;
    Sequential net = make_mlp(s, rng);
    test::randomize_batch_norm(net, rng);
    return net;
}

TEST(Serialization, RoundTripIsBitwiseForTwoNetworksInOneFile)
{
    Rng rng(91);
    Sequential dec = trained_decoder(rng);
    Sequential enc = encoder(rng);
    const Standardizer std_enc = Standardizer::fit(test::random_matrix(21, 30, rng, -3, 5));
    const std::string path = tmp_path("autoencoder.h5");
    {
        h5::File f = h5::File::create(path);
        save_network(f, "encoder.", enc, &std_enc);
        save_network(f, "decoder.", dec);
    }
    const h5::File f = h5::File::open(path);
    LoadedNetwork enc2 = load_network(f, "encoder.");
    LoadedNetwork dec2 = load_network(f, "decoder.");
    ASSERT_TRUE(enc2.standardizer.has_value());
    EXPECT_FALSE(dec2.standardizer.has_value());
    EXPECT_EQ(enc2.standardizer->mean(), std_enc.mean());
    EXPECT_EQ(enc2.standardizer->stddev(), std_enc.stddev());

    const MatrixXd X = test::random_matrix(21, 5, rng);
    const MatrixXd Z = test::random_matrix(4, 5, rng);
    EXPECT_EQ(enc2.network.forward(enc2.standardizer->apply(X), false), enc.forward(std_enc.apply(X), false));
    EXPECT_EQ(dec2.network.forward(Z, false), dec.forward(Z, false));
    // Same structure, parameters and buffers, bit for bit.
    EXPECT_EQ(describe_architecture(dec2.network, false), describe_architecture(dec, false));
    auto b1 = dec.buffers(), b2 = dec2.network.buffers();
    ASSERT_EQ(b1.size(), b2.size());
    for (std::size_t i = 0; i < b1.size(); ++i) EXPECT_EQ(MatrixXd(b1[i].value), MatrixXd(b2[i].value)) << b1[i].name;
    EXPECT_EQ(dynamic_cast<const BatchNorm1d*>(&dynamic_cast<const ResidualBlock&>(dec2.network.layer(0)).f().layer(1))
                  ->num_batches_tracked(),
              3);
}

TEST(Serialization, StateDictNamesShapesAndArchitectureAttribute)
{
    Rng rng(92);
    Sequential dec = trained_decoder(rng);
    const std::string path = tmp_path("decoder_names.h5");
    save_network(path, "decoder.", dec);
    const h5::File f = h5::File::open(path);
    EXPECT_EQ(f.shape("decoder.0.f.0.weight"), (std::vector<hsize_t>{10, 4}));  // (out, in) like torch
    EXPECT_EQ(f.shape("decoder.0.f.0.bias"), (std::vector<hsize_t>{10}));
    EXPECT_EQ(f.shape("decoder.0.f.1.running_var"), (std::vector<hsize_t>{10}));
    EXPECT_EQ(f.shape("decoder.0.f.1.num_batches_tracked"), (std::vector<hsize_t>{}));
    EXPECT_EQ(f.shape("decoder.0.skip.weight"), (std::vector<hsize_t>{10, 4}));
    EXPECT_EQ(f.shape("decoder.3.weight"), (std::vector<hsize_t>{21, 6}));  // the PCA layer
    EXPECT_FALSE(f.exists("decoder.1.skip.weight"));                         // identity skip
    const MatrixXd w = f.read_matrix("decoder.3.weight");
    EXPECT_EQ(w, dynamic_cast<const Linear&>(dec.layer(3)).weight());
    const std::string arch = f.attribute_string("/", "decoder.architecture");
    EXPECT_NE(arch.find("\"ResidualBlock\""), std::string::npos);
    EXPECT_NE(arch.find("\"format\": \"latentbench.nn/1\""), std::string::npos);
}

TEST(Serialization, ErrorsNameTheFileAndDataset)
{
    Rng rng(93);
    Sequential dec = trained_decoder(rng);
    const std::string path = tmp_path("broken.h5");
    {
        h5::File f = h5::File::create(path);
        save_network(f, "decoder.", dec);
        f.write("decoder.3.weight", MatrixXd(MatrixXd::Zero(21, 7)));  // wrong shape
    }
    try {
        load_network(path, "decoder.");
        FAIL() << "expected IoError";
    } catch (const IoError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("decoder.3.weight"), std::string::npos) << msg;
        EXPECT_NE(msg.find("broken.h5"), std::string::npos) << msg;
    }
    EXPECT_THROW(load_network(path, "encoder."), IoError);  // no such prefix
    EXPECT_THROW(parse_architecture("{\"format\": \"latentbench.nn/1\", \"standardizer\": false, \"network\": "
                                    "{\"type\": \"Sequential\", \"layers\": [{\"type\": \"Conv2d\"}]}}"),
                 IoError);
    EXPECT_THROW(parse_architecture("{\"format\": "), IoError);
}

TEST(Serialization, NumpyReferenceScriptAgrees)
{
    if (run_process({"/usr/bin/python3", "-c", "import numpy, h5py"}, {"/dev/null", "/dev/null"}) != 0)
        GTEST_SKIP() << "/usr/bin/python3 lacks numpy or h5py";
    Rng rng(94);
    Sequential enc = encoder(rng);
    const Standardizer st = Standardizer::fit(test::random_matrix(21, 40, rng, -3, 5));
    Sequential dec = trained_decoder(rng);
    const std::string model = tmp_path("reference_model.h5");
    h5::write_file_atomically(model, [&](h5::File& f) {
        save_network(f, "encoder.", enc, &st);
        save_network(f, "decoder.", dec);
    });
    const MatrixXd X = test::random_matrix(21, 7, rng, -3, 5);
    const std::string inputs = tmp_path("reference_inputs.h5");
    {
        h5::File f = h5::File::create(inputs);
        f.write("inputs", X);
    }
    for (const std::string prefix : {"encoder.", "decoder."}) {
        const std::string output = tmp_path("reference_output_" + prefix + "h5");
        std::remove(output.c_str());
        MatrixXd in = X;
        if (prefix == "decoder.") {
            in = test::random_matrix(4, 7, rng);
            h5::File f = h5::File::open(inputs, true);
            f.write("inputs", in);
        }
        const std::vector<std::string> argv{"/usr/bin/python3", std::string(LB_SOURCE_DIR) + "/scripts/nn_reference.py",
                                            model, "--prefix", prefix, "--input", inputs, "--dataset", "inputs",
                                            "--columns", "--output", output};
        ASSERT_EQ(run_process(argv), 0) << "scripts/nn_reference.py " << model << " --prefix " << prefix;
        const MatrixXd py = h5::File::open(output).read_matrix("output");
        const MatrixXd cpp = prefix == "encoder." ? enc.forward(st.apply(in), false) : dec.forward(in, false);
        ASSERT_EQ(py.rows(), cpp.rows());
        ASSERT_EQ(py.cols(), cpp.cols());
        EXPECT_LT((py - cpp).cwiseAbs().maxCoeff(), 1e-12 * std::max(1.0, cpp.cwiseAbs().maxCoeff())) << prefix;
    }
}

} // namespace
} // namespace lb::nn
