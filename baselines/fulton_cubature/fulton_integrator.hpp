#pragma once
// `fulton_cubature` / `fulton_full` (Fulton et al. 2019, "Latent-space dynamics for reduced
// deformable simulation"; DESIGN §4 "Baselines"): every step minimises the implicit-Euler
// incremental potential over the latent z of the autoencoder's decoder,
//
//   Φ(z) = 1/(2h²)‖x(z) − x̃‖²_M + Σ_{e∈C} w_e E_e(x_e(z)) − gᵀM x(z) [+ w_bc Σ_B ‖x_i(z) − x*_i‖²]
//
// with the decoder split at its PCA layer, x(z) = U s + c_t, s = g(z) (pca_split_decoder.hpp).
// The previous states are the method's own decoded states x_{t−k} = U s_{t−k} + c_{t−k}, so
// with Δs = s − s̃, s̃ = 2s_{t−1} − s_{t−2}, and δc = A(t_t − 2t_{t−1} + t_{t−2}) (the
// Dirichlet targets' acceleration through the offset):
//   inertia   1/(2h²)[Δsᵀ(UᵀMU)Δs + 2Δsᵀ(UᵀMA)δt + δcᵀMδc]     O(d_pca²) per evaluation
//   gravity   −(UᵀMg)ᵀs − (Mg)ᵀc_t                                 O(d_pca)
//   elastic   cubature: Σ_{e∈C} w_e E_e on x_V = U_V s + c_V, V the cubature elements'
//             vertices (only those are decoded);  full (fulton_full, the "oracle" of Sharp
//             et al. 2023): the exact E_elastic of x = U s + c_t, O(N d_pca)
//   penalty   exact, on the Dirichlet vertices' decoded rows (cloth and solids; rods decode
//             their roots exactly and have none: applied_penalty_weight)
//   ∇_z Φ = J_g(z)ᵀ ∇_s Φ, one vector-Jacobian product through the inner network g, with
//   ∇_s Φ = (UᵀMU Δs + UᵀMA δt)/h² − UᵀMg + U_Vᵀ ∇_{x_V}(elastic + penalty).
// Minimised by L-BFGS (NLopt, solver/lbfgs.hpp) from the extrapolation z₀ = 2z_{t−1} − z_{t−2}.
//
// Preconditioning (not in Fulton et al.; needed here): at h = 1/30 with w_bc = 1e5 and
// stiff materials the step is badly scaled in z (curvatures ~1e8 against gradients ~1e5
// on the small cantilever), and NLopt's L-BFGS then fails its very first line search. So
// L-BFGS runs in y, z = z₀ + P y, with P = L⁻ᵀ, L Lᵀ = J_gᵀ H_s J_g the Gauss–Newton
// reduced Hessian at a recent state: H_s = UᵀMU/h² + Σ_e w_e U_eᵀ[∇²E_e]₊U_e (element
// Hessians projected to PSD; every element for fulton_full) + 2 w_bc U_BᵀU_B. It is
// computed at reset() and every `preconditioner_refresh` steps (a fixed linear change of
// variables within a step; L-BFGS itself is untouched), and again at the best point when
// NLopt gives up on a step (one retry, its counts added to the step's summary). Converged when
//   ‖∇_yΦ‖ = ‖Pᵀ∇_zΦ‖ ≤ gradient_tolerance · √(force scale · length scale),
// ½‖∇_yΦ‖² being the predicted energy decrease left (a Newton decrement), in J.
// Every step's SolveSummary is kept; a step that did not converge is counted and the first
// one logged, never silent; a non-finite state is returned as NaN (ends the stable horizon).
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "baselines/fulton_cubature/cubature.hpp"
#include "baselines/fulton_cubature/pca_split_decoder.hpp"
#include "integrators/integrator.hpp"
#include "solver/lbfgs.hpp"

