#pragma once
// E(D(z)): the implicit-Euler incremental potential of the positions an autoencoder
// decodes from a latent, and its gradient with respect to the latent through the
// frozen decoder. The physics shared by the latent methods: Li et al. 2025's
// self-supervised integrator loss (integrators/trainer.hpp), Fulton et al. 2019's
// latent optimisation, Tan et al.'s physics-loss MLP.
//
//   x    = D(z; x*_B)                          3N, decoded BC-relative (autoencoder.hpp)
//   E(x) = 1/(2h²)(x − x̃)ᵀM(x − x̃) + E_elastic(x) − Σ m_i g·x_i [+ w_bc Σ_B |x_i − x*_i|²],
//   x̃    = 2 x_{t−1} − x_{t−2}                 (sim/physics_model.hpp)
//   ∇_z E(D(z)) = J_D(z)ᵀ ∇_x E(x)             one vector-Jacobian product through the decoder
//
// w_bc is applied_penalty_weight(model, penalty_weight) (sim/physics_model.hpp): the
// penalty for cloth and solids, none for rods (their roots are decoded exactly).
// With overwrite_dirichlet, every decoded x has its Dirichlet vertices replaced by their
// targets x*_B (evaluate() and decode()): x_B no longer depends on z, so the penalty term is
// 0 and J_Dᵀ∇E takes no contribution from the Dirichlet rows (their ∇_x E rows are zeroed
// before the VJP). Rods decode their roots exactly anyway, so it changes nothing there.
// The decoder is evaluated in eval mode and never modified. A caller that will not change
// the decoder either (the integrator trainers) may freeze_decoder(): the decoder is then
// compiled once (BatchNorm folded into the linear layers, nn/inference_network.hpp) and a
// batch costs one decoder pass with the VJP reusing it, instead of two.
#include <memory>
#include <vector>

#include "core/error.hpp"
#include "latent/autoencoder.hpp"
#include "nn/inference_network.hpp"
#include "sim/physics_model.hpp"

namespace lb {

/// A checked evaluation found a non-finite incremental potential: `column` is the first
/// column of the batch with one, `value` its energy. Callers that know what the columns
/// are (the integrator trainer: its samples) rethrow it naming the sample.
class NonFinitePotential : public NumericalError {
public:
    NonFinitePotential(Index column, double value)
        : NumericalError("non-finite incremental potential (" + text(value) + ") in column " + std::to_string(column) +
                         " of the training batch"),
          column(column),
          value(value)
    {
    }
    Index column;
    double value;
    /// "NaN", "inf" or "-inf" (std::to_string writes "-nan" for some NaNs).
    static std::string text(double value) { return value != value ? "NaN" : value > 0 ? "inf" : "-inf"; }
};

/// What evaluate() computes besides the per-sample energies.
struct LatentEnergyOptions {
    bool gradient = false;  ///< compute LatentEnergies::grad_z
    bool decoded = false;   ///< return the decoded positions LatentEnergies::X
    /// Per-sample weights w_i (B); empty: every w_i = 1.
    VectorXd weights;
    /// n of the objective Σ_i w_i E_i / n (e.g. the batch size B for a weighted mean).
    double normalization = 1.0;
};

/// The result of LatentPotential::evaluate for B samples.
struct LatentEnergies {
    VectorXd energies;       ///< E_i = E(D(z_i); x_{t−1,i}, x_{t−2,i}, x*_{B,i}), unweighted (B)
    double objective = 0.0;  ///< Σ_i w_i E_i / n
    /// ∂objective/∂z_i = (w_i / n) J_D(z_i)ᵀ ∇_x E_i(D(z_i)), latent × B (if options.gradient).
    MatrixXd grad_z;
    /// (w_i / n) ∇_x E_i(x_i), 3N × B (if options.gradient): what grad_z back-propagates
    /// (its Dirichlet rows 0 if the decoded Dirichlet vertices are overwritten).
    MatrixXd grad_x;
    MatrixXd X;  ///< D(z_i), 3N × B (if options.decoded)
};

class LatentPotential {
public:
    /// @param model           the physics; must outlive this object
    /// @param autoencoder     whose decoder D is used (frozen); must outlive this object
    /// @param penalty_weight  the configured w_bc (> 0); the applied one follows the
    ///                        boundary policy (applied_penalty_weight: 0 for rods)
    /// @param overwrite_dirichlet  replace the decoded Dirichlet vertices by their targets
    LatentPotential(const PhysicsModel& model, Autoencoder& autoencoder, double penalty_weight,
                    bool overwrite_dirichlet = false);

