#pragma once
// Thread-count policy. Element loops go parallel only above a size where the
// fork/join cost (and, on a loaded 2-core machine, spin-waiting threads) is
// repaid: a 576-DOF cloth step ran 40× slower with two OpenMP threads than
// with one while other processes held both cores.
namespace lb {

/// Minimum number of elements for an OpenMP-parallel element loop.
constexpr long kParallelElementThreshold = 2048;
/// Minimum number of columns (samples, frames) for an OpenMP-parallel loop over the columns
/// of a batch of states whose per-column work is a pass over the vertices (a training batch
/// has hundreds; a rollout step one).
constexpr long kParallelColumns = 16;

/// Set the number of threads used by latentbench's OpenMP loops (≤ 0: all cores).
void set_num_threads(int threads);
int num_threads();

} // namespace lb
