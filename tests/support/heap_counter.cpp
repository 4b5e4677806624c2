#include "support/heap_counter.hpp"

#include <atomic>
#include <cerrno>

#if defined(__SANITIZE_ADDRESS__)
#define LB_HEAP_COUNTER 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define LB_HEAP_COUNTER 0
#endif
#endif
#if !defined(LB_HEAP_COUNTER) && defined(__GLIBC__)
#define LB_HEAP_COUNTER 1
#elif !defined(LB_HEAP_COUNTER)
#define LB_HEAP_COUNTER 0
#endif

namespace {
std::atomic<long> g_allocations{0};
std::atomic<int> g_counting{0};

inline void note_allocation()
{
    if (g_counting.load(std::memory_order_relaxed) != 0) g_allocations.fetch_add(1, std::memory_order_relaxed);
}
} // namespace

#if LB_HEAP_COUNTER
// glibc's allocator under its internal names; the definitions below take the public ones.
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* ptr, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
void* __libc_valloc(std::size_t size);
void* __libc_pvalloc(std::size_t size);
void __libc_free(void* ptr);

void* malloc(std::size_t size)
{
    note_allocation();
    return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size)
{
    note_allocation();
    return __libc_calloc(count, size);
}
void* realloc(void* ptr, std::size_t size)
{
    note_allocation();
    return __libc_realloc(ptr, size);
}
void* memalign(std::size_t alignment, std::size_t size)
{
    note_allocation();
    return __libc_memalign(alignment, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size)
{
    note_allocation();
    return __libc_memalign(alignment, size);
}
void* valloc(std::size_t size)
{
    note_allocation();
    return __libc_valloc(size);
}
void* pvalloc(std::size_t size)
{
    note_allocation();
    return __libc_pvalloc(size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size)
{
    note_allocation();
    if (alignment % sizeof(void*) != 0 || (alignment & (alignment - 1)) != 0) return EINVAL;
    void* p = __libc_memalign(alignment, size);
    if (p == nullptr && size != 0) return ENOMEM;
    *out = p;
    return 0;
}
void free(void* ptr) { __libc_free(ptr); }
}
#endif

namespace lb::testing {

bool heap_counting_available() { return LB_HEAP_COUNTER != 0; }

HeapCounter::HeapCounter() : m_start(g_allocations.load())
{
    g_counting.fetch_add(1);
}

HeapCounter::~HeapCounter() { g_counting.fetch_sub(1); }

long HeapCounter::count() const { return g_allocations.load() - m_start; }

} // namespace lb::testing
