// keep_freed_memory (core/allocator.hpp): after it, freeing blocks at the top of the heap
// does not hand the memory back to the kernel (the program break stays where it was), and
// a block of a few MB comes from the heap, not from a fresh mapping. Before 2026-12-03 the
// policy compiled to nothing (its #if was tested before any C library header defined
// __GLIBC__); this test failed there.
#include <gtest/gtest.h>

#include <cstdlib>
#include <vector>

#if defined(__GLIBC__)
#include <malloc.h>
#include <unistd.h>
#endif

#include "core/allocator.hpp"

namespace lb {
namespace {

#if defined(__GLIBC__)
TEST(KeepFreedMemory, FreedHeapTopIsKept)
{
    keep_freed_memory();
    std::vector<char*> blocks;
    for (int i = 0; i < 160; ++i) {
        blocks.push_back(static_cast<char*>(std::malloc(100 * 1024)));  // 16 MB in all, each below
                                                                         // glibc's default mmap threshold
        ASSERT_NE(blocks.back(), nullptr);
        blocks.back()[0] = 1;
    }
    char* big = static_cast<char*>(std::malloc(8 << 20));  // above glibc's default mmap threshold
    ASSERT_NE(big, nullptr);
    big[0] = 1;
    // The 8 MB block came from the heap, not from a mapping of its own.
    EXPECT_EQ(mallinfo2().hblkhd, 0u) << "bytes in mmapped blocks";
    const void* top = sbrk(0);
    std::free(big);
    for (auto it = blocks.rbegin(); it != blocks.rend(); ++it) std::free(*it);
    EXPECT_EQ(sbrk(0), top) << "the heap was trimmed after free";
}
#endif

} // namespace
} // namespace lb