    /// The w_bc applied (0 for rods: hard roots).
    double penalty_weight() const { return m_penalty_weight; }
    bool overwrites_dirichlet() const { return m_overwrite_dirichlet; }
    const PhysicsModel& model() const { return m_model; }
    Autoencoder& autoencoder() { return m_autoencoder; }

    // One sample. A non-finite energy is returned as it is (optimisers treat it as a
    // failed trial point).
    /// E(D(z)).
    /// @param z           latent
    /// @param bc_targets  3B Dirichlet targets x*_B of the step (decoding and penalty)
    /// @param x_prev      3N positions x_{t−1}
    /// @param x_prev2     3N positions x_{t−2}
    double value(const Eigen::Ref<const VectorXd>& z, const Eigen::Ref<const VectorXd>& bc_targets,
                 const Eigen::Ref<const VectorXd>& x_prev, const Eigen::Ref<const VectorXd>& x_prev2);
    /// E(D(z)) and grad_z = J_D(z)ᵀ ∇_x E(D(z)) (latent); arguments as value().
    double value_and_gradient(const Eigen::Ref<const VectorXd>& z, const Eigen::Ref<const VectorXd>& bc_targets,
                              const Eigen::Ref<const VectorXd>& x_prev, const Eigen::Ref<const VectorXd>& x_prev2,
                              VectorXd& grad_z);

    /// B samples (columns): one batched decode, the energies (and their x-gradients) in
    /// parallel over the samples (OpenMP, one IncrementalPotential per thread), then one
    /// batched decoder VJP of the weighted x-gradients (w_i / n) ∇_x E_i.
    /// Throws NumericalError if an energy is not finite.
    /// @param Z           latent × B
    /// @param bc_targets  3B_dirichlet × B Dirichlet targets of the steps
    /// @param X_prev      3N × B positions x_{t−1}
    /// @param X_prev2     3N × B positions x_{t−2}
    LatentEnergies evaluate(const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& bc_targets,
                            const Eigen::Ref<const MatrixXd>& X_prev, const Eigen::Ref<const MatrixXd>& X_prev2,
                            const LatentEnergyOptions& options = {});
    /// evaluate() with the steps' history given as x̃ = 2 x_{t−1} − x_{t−2} (3N × B), which is
    /// all the potential reads of it (the inertia term): for callers that keep x̃, as the
    /// integrator trainer does per training sample. The same numbers as evaluate() on the
    /// x_{t−1}, x_{t−2} that inertial_target() (energy/inertia_energy.hpp) turns into X_tilde.
    LatentEnergies evaluate_tilde(const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& bc_targets,
                                  const Eigen::Ref<const MatrixXd>& X_tilde, const LatentEnergyOptions& options = {});
    /// evaluate_tilde's objective Σ_i w_i E_i / n, and with `gradient` its z-gradient into
    /// grad_z (latent × B, shaped by the caller; ignored without): the training loop's form.
    /// The energies, positions and x-gradients stay in buffers the potential keeps, so with a
    /// frozen decoder nothing is allocated once they have grown to the batch.
    /// @param weights  B per-sample weights, or empty for all 1
    double objective_tilde(const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& bc_targets,
                           const Eigen::Ref<const MatrixXd>& X_tilde, const Eigen::Ref<const VectorXd>& weights,
                           double normalization, bool gradient, Eigen::Ref<MatrixXd> grad_z);

