#pragma once
// Thread-count policy. Element loops go parallel only above a size where the
// fork/join cost (and, on a loaded 2-core machine, spin-waiting threads) is
// repaid: a 576-DOF cloth step ran 40× slower with two OpenMP threads than
// with one while other processes held both cores.
namespace lb {

/// Minimum number of elements for an OpenMP-parallel element loop.
constexpr long kParallelElementThreshold = 2048;

/// Set the number of threads used by latentbench's OpenMP loops (≤ 0: all cores).
void set_num_threads(int threads);
int num_threads();

} // namespace lb
