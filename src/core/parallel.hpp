#pragma once
// Thread-count policy. Element loops go parallel only above a size where the
// fork/join cost (and, on a loaded 2-core machine, spin-waiting threads) is
// repaid: a 576-DOF cloth step ran 40× slower with two OpenMP threads than
// with one while other processes held both cores.
#include <cstddef>

#include <omp.h>

namespace lb {

/// Minimum number of elements for an OpenMP-parallel element loop.
constexpr long kParallelElementThreshold = 2048;
/// Minimum number of columns (samples, frames) for an OpenMP-parallel loop over the columns
/// of a batch of states whose per-column work is a pass over the vertices (a training batch
/// has hundreds; a rollout step one).
constexpr long kParallelColumns = 16;

/// body(i) for i in [0, n): over the OpenMP threads if `parallel` (schedule static, or
/// dynamic with chunk 1 if `dynamic`), else in the calling thread, as also with one thread or
/// inside a parallel region. Unlike `#pragma omp parallel for if (parallel)`, the serial path
/// opens no OpenMP region: libgomp allocates a team for every region that runs on one thread
/// (a false `if`, one thread), a heap allocation that the trainer's batches avoid.
template <typename Body>
void parallel_for(std::ptrdiff_t n, bool parallel, Body&& body, bool dynamic = false)
{
    if (!parallel || n < 2 || omp_get_max_threads() < 2 || omp_in_parallel()) {
        for (std::ptrdiff_t i = 0; i < n; ++i) body(i);
        return;
    }
    if (dynamic) {
#pragma omp parallel for schedule(dynamic, 1)
        for (std::ptrdiff_t i = 0; i < n; ++i) body(i);
    } else {
#pragma omp parallel for schedule(static)
        for (std::ptrdiff_t i = 0; i < n; ++i) body(i);
    }
}

/// Set the number of threads used by latentbench's OpenMP loops (≤ 0: all cores).
void set_num_threads(int threads);
int num_threads();

} // namespace lb
