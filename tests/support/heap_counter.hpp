#pragma once
// Counts the process's heap allocations while switched on: the test executable replaces
// the C library's malloc family (heap_counter.cpp) with versions that count and then call
// glibc's own allocator; every C++ `new` and Eigen's aligned allocations end there. Linked
// into the test executables listed in LB_HEAP_COUNTED_TESTS (tests/CMakeLists.txt). Not
// available under AddressSanitizer (which replaces the same functions) nor outside glibc:
// heap_counting_available() is then false.
#include <cstddef>

namespace lb::testing {

bool heap_counting_available();

/// Counting on from construction to destruction; count() is the number of calls to malloc,
/// calloc, realloc, posix_memalign, aligned_alloc, memalign, valloc and pvalloc made by any
/// thread in between (free is not counted).
class HeapCounter {
public:
    HeapCounter();
    ~HeapCounter();
    HeapCounter(const HeapCounter&) = delete;
    HeapCounter& operator=(const HeapCounter&) = delete;
    long count() const;

private:
    long m_start;
};

} // namespace lb::testing
