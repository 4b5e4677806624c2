#pragma once
// The serial value-and-gradient pass of an element energy vectorised across elements: the
// training losses' hot loop (Energy::add_value_gradient, once per sample of every batch).
//
// The element kernels of ElementEnergy work on one element's fixed-size matrices, so the
// compiler can only use short vectors inside an element. Here the elements are stored in
// blocks of kLanes (structure of arrays: the vertex indices and the P per-element
// parameters, e.g. shape gradients and rest measure, an array over the block's lanes), and
// one loop over the lanes runs the whole element kernel, which the compiler turns into one
// SIMD lane per element (8 doubles with AVX-512). Gradients are scattered lane by lane after
// each block (elements share vertices). The last block is padded with copies of the last
// element whose lane scale is 0, so padding adds exactly 0 and never divides by zero.
//
// A kernel is a callable inlined into that loop:
//   double kernel(const double (&x)[K][3], const auto& p, double (&g)[K][3])
// returning E_e(x) and writing ∂E_e/∂x_a to g[a]; p[j] (j < P) reads the element's parameters
// (a double array on the one-element path, a view into the block on the lane path). An energy using it runs the same kernel for
// one element (evaluate, its local_value_gradient), so there is one copy of its formulas; the
// energy tests check the blocked pass against value() and gradient() (check_fused_value_gradient)
// and the gradient against finite differences of value(), whose local_value is written apart.
#include <array>
#include <vector>

#include "core/types.hpp"
#include "energy/energy.hpp"

namespace lb {

template <int K, int P>
class ElementLanes {
public:
    static constexpr int kLanes = Energy::kColumnLanes;  // 8 doubles: one AVX-512 register
    using Params = std::array<double, P>;

    ElementLanes() = default;
    /// @param n          number of elements
    /// @param nodes      K vertex indices of element e at nodes[K e + a]
    /// @param params_of  e ↦ the P parameters of element e (Params)
    template <typename ParamsOf>
    ElementLanes(Index n, const int* nodes, ParamsOf&& params_of)
    {
        m_count = n;
        m_blocks.resize(std::size_t((n + kLanes - 1) / kLanes));
        for (std::size_t k = 0; k < m_blocks.size(); ++k) {
            Block& blk = m_blocks[k];
            for (int l = 0; l < kLanes; ++l) {
                const Index real = Index(k) * kLanes + l;
                const Index e = real < n ? real : n - 1;
                blk.scale[l] = real < n ? 1.0 : 0.0;
                const Params p = params_of(e);
                for (int j = 0; j < P; ++j) blk.params[j][l] = p[std::size_t(j)];
                for (int a = 0; a < K; ++a) blk.nodes[a][l] = nodes[K * e + a];
            }
        }
    }

    /// The kernel on one gathered element (xe and g 3K, xyz interleaved): the per-element path
    /// (local_value_gradient) of an energy whose lane kernel is its one value-and-gradient code.
    template <typename Kernel>
    static double evaluate(const Eigen::Matrix<double, 3 * K, 1>& xe, const Params& params,
                           Eigen::Matrix<double, 3 * K, 1>& g, const Kernel& kernel)
    {
        double x[K][3], p[P], ge[K][3];
        for (int a = 0; a < K; ++a) {
            for (int i = 0; i < 3; ++i) x[a][i] = xe[3 * a + i];
        }
        for (int j = 0; j < P; ++j) p[j] = params[std::size_t(j)];
        const double value = kernel(x, p, ge);
        for (int a = 0; a < K; ++a) {
            for (int i = 0; i < 3; ++i) g[3 * a + i] = ge[a][i];
        }
        return value;
    }

    /// Returns Σ_e E_e(x) and adds weight · ∇E(x) to g (both 3N, xyz interleaved); serial,
    /// allocates nothing.
    template <typename Kernel>
    double add_value_gradient(const VectorXd& x, double weight, VectorXd& g, const Kernel& kernel) const
    {
        const double* xd = x.data();
        double* gd = g.data();
        double sum = 0.0;
        alignas(64) double xs[K][3][kLanes];
        alignas(64) double out[K][3][kLanes];
        for (const Block& blk : m_blocks) {
            // Gather first, so the lane loop below reads and writes unit-stride arrays only.
            for (int a = 0; a < K; ++a) {
                for (int l = 0; l < kLanes; ++l) {
                    const double* xa = xd + 3 * Index(blk.nodes[a][l]);
                    for (int i = 0; i < 3; ++i) xs[a][i][l] = xa[i];
                }
            }

            alignas(64) double values[kLanes];
#pragma omp simd
            for (int l = 0; l < kLanes; ++l) {
                double xe[K][3], ge[K][3];
                for (int a = 0; a < K; ++a) {
                    for (int i = 0; i < 3; ++i) xe[a][i] = xs[a][i][l];
                }
                // Not a private copy: GCC stores a private array of P > 1 doubles per lane
                // with a stride and then refuses the loop ("not suitable for scatter store").
                const LaneParams p{&blk.params[0][l]};
                const double s = blk.scale[l];
                values[l] = s * kernel(xe, p, ge);
                for (int a = 0; a < K; ++a) {
                    for (int i = 0; i < 3; ++i) out[a][i][l] = s * ge[a][i];
                }
            }
            for (int l = 0; l < kLanes; ++l) sum += values[l];
            for (int l = 0; l < kLanes; ++l) {
                for (int a = 0; a < K; ++a) {
                    double* ga = gd + 3 * Index(blk.nodes[a][l]);
                    for (int i = 0; i < 3; ++i) ga[i] += weight * out[a][i][l];
                }
            }
        }
        return sum;
    }

