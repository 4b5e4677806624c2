// Network files from elsewhere: a hostile architecture description (200,000 nested
// '[' used to overflow the stack; NaN or huge widths), and NaN/inf weights, buffers,
// standardiser statistics or optimiser state, are IoErrors naming the file and the
// attribute or dataset, never a crash or a network that computes NaN.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <limits>
#include <string>

#include "core/error.hpp"
#include "io/hdf5.hpp"
#include "nn/adam.hpp"
#include "nn/architecture.hpp"
#include "nn/mlp_spec.hpp"
#include "nn/serialization.hpp"
#include "nn_test_support.hpp"

namespace lb::nn {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string tmp_path(const std::string& name)
{
    std::filesystem::create_directories(LB_TEST_TMP_DIR);
    return std::string(LB_TEST_TMP_DIR) + "/nn_hostile_" + name;
}

void expect_io_error(const std::function<void()>& f, const std::vector<std::string>& parts)
{
    try {
        f();
        ADD_FAILURE() << "expected IoError";
    } catch (const IoError& e) {
        for (const std::string& p : parts) EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
    }
}

std::string document(const std::string& network)
{
    return std::string("{\"format\": \"latentbench.nn/1\", \"standardizer\": false, \"network\": ") + network + "}";
}

TEST(ArchitectureLimits, DeepNestingIsRefusedWithoutRecursingIntoIt)
{
    expect_io_error([] { parse_architecture(std::string(200000, '[')); }, {"nested deeper than 64"});
    expect_io_error([] { parse_architecture(document(std::string(100, '[') + std::string(100, ']'))); },
                    {"nested deeper than 64"});
    std::string objects;
    for (int i = 0; i < 100; ++i) objects += "{\"a\": ";
    expect_io_error([&] { parse_architecture(objects); }, {"nested deeper than 64"});
    // Shallower nesting is only as malformed as its content.
    expect_io_error([] { parse_architecture(document(std::string(30, '[') + std::string(30, ']'))); },
                    {"architecture"});
}

TEST(ArchitectureLimits, OversizedDocumentIsRefused)
{
    const std::string big = document("{\"type\": \"Sequential\", \"layers\": []}") + std::string(kMaxArchitectureBytes, ' ');
    expect_io_error([&] { parse_architecture(big); }, {"exceeds the limit"});
}

TEST(ArchitectureLimits, NonFiniteAndHugeNumbersAreRefused)
{
    const auto linear = [](const std::string& in, const std::string& out) {
        return document("{\"type\": \"Sequential\", \"layers\": [{\"type\": \"Linear\", \"in\": " + in +
                        ", \"out\": " + out + "}]}");
    };
    expect_io_error([&] { parse_architecture(linear("nan", "3")); }, {"non-finite number"});
    expect_io_error([&] { parse_architecture(linear("1e999", "3")); }, {"non-finite number"});
    expect_io_error([&] { parse_architecture(linear("1e15", "3")); }, {"integer width"});
    expect_io_error([&] { parse_architecture(linear("2.5", "3")); }, {"integer width"});
    expect_io_error([&] { parse_architecture(linear("10000000", "10000000")); }, {"too large"});
    EXPECT_EQ(parse_architecture(linear("4", "3")).network.out_features(), 3);
}

/// A small 3 → hidden → 2 MLP (with BatchNorm if asked) for the file tests below.
Sequential small_net(std::uint64_t seed, Index hidden, bool batch_norm, Rng* rng_out = nullptr)
{
    Rng rng(seed);
    MlpSpec s;
    s.in_dim = 3;
    s.hidden = {hidden};
    s.out_dim = 2;
    s.batch_norm = batch_norm;
    Sequential net = make_mlp(s, rng);
    if (rng_out) *rng_out = rng;
    return net;
}

TEST(ArchitectureLimits, LoadNetworkNamesTheFileAndAttribute)
{
    Sequential net = small_net(7, 5, false);
    const std::string path = tmp_path("deep.h5");
    {
        h5::File f = h5::File::create(path);
        save_network(f, "decoder.", net);
        f.set_attribute("/", "decoder.architecture", std::string(200000, '['));
    }
    expect_io_error([&] { load_network(path, "decoder."); }, {path, "attribute 'decoder.architecture'", "nested"});
}

/// A saved network with a standardizer and BatchNorm (so every kind of array is
/// present), then `mutate` applied to the file; load_network must refuse it.
void expect_load_refused(const std::string& name, const std::function<void(h5::File&)>& mutate,
                         const std::vector<std::string>& parts)
{
    Rng rng(0);
    Sequential net = small_net(11, 5, true, &rng);
    const Standardizer st = Standardizer::fit(test::random_matrix(3, 20, rng, -2, 2));
    const std::string path = tmp_path(name + ".h5");
    {
        h5::File f = h5::File::create(path);
        save_network(f, "net.", net, &st);
    }
    {
        const LoadedNetwork ok = load_network(path, "net.");  // the unmutated file loads
        EXPECT_TRUE(ok.standardizer.has_value());
    }
    {
        h5::File f = h5::File::open(path, /*writable=*/true);
        mutate(f);
    }
    std::vector<std::string> all = parts;
    all.push_back(path);
    expect_io_error([&] { load_network(path, "net."); }, all);
}

/// The first parameter, buffer and running variance names of the test network.
std::string first_name(const std::string& suffix)
{
    Sequential net = small_net(11, 5, true);
    for (const auto& p : net.parameters("net."))
        if (p.name.size() >= suffix.size() && p.name.compare(p.name.size() - suffix.size(), suffix.size(), suffix) == 0)
            return p.name;
    for (const auto& b : net.buffers("net."))
        if (b.name.size() >= suffix.size() && b.name.compare(b.name.size() - suffix.size(), suffix.size(), suffix) == 0)
            return b.name;
    ADD_FAILURE() << "no array named *" << suffix;
    return "";
}

TEST(NonFiniteNetworks, WeightsBuffersAndStandardizerAreRefused)
{
    const std::string weight = first_name("weight"), bias = first_name("bias");
    const std::string mean = first_name("running_mean"), var = first_name("running_var");
    expect_load_refused(
        "nan_weight",
        [&](h5::File& f) {
            MatrixXd w = f.read_matrix(weight);
            w(0, 0) = kNaN;
            f.write(weight, w);
        },
        {"'" + weight + "'", "non-finite"});
    expect_load_refused(
        "inf_bias",
        [&](h5::File& f) {
            VectorXd b = f.read_vector(bias);
            b(0) = kInf;
            f.write(bias, b);
        },
        {"'" + bias + "'", "non-finite"});
    expect_load_refused(
        "nan_running_mean",
        [&](h5::File& f) { f.write(mean, VectorXd(VectorXd::Constant(f.read_vector(mean).size(), kNaN))); },
        {"'" + mean + "'", "non-finite"});
    expect_load_refused(
        "negative_running_var",
        [&](h5::File& f) { f.write(var, VectorXd(VectorXd::Constant(f.read_vector(var).size(), -1.0))); },
        {"'" + var + "'", "negative"});
    expect_load_refused(
        "nan_standardizer_mean",
        [](h5::File& f) { f.write("net.standardizer.mean", VectorXd(VectorXd::Constant(3, kNaN))); },
        {"'net.standardizer.mean'", "non-finite"});
    expect_load_refused(
        "inf_standardizer_std",
        [](h5::File& f) { f.write("net.standardizer.std", VectorXd(VectorXd::Constant(3, kInf))); },
        {"'net.standardizer.std'", "non-finite"});
}

TEST(NonFiniteNetworks, AdamStateIsRefused)
{
    Rng rng(0);
    Sequential net = small_net(12, 4, false, &rng);
    std::vector<ParameterRef> params = net.parameters("net.");
    Adam adam(params);
    for (auto& p : params) p.grad.setOnes();
    adam.step();
    const std::string path = tmp_path("adam.h5");
    {
        h5::File f = h5::File::create(path);
        save_adam_state(f, "", adam, params);
        const std::string v = "adam/v/" + params[0].name;
        MatrixXd bad = f.read_matrix(v);
        bad(0, 0) = kNaN;
        f.write(v, bad);
    }
    const h5::File f = h5::File::open(path);
    Adam fresh(params);
    expect_io_error([&] { load_adam_state(f, "", fresh, params); }, {path, "adam/v/" + params[0].name, "non-finite"});
}

} // namespace
} // namespace lb::nn