namespace lb {

struct FultonOptions {
    double penalty_weight = 1e5;  ///< w_bc (cloth, solids; rods use hard roots)
    /// Converged when ‖Pᵀ∇_zΦ‖ ≤ gradient_tolerance · √(force_scale · length_scale) (above).
    double gradient_tolerance = 1e-6;
    /// Recompute the preconditioner every this many steps (0: only at reset()).
    int preconditioner_refresh = 10;
    /// Evaluations of Φ and ∇Φ per step (L-BFGS line-search trials included).
    int max_evaluations = 200;
    /// L-BFGS correction pairs.
    int history_size = 10;
};

class FultonIntegrator final : public Integrator {
public:
    /// @param cubature  the elastic cubature (fulton_cubature); std::nullopt: the exact
    ///                  full-space elastic energy (fulton_full)
    FultonIntegrator(std::string name, std::shared_ptr<Autoencoder> autoencoder, const PhysicsModel& model,
                     std::optional<Cubature> cubature, FultonOptions options);

    std::string name() const override { return m_name; }
    void reset(const VectorXd& x_prev2, const BoundaryState& bc_prev2, const VectorXd& x_prev,
               const BoundaryState& bc_prev) override;
    /// Integration: the L-BFGS solve (decoding only the cubature vertices); decode: x = U s + c_t.
    StepTiming step(const BoundaryState& bc) override;
    const VectorXd& positions() const override { return m_x; }
    const VectorXd& latent() const override { return m_z; }

    /// Φ(z) for the step to `bc` from the current state (after reset()), and ∇_zΦ if asked:
    /// exposed for derivative tests.
    double objective(const VectorXd& z, const BoundaryState& bc, VectorXd* gradient);
    /// The same objective through LatentPotential's full decode (no split, no cubature): equal
    /// to objective() for fulton_full up to round-off (a test of the precomputation).
    double reference_objective(const VectorXd& z, const BoundaryState& bc);

    bool uses_cubature() const { return m_cubature.has_value(); }
    /// Vertices decoded per evaluation (the cubature elements' and the Dirichlet ones; all for fulton_full).
    Index decoded_vertices() const { return m_cubature ? Index(m_vertices.size()) : m_model.num_vertices(); }
    /// One summary per step since construction (over every reset).
    const std::vector<SolveSummary>& summaries() const { return m_summaries; }
    int unconverged_steps() const { return m_unconverged; }
    double mean_iterations() const;
    double mean_evaluations() const;

private:
    class StepObjective;
    void prepare_step(const BoundaryState& bc);
    /// P from the Gauss–Newton reduced Hessian at latent z with decoded positions x (3N).
    void update_preconditioner(const VectorXd& z, const VectorXd& x);
    double evaluate(const Eigen::Ref<const VectorXd>& z, VectorXd* grad_z);

    std::string m_name;
    std::shared_ptr<Autoencoder> m_autoencoder;
    const PhysicsModel& m_model;
    std::optional<Cubature> m_cubature;
    FultonOptions m_options;
    PcaSplitDecoder m_split;
    double m_penalty_weight = 0.0;
    LbfgsOptions m_lbfgs;
    LbfgsWorkspace m_workspace;

    // Cubature: the decoded vertices V (the elements' and, with a penalty, the Dirichlet
    // ones), their rows of U, and each element's vertices as offsets into V.
    std::vector<int> m_vertices;
    MatrixXd m_U_V;                   ///< 3|V| × d_pca
    std::vector<int> m_element_slots; ///< per cubature element, its K local vertex slots (flattened)
    std::vector<int> m_bc_slots;      ///< slot in V of each Dirichlet vertex (cubature mode)

    // The step being solved (prepare_step).
    VectorXd m_s_tilde, m_q, m_c, m_c_V, m_targets;
    MatrixXd m_P;  ///< preconditioner, latent × latent
    VectorXd m_z_start;
    int m_steps_since_preconditioner = 0;
    double m_constant = 0.0;  ///< δcᵀMδc/(2h²) − (Mg)ᵀc_t
    // State.
    VectorXd m_z, m_z_prev, m_s_prev, m_s_prev2, m_t_prev, m_t_prev2, m_x;
    // Buffers.
    VectorXd m_x_buffer, m_grad_V, m_grad_x;

    std::vector<SolveSummary> m_summaries;
    int m_unconverged = 0;
};

} // namespace lb
