#pragma once
// What a training checkpoint was made from, and the rules for reusing one.
//
// A checkpoint is resumed only if every part of its fingerprint equals this run's:
// the resolved training options (every field that changes the numbers), and content
// hashes of the inputs (the autoencoder's weights, the training data, the physics,
// the initial network). Parts are compared one by one so that a refusal says which
// input changed. A checkpoint that does not match, cannot be read, or whose tensors
// have the wrong shapes is never resumed: it is set aside as `<path>.stale.<n>` (the
// first n free: an earlier set-aside is never replaced) with a log line giving the
// reason and the new name, and training starts from scratch. No checkpoint is ever
// deleted: one that cannot be set aside stops the run (IoError), left in place.
//
// File layout: root attributes "fingerprint.parts" (comma-separated part names) and
// "fingerprint.<name>" (the part's text) for every part.
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/hash.hpp"
#include "io/hdf5.hpp"
#include "nn/sequential.hpp"

namespace lb::nn {

struct Fingerprint {
    /// (name, value) in comparison order, e.g. {"options", "..."}, {"data", "a1b2..."}.
    std::vector<std::pair<std::string, std::string>> parts;

    Fingerprint& add(std::string name, std::string value)
    {
        parts.emplace_back(std::move(name), std::move(value));
        return *this;
    }
};

void write_fingerprint(h5::File& file, const Fingerprint& fingerprint);
/// Empty if `file` carries exactly the parts of `expected` with equal values; otherwise
/// the reason, naming the first part that differs (e.g. "its options differ: epochs=3
/// vs epochs=6" for the "options" part, "its autoencoder differs" for a hash part).
std::string fingerprint_mismatch(const h5::File& file, const Fingerprint& expected);

/// Thrown while reading a checkpoint whose tensors do not fit this run (shape or name
/// differences); the training loop sets such a checkpoint aside.
class CheckpointMismatch : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Throws CheckpointMismatch naming `what` unless `loaded` is rows × cols.
void require_shape(const std::string& what, const MatrixXd& loaded, Index rows, Index cols);
/// Copy the parameters and buffers of `src` into `dst` (storage of `dst` kept, so an
/// optimiser holding references stays valid), after checking that every name and shape
/// agrees; nothing is copied if one differs (CheckpointMismatch).
void copy_network_state(Sequential& dst, Sequential& src);

/// Rename `path` to `path + ".stale.<n>"`, n the first free number from 1 (an existing
/// name is never replaced), log `reason` and the new name, and return it. IoError, with
/// `path` left in place, if it cannot be renamed.
std::string set_aside_checkpoint(const std::string& path, const std::string& reason);

/// Add the names, shapes and values of every parameter and buffer of `net` to `hash`.
void hash_network(Fnv1a64& hash, Sequential& net);

/// "%a" text of a double (exact, for fingerprints).
std::string exact_text(double value);

} // namespace lb::nn
