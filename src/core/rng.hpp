#pragma once
// Seeded random numbers: every stochastic component takes an Rng seeded from
// the run's configuration, so runs are reproducible.
#include <cstdint>
#include <random>

#include "core/types.hpp"

namespace lb {

class Rng {
public:
    explicit Rng(std::uint64_t seed = 0) : m_engine(seed) { }
    double uniform(double lo = 0.0, double hi = 1.0)
    {
        return std::uniform_real_distribution<double>(lo, hi)(m_engine);
    }
    double normal(double mean = 0.0, double stddev = 1.0)
    {
        return std::normal_distribution<double>(mean, stddev)(m_engine);
    }
    /// Uniform integer in [0, n).
    Index index(Index n) { return std::uniform_int_distribution<Index>(0, n - 1)(m_engine); }
    VectorXd uniform_vector(Index n, double lo, double hi)
    {
        VectorXd v(n);
        for (Index i = 0; i < n; ++i) v[i] = uniform(lo, hi);
        return v;
    }
    std::mt19937_64& engine() { return m_engine; }

private:
    std::mt19937_64 m_engine;
};

} // namespace lb
