#include "core/allocator.hpp"

#include <cstdlib>  // defines __GLIBC__ (features.h); without a C library header first,
                    // the test below was always false and the policy compiled to nothing
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace lb {

void keep_freed_memory()
{
#if defined(__GLIBC__)
    constexpr int kMmapThreshold = 1 << 30;  // bytes: larger blocks still get their own mapping
    constexpr int kTrimThreshold = 0x7fffffff;  // bytes of free heap top kept before trimming
    mallopt(M_MMAP_THRESHOLD, kMmapThreshold);
    mallopt(M_TRIM_THRESHOLD, kTrimThreshold);
#endif
}

} // namespace lb