    /// The same pass with the lanes over kLanes samples (columns) instead of over elements: X
    /// and G hold 3N × kLanes numbers, row-major (coordinate r of sample l at r · kLanes + l),
    /// so a lane's gather and scatter are unit-stride vector loads and stores. Adds weight ·
    /// ∇E of sample l to its column of G and E of sample l to values[l]; serial, allocates
    /// nothing. Element by element in the element pass's order, each lane computing, storing
    /// and then adding what that pass does for its sample: the two passes give the same
    /// numbers bit for bit (tests/energy/test_column_lanes.cpp checks every lane energy).
    template <typename Kernel>
    void add_value_gradient_columns(const double* X, double weight, double* G, double* values,
                                    const Kernel& kernel) const
    {
        // Two elements per lane loop: one element's kernel is a chain of dependent divisions
        // and square roots (the hinge's atan2), and two independent chains can overlap. (The
        // gain was not separable from the machine's noise: hinge 5.1 against 5.4 µs per
        // sample, one run each.) Their values and gradients are still added in element order.
        Index e = 0;
        for (; e + 1 < m_count; e += 2) column_step<2>(e, X, weight, G, values, kernel);
        if (e < m_count) column_step<1>(e, X, weight, G, values, kernel);
    }

private:
    /// p[j] of one lane, read in place from the block's structure of arrays.
    struct LaneParams {
        const double* first;  ///< &params[0][lane]
        double operator[](int j) const { return first[j * kLanes]; }
    };

    /// add_value_gradient_columns's step: elements e, …, e + M − 1 on every sample lane.
    template <int M, typename Kernel>
    void column_step(Index e, const double* X, double weight, double* G, double* values, const Kernel& kernel) const
    {
        const double* xa[M][K];
        double* ga[M][K];
        const double* params[M];
        // The element's lane scale (1: e is a real element), multiplied in as the element pass
        // does: the compiler fuses v's product into the sum below (the element pass cannot,
        // its sum being scalar), and a product with 1 is exact, so fused or not the sum is
        // the same.
        double s[M];
        for (int m = 0; m < M; ++m) {
            const Block& blk = m_blocks[std::size_t((e + m) / kLanes)];
            const int slot = int((e + m) % kLanes);
            for (int a = 0; a < K; ++a) {
                xa[m][a] = X + 3 * kLanes * Index(blk.nodes[a][slot]);
                ga[m][a] = G + 3 * kLanes * Index(blk.nodes[a][slot]);
            }
            params[m] = &blk.params[0][slot];
            s[m] = blk.scale[slot];
        }
        alignas(64) double v[M][kLanes];
        alignas(64) double out[M][K][3][kLanes];
        // Element m of the step on lane l (m a constant where it is called: GCC does not
        // unroll a loop over m inside the lane loop, and then refuses to vectorise it).
        auto element = [&](int m, int l) {
            double xe[K][3], ge[K][3];
            for (int a = 0; a < K; ++a) {
                for (int i = 0; i < 3; ++i) xe[a][i] = xa[m][a][i * kLanes + l];
            }
            v[m][l] = s[m] * kernel(xe, LaneParams{params[m]}, ge);  // the same element in every lane
            for (int a = 0; a < K; ++a) {
                for (int i = 0; i < 3; ++i) out[m][a][i][l] = s[m] * ge[a][i];
            }
        };
#pragma omp simd
        for (int l = 0; l < kLanes; ++l) {
            element(0, l);
            if constexpr (M == 2) element(1, l);
        }
        for (int m = 0; m < M; ++m) {
            for (int l = 0; l < kLanes; ++l) values[l] += v[m][l];
            for (int a = 0; a < K; ++a) {
                for (int i = 0; i < 3; ++i) {
                    double* gi = ga[m][a] + i * kLanes;
                    for (int l = 0; l < kLanes; ++l) gi[l] += weight * out[m][a][i][l];
                }
            }
        }
    }
    struct alignas(64) Block {
        int nodes[K][kLanes];
        double params[P][kLanes];
        double scale[kLanes];  ///< 1, or 0 for padding
    };
    std::vector<Block> m_blocks;
    Index m_count = 0;  ///< elements (the last block's padding excluded)
};

} // namespace lb
