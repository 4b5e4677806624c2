#include "nn/architecture.hpp"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

#include "core/error.hpp"
#include "io/json.hpp"
#include "nn/activation.hpp"
#include "nn/batch_norm.hpp"
#include "nn/linear.hpp"
#include "nn/residual_block.hpp"

namespace lb::nn {

namespace {

/// Layer widths above this are refused before anything is allocated (a corrupt
/// "in": 1e15 would otherwise end in std::bad_alloc).
constexpr Index kMaxWidth = Index(1) << 24;
/// Entries of one weight matrix (in × out), 2^31 (16 GiB of doubles).
constexpr Index kMaxWeights = Index(1) << 31;

using Json = JsonValue;

/// A layer width: an integer in [0, kMaxWidth] (checked before the cast, which is
/// undefined for values outside Index's range).
Index index_of(const Json& j)
{
    const double v = j.number();
    if (!(v >= 0 && v <= double(kMaxWidth)) || v != std::floor(v))
        throw IoError("architecture: expected an integer width in [0, " + std::to_string(kMaxWidth) + "]");
    return static_cast<Index>(v);
}

Sequential build_sequential(const Json& j);

std::unique_ptr<Layer> build_layer(const Json& j)
{
    const std::string& type = j.at("type").string();
    if (type == "Sequential") return std::make_unique<Sequential>(build_sequential(j));
    if (type == "Linear") {
        const Index in = index_of(j.at("in")), out = index_of(j.at("out"));
        if (in > 0 && out > kMaxWeights / in)
            throw IoError("architecture: Linear " + std::to_string(in) + " → " + std::to_string(out) + " is too large");
        return std::make_unique<Linear>(in, out);
    }
    if (type == "BatchNorm1d") {
        const double eps = j.has("eps") ? j.at("eps").number() : BatchNorm1d::default_eps;
        if (!(eps > 0)) throw IoError("architecture: BatchNorm1d eps must be positive");
        const double momentum = j.has("momentum") ? j.at("momentum").number() : BatchNorm1d::default_momentum;
        return std::make_unique<BatchNorm1d>(index_of(j.at("features")), eps, momentum);
    }
    if (type == "ResidualBlock") {
        std::optional<Linear> skip;
        const Json& s = j.at("skip");
        if (s.type != Json::Type::null) skip.emplace(index_of(s.at("in")), index_of(s.at("out")));
        try {
            return std::make_unique<ResidualBlock>(build_sequential(j.at("f")), std::move(skip));
        } catch (const std::invalid_argument& e) {
            throw IoError(std::string("architecture: ") + e.what());
        }
    }
    try {
        const ActivationKind kind = activation_from_string(type);
        if (kind == ActivationKind::swish) return std::make_unique<Swish>();
        return std::make_unique<Activation>(kind);
    } catch (const ConfigError&) {
        throw IoError("architecture: unknown layer type '" + type + "'");
    }
}

Sequential build_sequential(const Json& j)
{
    if (j.at("type").string() != "Sequential") throw IoError("architecture: expected a Sequential");
    const Json& layers = j.at("layers");
    if (layers.type != Json::Type::array) throw IoError("architecture: 'layers' must be an array");
    Sequential net;
    for (const Json& l : layers.arr) {
        try {
            net.add(build_layer(l));
        } catch (const std::invalid_argument& e) {
            throw IoError(std::string("architecture: ") + e.what());
        }
    }
    return net;
}

} // namespace

std::string describe_architecture(const Sequential& net, bool has_standardizer)
{
    std::ostringstream os;
    os << std::setprecision(std::numeric_limits<double>::digits10);
    os << "{\"format\": \"" << architecture_format << "\", \"standardizer\": " << (has_standardizer ? "true" : "false")
       << ", \"network\": ";
    net.describe(os);
    os << "}";
    return os.str();
}

Architecture parse_architecture(const std::string& json)
{
    const Json doc = parse_json(json, "architecture", kMaxArchitectureBytes, kMaxArchitectureDepth);
    const std::string& format = doc.at("format").string();
    if (format != architecture_format)
        throw IoError("architecture: unsupported format '" + format + "' (expected " + architecture_format + ")");
    Architecture a;
    a.network = build_sequential(doc.at("network"));
    const Json& s = doc.at("standardizer");
    if (s.type != Json::Type::boolean) throw IoError("architecture: 'standardizer' must be true or false");
    a.has_standardizer = s.b;
    return a;
}

} // namespace lb::nn
