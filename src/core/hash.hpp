#pragma once
// FNV-1a, 64 bit: content hashes of in-memory inputs (option text, network weights,
// training data) for checkpoint fingerprints and cache keys. Not cryptographic: it
// guards against accidental reuse of results made from other inputs.
//
//   h₀ = 14695981039346656037,  h ← (h ⊕ byte) · 1099511628211  for every byte.
//
// Matrices are hashed with their shape (rows, cols as int64) before their entries in
// column-major order, so a reshaped array hashes differently.
#include <cstdint>
#include <cstdio>
#include <string>
#include <type_traits>

#include "core/types.hpp"

namespace lb {

class Fnv1a64 {
public:
    static constexpr std::uint64_t offset_basis = 1469598103934665603ull;
    static constexpr std::uint64_t prime = 1099511628211ull;

    Fnv1a64& add_bytes(const void* data, std::size_t size)
    {
        const auto* bytes = static_cast<const unsigned char*>(data);
        for (std::size_t i = 0; i < size; ++i) {
            m_hash ^= bytes[i];
            m_hash *= prime;
        }
        return *this;
    }
    /// The characters of `text` only (no length), so fnv1a64_hex(a + b) chains.
    Fnv1a64& add(const std::string& text) { return add_bytes(text.data(), text.size()); }
    /// The bytes of one scalar (integers, doubles: bitwise, so −0.0 ≠ 0.0).
    template <class T, class = std::enable_if_t<std::is_arithmetic_v<T>>>
    Fnv1a64& add(T value)
    {
        return add_bytes(&value, sizeof value);
    }
    /// Shape, then entries column by column.
    Fnv1a64& add(const Eigen::Ref<const MatrixXd>& m) { return add_matrix(m); }
    Fnv1a64& add(const Eigen::Ref<const MatrixXi>& m) { return add_matrix(m); }

    std::uint64_t value() const { return m_hash; }
    /// 16 lower-case hex digits.
    std::string hex() const
    {
        char buf[17];
        std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(m_hash));
        return buf;
    }

private:
    template <class M>
    Fnv1a64& add_matrix(const M& m)
    {
        add(std::int64_t(m.rows()));
        add(std::int64_t(m.cols()));
        for (Index j = 0; j < m.cols(); ++j) {
            add_bytes(m.col(j).data(), sizeof(typename M::Scalar) * static_cast<std::size_t>(m.rows()));
        }
        return *this;
    }

    std::uint64_t m_hash = offset_basis;
};

/// FNV-1a/64 of the characters of `text` as 16 hex digits.
inline std::string fnv1a64_hex(const std::string& text) { return Fnv1a64().add(text).hex(); }

} // namespace lb
