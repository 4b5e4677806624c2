#include "solver/sparse_cholesky.hpp"

#include <Eigen/CholmodSupport>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>
#include <type_traits>
#include <unordered_map>
#include <vector>

#include "core/error.hpp"

#include <omp.h>

namespace lb {

namespace {

/// CHOLMOD's heap, kept between factorisations. Each numeric factorisation of a supernodal
/// factor allocates a permuted copy of A (cholmod_ptranspose), and each cholmod_solve2
/// reallocates its Y workspace (CHOLMOD reshapes it during the solve): a few blocks of the
/// same sizes per Newton iteration, megabytes each on the full-size scenes. This allocator,
/// installed in SuiteSparse_config before CHOLMOD's first allocation, keeps freed blocks by
/// size and hands them back for the same size, so a Newton step of a pattern it has seen
/// calls malloc nothing (tests/sim/test_step_allocations.cpp). At most kMaxCachedBytes stay
/// cached; beyond that, blocks go back to malloc's free.
class CholmodMemory {
public:
    static void install()
    {
        static std::once_flag once;
        std::call_once(once, [] {
            SuiteSparse_config.malloc_func = &CholmodMemory::allocate;
            SuiteSparse_config.calloc_func = &CholmodMemory::allocate_zeroed;
            SuiteSparse_config.realloc_func = &CholmodMemory::reallocate;
            SuiteSparse_config.free_func = &CholmodMemory::release;
        });
    }

private:
    /// Before every block: its usable size (16 bytes, so the block keeps malloc's alignment).
    struct alignas(16) Header {
        size_t capacity;
    };
    static constexpr size_t kMaxCachedBytes = size_t(512) << 20;
    static constexpr size_t kMaxBlocksPerSize = 64;

    static CholmodMemory& pool()
    {
        static CholmodMemory* instance = new CholmodMemory;  // never destroyed: CHOLMOD may free at exit
        return *instance;
    }
    static Header* header(void* p) { return static_cast<Header*>(p) - 1; }

    static void* allocate(size_t size)
    {
        if (size == 0) size = 1;
        CholmodMemory& m = pool();
        {
            std::lock_guard<std::mutex> lock(m.m_mutex);
            auto it = m.m_free.find(size);
            if (it != m.m_free.end() && !it->second.empty()) {
                void* p = it->second.back();
                it->second.pop_back();
                m.m_cached -= size;
                return p;
            }
        }
        if (size > SIZE_MAX - sizeof(Header)) return nullptr;
        auto* h = static_cast<Header*>(std::malloc(sizeof(Header) + size));
        if (!h) return nullptr;
        h->capacity = size;
        return h + 1;
    }
    static void* allocate_zeroed(size_t count, size_t size)
    {
        if (size != 0 && count > SIZE_MAX / size) return nullptr;
        void* p = allocate(count * size);
        if (p) std::memset(p, 0, count * size);
        return p;
    }
    static void* reallocate(void* p, size_t size)
    {
        if (!p) return allocate(size);
        const size_t capacity = header(p)->capacity;
        if (size <= capacity) return p;
        void* q = allocate(size);
        if (!q) return nullptr;  // p stays valid, as realloc's contract says
        std::memcpy(q, p, capacity);
        release(p);
        return q;
    }
    static void release(void* p)
    {
        if (!p) return;
        const size_t capacity = header(p)->capacity;
        CholmodMemory& m = pool();
        {
            std::lock_guard<std::mutex> lock(m.m_mutex);
            if (m.m_cached + capacity <= kMaxCachedBytes) {
                std::vector<void*>& blocks = m.m_free[capacity];
                if (blocks.capacity() == 0) blocks.reserve(kMaxBlocksPerSize);  // pushes never reallocate
                if (blocks.size() < kMaxBlocksPerSize) {
                    blocks.push_back(p);
                    m.m_cached += capacity;
                    return;
                }
            }
        }
        std::free(header(p));
    }

