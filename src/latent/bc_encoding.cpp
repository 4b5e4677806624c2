#include <cassert>
#include "latent/bc_encoding.hpp"

#include <string>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/rigid_motion.hpp"

namespace lb {

const char* encoding_frame_name(EncodingFrame frame)
{
    return frame == EncodingFrame::rigid ? "rigid" : "translation";
}

EncodingFrame parse_encoding_frame(const std::string& text)
{
    if (text == "translation") return EncodingFrame::translation;
    if (text == "rigid") return EncodingFrame::rigid;
    throw ConfigError("unknown encoding frame '" + text + "' (expected 'translation' or 'rigid')");
}

BcRelativeEncoding::BcRelativeEncoding(const PhysicsSpec& physics, EncodingFrame frame)
    : m_rod_relative(physics.mesh.kind == MeshKind::Rods),
      m_frame(frame),
      m_num_dofs(3 * physics.mesh.num_vertices()),
      m_bc_indices(physics.bc_indices)
{
    const Index N = physics.mesh.num_vertices();
    if (m_bc_indices.empty())
        throw ConfigError("BC-relative encoding: the physics has no Dirichlet vertices to encode relative to");
    std::vector<int> bc_slot(static_cast<std::size_t>(N), -1);  // vertex -> index within bc_indices
    for (std::size_t b = 0; b < m_bc_indices.size(); ++b) {
        const int v = m_bc_indices[b];
        if (v < 0 || v >= N)
            throw ConfigError("BC-relative encoding: Dirichlet vertex " + std::to_string(v) + " outside the mesh (" +
                              std::to_string(N) + " vertices)");
        bc_slot[static_cast<std::size_t>(v)] = static_cast<int>(b);
    }
    if (m_frame == EncodingFrame::rigid) {
        m_rest_frame = RestFrame(dirichlet_positions(m_bc_indices, flatten(physics.mesh.rest_positions)));
        const Index B = m_rest_frame.size();
        if (!m_rest_frame.fixes_rotation())
            throw ConfigError("BC-relative encoding: the rigid frame needs a Dirichlet set that fixes a rotation (at "
                              "least three non-collinear vertices); this one has " + std::to_string(B) +
                              (B < 3 ? " vertices" : " collinear vertices") + " (use frame = \"translation\")");
    }

    if (!m_rod_relative) {
        m_num_features = m_num_dofs;
        return;
    }

    // Rods: every vertex belongs to one rod whose root (chain start) is a Dirichlet vertex.
    constexpr int unassigned = -1, is_root = -2;
    std::vector<int> root_slot(static_cast<std::size_t>(N), unassigned);
    const auto& rods = physics.mesh.rods;
    if (rods.empty()) throw ConfigError("BC-relative encoding: a rod mesh without rod chains (mesh.rods is empty)");
    for (std::size_t r = 0; r < rods.size(); ++r) {
        const auto& chain = rods[r];
        if (chain.empty()) throw ConfigError("BC-relative encoding: rod " + std::to_string(r) + " is empty");
        const int root = chain.front();
        const int slot = bc_slot[static_cast<std::size_t>(root)];
        if (slot < 0)
            throw ConfigError("BC-relative encoding: the root vertex " + std::to_string(root) + " of rod " +
                              std::to_string(r) + " is not a Dirichlet vertex (root-relative encoding needs "
                              "prescribed roots)");
        root_slot[static_cast<std::size_t>(root)] = is_root;
        for (std::size_t k = 1; k < chain.size(); ++k) {
            const int v = chain[k];
            if (root_slot[static_cast<std::size_t>(v)] != unassigned)
                throw ConfigError("BC-relative encoding: vertex " + std::to_string(v) + " belongs to two rods");
            root_slot[static_cast<std::size_t>(v)] = slot;
        }
    }
    // Features in ascending vertex order, roots skipped.
    for (Index v = 0; v < N; ++v) {
        const int s = root_slot[static_cast<std::size_t>(v)];
        if (s == unassigned)
            throw ConfigError("BC-relative encoding: vertex " + std::to_string(v) + " belongs to no rod");
        if (s == is_root) continue;
        m_rod_vertices.emplace_back(static_cast<int>(v), s);
    }
    m_num_features = 3 * static_cast<Index>(m_rod_vertices.size());
}

const char* BcRelativeEncoding::kind_name() const
{
    if (m_frame == EncodingFrame::rigid) return m_rod_relative ? "rod_root_rigid" : "dirichlet_rigid";
    return m_rod_relative ? "rod_root" : "dirichlet_mean";
}

Vector3d BcRelativeEncoding::bc_mean(const Eigen::Ref<const VectorXd>& x) const
{
    Vector3d mean = Vector3d::Zero();
    for (int v : m_bc_indices) mean += x.segment<3>(3 * Index(v));
    return mean / double(m_bc_indices.size());
}

Matrix3d BcRelativeEncoding::frame_rotation(const double* p) const
{
    return m_frame == EncodingFrame::translation ? Matrix3d::Identity() : m_rest_frame.rotation(p);
}

MatrixXd BcRelativeEncoding::to_features(const MatrixXd& X) const
{
    if (X.rows() != m_num_dofs)
        throw std::invalid_argument("BcRelativeEncoding::to_features: expected " + std::to_string(m_num_dofs) +
                                    " rows, got " + std::to_string(X.rows()));
    const Index S = X.cols();
    MatrixXd F(m_num_features, S);
    for (Index s = 0; s < S; ++s) {
        const Matrix3d Rt = frame_rotation(dirichlet_positions(m_bc_indices, X.col(s)).data()).transpose();
        if (m_rod_relative) {
            for (std::size_t k = 0; k < m_rod_vertices.size(); ++k) {
                const auto [v, slot] = m_rod_vertices[k];
                const int root = m_bc_indices[static_cast<std::size_t>(slot)];
                F.col(s).segment<3>(3 * Index(k)) =
                    Rt * (X.col(s).segment<3>(3 * Index(v)) - X.col(s).segment<3>(3 * Index(root)));
            }
        } else {
            const Vector3d mean = bc_mean(X.col(s));
            for (Index i = 0; i < m_num_dofs / 3; ++i) F.col(s).segment<3>(3 * i) = Rt * (X.col(s).segment<3>(3 * i) - mean);
        }
    }
    return F;
}

template <typename Scalar>
void BcRelativeEncoding::positions_of_frame(const Scalar* f, const double* targets, double* x) const
{
    const Index B = static_cast<Index>(m_bc_indices.size());
    Eigen::Map<const Eigen::Matrix<Scalar, Eigen::Dynamic, 1>> F(f, m_num_features);
    Eigen::Map<const VectorXd> T(targets, 3 * B);
    Eigen::Map<VectorXd> X(x, m_num_dofs);
    const Matrix3d R = frame_rotation(targets);
    if (m_rod_relative) {
        // Roots take their targets (written for every Dirichlet vertex, then overwritten on
        // the non-root ones, which are decoded like any other vertex: root + feature).
        for (Index b = 0; b < B; ++b) X.segment<3>(3 * Index(m_bc_indices[std::size_t(b)])) = T.segment<3>(3 * b);
        for (std::size_t k = 0; k < m_rod_vertices.size(); ++k) {
            const auto [v, slot] = m_rod_vertices[k];
            X.segment<3>(3 * Index(v)) = R * F.template segment<3>(3 * Index(k)).template cast<double>() + T.segment<3>(3 * Index(slot));
        }
    } else {
        Vector3d mean = Vector3d::Zero();
        for (Index b = 0; b < B; ++b) mean += T.segment<3>(3 * b);
        mean /= double(B);
        for (Index i = 0; i < m_num_dofs / 3; ++i) X.segment<3>(3 * i) = R * F.template segment<3>(3 * i).template cast<double>() + mean;
    }
}

void BcRelativeEncoding::to_positions_into(const Eigen::Ref<const VectorXd>& f, const Eigen::Ref<const VectorXd>& targets,
                                           Eigen::Ref<VectorXd> x) const
{
    assert(f.size() == m_num_features && targets.size() == 3 * Index(m_bc_indices.size()) && x.size() == m_num_dofs);
    positions_of_frame(f.data(), targets.data(), x.data());
}

void BcRelativeEncoding::to_positions_into(const Eigen::Ref<const Eigen::VectorXf>& f,
                                           const Eigen::Ref<const VectorXd>& targets, Eigen::Ref<VectorXd> x) const
{
    assert(f.size() == m_num_features && targets.size() == 3 * Index(m_bc_indices.size()) && x.size() == m_num_dofs);
    positions_of_frame(f.data(), targets.data(), x.data());
}

template <typename Scalar>
void BcRelativeEncoding::positions_of_columns(
    const Eigen::Ref<const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>>& F,
    const Eigen::Ref<const MatrixXd>& targets, Eigen::Ref<MatrixXd> X) const
{
    const Index B = static_cast<Index>(m_bc_indices.size());
    if (F.rows() != m_num_features || targets.rows() != 3 * B || targets.cols() != F.cols() ||
        X.rows() != m_num_dofs || X.cols() != F.cols())
        throw std::invalid_argument("BcRelativeEncoding::to_positions: expected " + std::to_string(m_num_features) +
                                    " × S features, " + std::to_string(3 * B) + " × S targets and " +
                                    std::to_string(m_num_dofs) + " × S positions, got " + std::to_string(F.rows()) +
                                    " × " + std::to_string(F.cols()) + ", " + std::to_string(targets.rows()) + " × " +
                                    std::to_string(targets.cols()) + " and " + std::to_string(X.rows()) + " × " +
                                    std::to_string(X.cols()));
    // Columns are independent: parallel over a training batch, serial for a rollout's one frame.
    parallel_for(F.cols(), F.cols() >= kParallelColumns,
                 [&](Index s) { positions_of_frame(F.col(s).data(), targets.col(s).data(), X.col(s).data()); });
}

MatrixXd BcRelativeEncoding::to_positions(const Eigen::Ref<const MatrixXd>& F,
                                          const Eigen::Ref<const MatrixXd>& targets) const
{
    MatrixXd X(m_num_dofs, F.cols());
    positions_of_columns<double>(F, targets, X);
    return X;
}

void BcRelativeEncoding::to_positions(const Eigen::Ref<const MatrixXd>& F, const Eigen::Ref<const MatrixXd>& targets,
                                      Eigen::Ref<MatrixXd> X) const
{
    positions_of_columns<double>(F, targets, X);
}

void BcRelativeEncoding::to_positions(const Eigen::Ref<const Eigen::MatrixXf>& F,
                                      const Eigen::Ref<const MatrixXd>& targets, Eigen::Ref<MatrixXd> X) const
{
    positions_of_columns<float>(F, targets, X);
}

template <typename Scalar>
void BcRelativeEncoding::gradient_into(const Eigen::Ref<const MatrixXd>& grad_x, const Eigen::Ref<const MatrixXd>& targets,
                                       Eigen::Ref<Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>> G) const
{
    const Index B = static_cast<Index>(m_bc_indices.size());
    if (grad_x.rows() != m_num_dofs || targets.rows() != 3 * B || targets.cols() != grad_x.cols() ||
        G.rows() != m_num_features || G.cols() != grad_x.cols())
        throw std::invalid_argument("BcRelativeEncoding::gradient_to_features: expected " + std::to_string(m_num_dofs) +
                                    " × S gradients, " + std::to_string(3 * B) + " × S targets and " +
                                    std::to_string(m_num_features) + " × S features, got " +
                                    std::to_string(grad_x.rows()) + " × " + std::to_string(grad_x.cols()) + ", " +
                                    std::to_string(targets.rows()) + " × " + std::to_string(targets.cols()) + " and " +
                                    std::to_string(G.rows()) + " × " + std::to_string(G.cols()));
    const bool identity = !m_rod_relative && m_frame == EncodingFrame::translation;  // P = I
    parallel_for(grad_x.cols(), grad_x.cols() >= kParallelColumns, [&](Index s) {
        if (identity) {
            G.col(s) = grad_x.col(s).template cast<Scalar>();
            return;
        }
        const Matrix3d Rt = frame_rotation(targets.col(s).data()).transpose();
        if (m_rod_relative) {
            for (std::size_t k = 0; k < m_rod_vertices.size(); ++k)
                G.col(s).template segment<3>(3 * Index(k)) =
                    (Rt * grad_x.col(s).segment<3>(3 * Index(m_rod_vertices[k].first))).template cast<Scalar>();
        } else {
            for (Index i = 0; i < m_num_dofs / 3; ++i)
                G.col(s).template segment<3>(3 * i) = (Rt * grad_x.col(s).segment<3>(3 * i)).template cast<Scalar>();
        }
    });
}

MatrixXd BcRelativeEncoding::gradient_to_features(const Eigen::Ref<const MatrixXd>& grad_x,
                                                  const Eigen::Ref<const MatrixXd>& targets) const
{
    MatrixXd G(m_num_features, grad_x.cols());
    gradient_into<double>(grad_x, targets, G);
    return G;
}

void BcRelativeEncoding::gradient_to_features(const Eigen::Ref<const MatrixXd>& grad_x,
                                              const Eigen::Ref<const MatrixXd>& targets, Eigen::Ref<MatrixXd> G) const
{
    gradient_into<double>(grad_x, targets, G);
}

void BcRelativeEncoding::gradient_to_features(const Eigen::Ref<const MatrixXd>& grad_x,
                                              const Eigen::Ref<const MatrixXd>& targets,
                                              Eigen::Ref<Eigen::MatrixXf> G) const
{
    gradient_into<float>(grad_x, targets, G);
}

} // namespace lb