    /// Compile the decoder as it is now and use that copy from here on (see above). The
    /// results equal the live decoder's to round-off (the folding reorders operations);
    /// later changes to the autoencoder's weights are NOT seen. With `float32`, the copy
    /// computes in single precision (latents in, features and their VJP out are converted;
    /// the energies stay double): about half the GEMM cost, results to float round-off.
    void freeze_decoder(bool float32 = false);
    bool decoder_frozen() const { return m_frozen != nullptr || m_frozen_float != nullptr; }
    bool decoder_float32() const { return m_frozen_float != nullptr; }
    /// D(z) for latent × B codes and 3B × B targets: the frozen copy if any, else the
    /// autoencoder's decode(); Dirichlet vertices overwritten if overwrites_dirichlet().
    MatrixXd decode(const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& bc_targets);
    /// The same into X (3N × B, shaped by the caller): with a frozen decoder, no allocation
    /// once its buffers have grown to the batch. `record` keeps the frozen decoder's tape for
    /// the z-gradient (evaluate's use).
    void decode(const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& bc_targets,
                Eigen::Ref<MatrixXd> X, bool record = false);

    /// The incremental potentials of B given position vectors (no decoding) and, if
    /// options.gradient, their weighted x-gradients LatentEnergies::grad_x (grad_z stays
    /// empty): for losses that back-propagate through a decoder themselves.
    /// Throws NumericalError if an energy is not finite.
    /// @param X  3N × B positions x_t; other arguments as evaluate()
    LatentEnergies evaluate_positions(const Eigen::Ref<const MatrixXd>& X, const Eigen::Ref<const MatrixXd>& bc_targets,
                                      const Eigen::Ref<const MatrixXd>& X_prev,
                                      const Eigen::Ref<const MatrixXd>& X_prev2, const LatentEnergyOptions& options);

private:
    /// Energies, objective and (if options.gradient) weighted x-gradients of the columns of X.
    void energies_of(const Eigen::Ref<const MatrixXd>& X, const Eigen::Ref<const MatrixXd>& bc_targets,
                     const Eigen::Ref<const MatrixXd>& X_tilde, const LatentEnergyOptions& options, bool check_finite,
                     LatentEnergies& out);
    /// energies_of into caller-shaped outputs (energies B, grad_x 3N × B or empty without the
    /// gradient); weights B or empty (all 1); returns the objective. Its weights live in kept
    /// buffers: no allocation.
    double energies_into(const Eigen::Ref<const MatrixXd>& X, const Eigen::Ref<const MatrixXd>& bc_targets,
                         const Eigen::Ref<const MatrixXd>& X_tilde, const Eigen::Ref<const VectorXd>& sample_weights,
                         double normalization, bool gradient, bool check_finite, Eigen::Ref<VectorXd> energies,
                         Eigen::Ref<MatrixXd> grad_x);
    /// energies_of's gradient pass for the Energy::kColumnLanes columns from c0 on: the terms
    /// with a column pass (the elastic ones) run on all of them at once, the others column
    /// by column; the same numbers as one IncrementalPotential::value_gradient per column, bit
    /// for bit (terms in the same order, each column's sums in the same order).
    void energies_of_columns(Index c0, const Eigen::Ref<const MatrixXd>& X, const Eigen::Ref<const MatrixXd>& bc_targets,
                             const Eigen::Ref<const MatrixXd>& X_tilde, const Eigen::Ref<const VectorXd>& gradient_scale,
                             Eigen::Ref<VectorXd> energies, Eigen::Ref<MatrixXd> grad_x);
    /// Give `pot` column i's x̃ and Dirichlet targets.
    static void set_column_state(IncrementalPotential& pot, Index i, const Eigen::Ref<const MatrixXd>& bc_targets,
                                 const Eigen::Ref<const MatrixXd>& X_tilde);
    /// inertial_target(X_prev, X_prev2) after checking both are 3N × B (throws Error naming `caller`).
    MatrixXd checked_x_tilde(const char* caller, Index B, const Eigen::Ref<const MatrixXd>& X_prev,
                             const Eigen::Ref<const MatrixXd>& X_prev2) const;
    /// evaluate_columns and objective_tilde: the shape checks (throws Error), the decoding into
    /// m_decoded, energies and (with `gradient`) x- and z-gradients into caller-shaped
    /// outputs; returns the objective. Throws on a non-finite energy iff check_finite.
    double evaluate_into(const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& bc_targets,
                         const Eigen::Ref<const MatrixXd>& X_tilde, const Eigen::Ref<const VectorXd>& weights,
                         double normalization, bool gradient, bool check_finite, Eigen::Ref<VectorXd> energies,
                         Eigen::Ref<MatrixXd> grad_x, Eigen::Ref<MatrixXd> grad_z);
    /// evaluate_tilde(), with the shape checks (throws Error); throws on a non-finite energy iff check_finite.
    LatentEnergies evaluate_columns(const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& bc_targets,
                                    const Eigen::Ref<const MatrixXd>& X_tilde, const LatentEnergyOptions& options,
                                    bool check_finite);