    std::mutex m_mutex;
    std::unordered_map<size_t, std::vector<void*>> m_free;  ///< freed blocks by capacity
    size_t m_cached = 0;                                    ///< bytes in m_free
};

/// CHOLMOD's own OpenMP loops run serially while this lives. Debian's CHOLMOD (SuiteSparse
/// 5.12) opens a region of num_threads(CHOLMOD_OMP_NUM_THREADS = 4) for every large
/// supernode, to zero and scatter it: thousands of fork/joins per factorisation, four
/// threads on a 2-core machine. On the full armadillo (10k DOFs, 0.17 GFLOP per
/// factorisation) the numeric factorisation took 122 ms with them and 20-25 ms without,
/// and a full-space step 226-297 ms against 132 ms (bench sim_phase/armadillo/factorize,
/// sim_step/armadillo, 2026-12-07, with the command line's thread environment). The BLAS
/// inside is untouched (one thread under the command line's OPENBLAS_NUM_THREADS=1).
/// libgomp keeps max-active-levels in one global, so only the initial thread outside any
/// parallel region changes it (inside one, CHOLMOD's regions are nested, and libgomp runs
/// nested regions on one thread unless nesting is enabled).
class SerialOpenMp {
public:
    SerialOpenMp() : m_levels(omp_in_parallel() ? -1 : omp_get_max_active_levels())
    {
        if (m_levels > 0) omp_set_max_active_levels(0);
    }
    ~SerialOpenMp()
    {
        if (m_levels > 0) omp_set_max_active_levels(m_levels);
    }
    SerialOpenMp(const SerialOpenMp&) = delete;
    SerialOpenMp& operator=(const SerialOpenMp&) = delete;

private:
    int m_levels;
};

} // namespace

struct SparseCholesky::Impl {
    /// Eigen's wrapper, with its factor exposed for cholmod_solve2.
    struct Decomposition : Eigen::CholmodDecomposition<SparseMatrixd, Eigen::Lower> {
        cholmod_factor* factor() { return m_cholmodFactor; }
    };
    Decomposition llt;
    // cholmod_solve2's solution and workspace, reused while the size stays (freed with
    // llt's cholmod_common, before it is finished).
    cholmod_dense* x = nullptr;
    cholmod_dense* y = nullptr;
    cholmod_dense* e = nullptr;
    ~Impl()
    {
        for (cholmod_dense** d : {&x, &y, &e}) {
            if (*d) cholmod_free_dense(d, &llt.cholmod());
        }
    }
};
static_assert(std::is_same_v<SparseMatrixd::StorageIndex, int>, "cholmod_solve2 below is CHOLMOD's int interface");

SparseCholesky::SparseCholesky() : m_impl((CholmodMemory::install(), std::make_unique<Impl>()))
{
    // LLᵀ, supernodal or simplicial as CHOLMOD's flop-count heuristic decides
    // (supernodal for every scene we ship; simplicial for very sparse factors).
    m_impl->llt.setMode(Eigen::CholmodAuto);
    // Failures are reported through FactorStatus; CHOLMOD's own stderr warnings
    // ("matrix not positive definite") would only repeat them.
    m_impl->llt.cholmod().print = 0;
}
SparseCholesky::~SparseCholesky() = default;

void SparseCholesky::analyze(const SparseMatrixd& lower)
{
    {
        const SerialOpenMp serial;
        m_impl->llt.analyzePattern(lower);
    }
    if (m_impl->llt.info() != Eigen::Success) {
        throw NumericalError("CHOLMOD symbolic analysis failed");
    }
    m_analyzed = true;
}

FactorStatus SparseCholesky::factorize(const SparseMatrixd& lower)
{
    if (!m_analyzed) analyze(lower);
    const double* v = lower.valuePtr();
    for (Index i = 0; i < lower.nonZeros(); ++i) {
        if (!std::isfinite(v[i])) {
            m_message = "non-finite entry in the Hessian";
            return FactorStatus::Fatal;
        }
    }
    {
        const SerialOpenMp serial;
        m_impl->llt.factorize(lower);
    }
    switch (m_impl->llt.info()) {
    case Eigen::Success:
        m_message.clear();
        return FactorStatus::Success;
    case Eigen::NumericalIssue:
        m_message = "matrix not positive definite";
        return FactorStatus::NotPositiveDefinite;
    default:
        m_message = "CHOLMOD factorisation failed";
        return FactorStatus::Fatal;
    }
}

double SparseCholesky::factor_nonzeros() const { return m_analyzed ? m_impl->llt.cholmod().lnz : 0.0; }
double SparseCholesky::factorization_flops() const { return m_analyzed ? m_impl->llt.cholmod().fl : 0.0; }

VectorXd SparseCholesky::solve(const VectorXd& b) const { return m_impl->llt.solve(b); }

void SparseCholesky::solve(const VectorXd& b, VectorXd& x)
{
    Impl& impl = *m_impl;
    cholmod_dense rhs = Eigen::viewAsCholmod(const_cast<VectorXd&>(b));
    const SerialOpenMp serial;
    if (!cholmod_solve2(CHOLMOD_A, impl.llt.factor(), &rhs, nullptr, &impl.x, nullptr, &impl.y, &impl.e,
                        &impl.llt.cholmod()))
        throw NumericalError("CHOLMOD solve failed (status " + std::to_string(impl.llt.cholmod().status) + ")");
    x.resize(b.size());
    std::copy_n(static_cast<const double*>(impl.x->x), size_t(b.size()), x.data());
}

} // namespace lb
