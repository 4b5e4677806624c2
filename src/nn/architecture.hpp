#pragma once
// The architecture description stored beside a network's weights: a small JSON
// document enough to rebuild the layer structure (weights are loaded separately),
// e.g.
//   {"format": "latentbench.nn/1", "standardizer": false,
//    "network": {"type": "Sequential", "layers": [
//       {"type": "ResidualBlock", "f": {"type": "Sequential", "layers": [...]},
//        "skip": {"type": "Linear", "in": 12, "out": 200}}, ...,
//       {"type": "Linear", "in": 50, "out": 10020}]}}
// Layer objects: Linear {in, out}; BatchNorm1d {features, eps, momentum};
// Swish | Tanh | ReLU | Identity; ResidualBlock {f, skip | null}; Sequential {layers}.
// scripts/nn_reference.py reads the same document.
#include <string>

#include "nn/sequential.hpp"

namespace lb::nn {

inline constexpr const char* architecture_format = "latentbench.nn/1";
/// Limits on a stored description (a real one is a few kB and ~6 levels deep):
/// larger or deeper documents are refused as malformed, never parsed.
inline constexpr std::size_t kMaxArchitectureBytes = std::size_t(1) << 20;
inline constexpr int kMaxArchitectureDepth = 64;

/// JSON description of `net`; `has_standardizer` records whether input
/// standardisation statistics are stored with it.
std::string describe_architecture(const Sequential& net, bool has_standardizer);

struct Architecture {
    Sequential network;            ///< the layer structure, parameters zero / default
    bool has_standardizer = false;
};

/// Rebuild the layer structure from describe_architecture's output.
/// Throws IoError with a message saying what is malformed (including a document
/// over kMaxArchitectureBytes or nested deeper than kMaxArchitectureDepth).
Architecture parse_architecture(const std::string& json);

} // namespace lb::nn