    /// decode()'s positions of the features the (frozen or live) decoder gave, double or
    /// float: the encoding's, with the Dirichlet vertices overwritten if asked for.
    template <typename Features>
    void positions_of(const Features& features, const Eigen::Ref<const MatrixXd>& bc_targets,
                      Eigen::Ref<MatrixXd> X) const;
    /// The frozen copy's forward to positions (`record` keeps its tape for frozen_vjp), and
    /// the vector-Jacobian product of position gradients back to latents, in its precision
    /// (the float copy takes its features and gives its VJP input without a double copy).
    /// Outputs shaped by the caller (X 3N × B, grad_z latent × B).
    void frozen_positions(const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& bc_targets,
                          bool record, Eigen::Ref<MatrixXd> X);
    void frozen_vjp(const Eigen::Ref<const MatrixXd>& grad_x, const Eigen::Ref<const MatrixXd>& bc_targets,
                    Eigen::Ref<MatrixXd> grad_z);

    const PhysicsModel& m_model;
    Autoencoder& m_autoencoder;
    double m_penalty_weight = 0.0;
    bool m_overwrite_dirichlet = false;
    std::vector<IncrementalPotential> m_potentials;  ///< one per thread
    /// Per thread, one per lane of energies_of_columns (kColumnLanes each, thread-major): each
    /// holds its column's x̃ and Dirichlet targets for the whole pass.
    std::vector<IncrementalPotential> m_lane_potentials;
    std::vector<VectorXd> m_gradients;               ///< one x-gradient workspace per thread
    std::vector<VectorXd> m_positions;               ///< one decoded-state workspace per thread
    /// Per thread, energies_of_columns's workspace: the columns' positions and gradients
    /// transposed (3N × kColumnLanes, row-major) and each column's gradient.
    struct ColumnWorkspace {
        VectorXd X, G;
        std::vector<VectorXd> g;
    };
    std::vector<ColumnWorkspace> m_columns;
    std::unique_ptr<nn::InferenceNetworkD> m_frozen;       ///< freeze_decoder()'s compiled decoder
    std::unique_ptr<nn::InferenceNetwork> m_frozen_float;  ///< or its single-precision copy
    // Batch workspaces that only grow: evaluate's decoded positions, the double copy's VJP
    // input, the float copy's input (latents, then VJP seeds).
    nn::GrowingMatrix<double> m_decoded, m_feature_grad;
    // objective_tilde's energies (B × 1) and x-gradients; energies_into's weights and scales.
    nn::GrowingMatrix<double> m_energies, m_grad_x, m_weights, m_gradient_scale;
    nn::GrowingMatrix<float> m_float_in;
};

} // namespace lb
