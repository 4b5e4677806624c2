#pragma once
// HDF5 (de)serialisation of networks in PyTorch state_dict style.
//
// A network saved under prefix P (e.g. "decoder.") writes, at the file root:
//   P0.weight (out × in), P0.bias (out), P1.weight, P1.bias, P1.running_mean,
//   P1.running_var, P1.num_batches_tracked (scalar), P2.f.0.weight, ...  (as
//   Sequential::parameters / buffers name them), and, with a standardizer,
//   Pstandardizer.mean, Pstandardizer.std (in);
// plus a string attribute "Parchitecture" on the root group holding the JSON of
// architecture.hpp. Several networks share a file under different prefixes
// (an autoencoder: "encoder." and "decoder."). Matrices are row-major rows × cols
// datasets, so h5py reads W as a NumPy (out, in) array like torch's state_dict.
#include <optional>
#include <string>

#include "io/hdf5.hpp"
#include "nn/adam.hpp"
#include "nn/sequential.hpp"
#include "nn/standardizer.hpp"

namespace lb::nn {

/// Write `net` (and optionally its input standardizer) under `prefix`.
void save_network(h5::File& file, const std::string& prefix, Sequential& net,
                  const Standardizer* standardizer = nullptr);

struct LoadedNetwork {
    Sequential network;
    std::optional<Standardizer> standardizer;
};

/// Rebuild and load the network saved under `prefix`. Throws IoError naming the
/// file and dataset when something is missing or has the wrong shape.
LoadedNetwork load_network(const h5::File& file, const std::string& prefix);

/// One-network convenience: create `path` (written to a temporary and renamed, so a
/// failure leaves no partial file) / open it read-only.
void save_network(const std::string& path, const std::string& prefix, Sequential& net,
                  const Standardizer* standardizer = nullptr);
LoadedNetwork load_network(const std::string& path, const std::string& prefix);

/// Optimiser state for checkpoints: datasets `<prefix>adam/m/<param>`, `<prefix>adam/v/<param>`
/// (one per parameter, in the order of `params`) and the attribute `<prefix>adam_step` on "/".
void save_adam_state(h5::File& file, const std::string& prefix, const Adam& adam,
                     const std::vector<ParameterRef>& params);
/// Restore what save_adam_state wrote into `adam`; IoError if shapes or names differ.
void load_adam_state(const h5::File& file, const std::string& prefix, Adam& adam,
                     const std::vector<ParameterRef>& params);

} // namespace lb::nn
