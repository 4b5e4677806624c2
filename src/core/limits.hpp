#pragma once
// Upper limits of integer options, shared by the TOML readers, the file readers and
// the command line. Beyond them a value is a typo or would not fit in memory; it is
// refused with a message naming the option before anything is allocated.
#include <limits>

namespace lb {

inline constexpr int kMaxWidth = 8192;  ///< layer widths, latent and PCA dimensions
inline constexpr int kMaxEpochs = 10'000'000;
inline constexpr int kMaxBatch = 10'000'000;
inline constexpr int kMaxThreads = 1024;
inline constexpr long long kMaxSeed = std::numeric_limits<long long>::max();  ///< seeds are ≥ 0
/// Meshes, generated or read from a file: beyond these a scene could not be simulated on
/// one machine anyway. A tet grid has about 6 tetrahedra per vertex (make_tet_beam).
inline constexpr long long kMaxMeshVertices = 2'000'000;
inline constexpr long long kMaxMeshElements = 6 * kMaxMeshVertices;

} // namespace lb
