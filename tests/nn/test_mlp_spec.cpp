#include <gtest/gtest.h>

#include "core/error.hpp"
#include "nn/batch_norm.hpp"
#include "nn/linear.hpp"
#include "nn/mlp_spec.hpp"
#include "paper/paper_architectures.hpp"
#include "nn/residual_block.hpp"

namespace lb::nn {
namespace {

std::vector<std::string> types(const Sequential& net)
{
    std::vector<std::string> t;
    for (Index i = 0; i < net.size(); ++i) t.push_back(net.layer(i).type_name());
    return t;
}

TEST(MlpSpec, PlainMlpWithBatchNorm)
{
    Rng rng(51);
    MlpSpec s;
    s.in_dim = 10;
    s.hidden = {8, 6};
    s.out_dim = 3;
    s.batch_norm = true;
    const Sequential net = make_mlp(s, rng);
    const std::vector<std::string> expected = {"Linear", "BatchNorm1d", "Swish", "Linear", "BatchNorm1d", "Swish",
                                               "Linear"};
    EXPECT_EQ(types(net), expected);
    EXPECT_EQ(net.in_features(), 10);
    EXPECT_EQ(net.out_features(), 3);
}

TEST(MlpSpec, DecoderWithResidualBlocksAndPcaOutput)
{
    Rng rng(52);
    const PaperArchitecture arch = table2_architecture("armadillo");
    Sequential net = make_mlp(arch.decoder, rng);
    const std::vector<std::string> expected = {"ResidualBlock", "ResidualBlock", "ResidualBlock", "Linear", "Linear"};
    EXPECT_EQ(types(net), expected);
    EXPECT_TRUE(dynamic_cast<const ResidualBlock&>(net.layer(0)).has_projection());   // 12 -> 200
    EXPECT_FALSE(dynamic_cast<const ResidualBlock&>(net.layer(1)).has_projection());  // 200 -> 200
    EXPECT_EQ(dynamic_cast<const Linear&>(net.layer(3)).out_features(), 50);
    EXPECT_EQ(dynamic_cast<const Linear&>(net.layer(4)).in_features(), 50);
    EXPECT_EQ(net.in_features(), 12);
    EXPECT_EQ(net.out_features(), 10020);
    EXPECT_EQ(arch.integrator.in_dim, 2 * 12 + 3 * 3);
}

TEST(MlpSpec, EncoderWithPcaInput)
{
    Rng rng(53);
    MlpSpec s;
    s.in_dim = 30;
    s.hidden = {16};
    s.out_dim = 4;
    s.pca_dim = 5;
    s.pca_placement = PcaPlacement::input;
    s.activation = ActivationKind::tanh;
    s.output_activation = true;
    const Sequential net = make_mlp(s, rng);
    const std::vector<std::string> expected = {"Linear", "Linear", "Tanh", "Linear", "Tanh"};
    EXPECT_EQ(types(net), expected);
    EXPECT_EQ(net.layer(0).out_features(), 5);
}

TEST(MlpSpec, ValidationNamesTheField)
{
    MlpSpec s;
    s.in_dim = 3;
    s.out_dim = 0;
    try {
        s.validate();
        FAIL() << "expected ConfigError";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("out_dim"), std::string::npos);
    }
    s.out_dim = 2;
    s.pca_placement = PcaPlacement::output;
    EXPECT_THROW(s.validate(), ConfigError);
    EXPECT_THROW(table2_architecture("teapot"), ConfigError);
}

TEST(MlpSpec, Summary)
{
    MlpSpec s = table2_architecture("cloth").decoder;
    EXPECT_EQ(s.summary(), "4 -> res[200,200,200] (bn, Swish) -> 50 -> pca -> 576");
}

} // namespace
} // namespace lb::nn
