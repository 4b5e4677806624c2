#pragma once
// Cubature for the elastic energy in a reduced space (An, Kim & James 2008, "Optimizing
// cubature for efficient integration of subspace deformations"), written here from
// the paper. With the decoder split at its PCA layer (pca_split_decoder.hpp), x = U s + c:
//
//   E(x) = Σ_e E_e(x_e)  ≈  Σ_{e∈C} w_e E_e(x_e),   w_e ≥ 0,  |C| ≪ #elements
//
// fitted so that the reduced elastic forces f(s) = Uᵀ∇E(x) (d_pca) match on training
// poses. "Elements" are every stencil of every elastic term of the scene (rod edges and
// bending triples, triangles and hinges, tets), indexed term by term.
//
// Training (train_cubature):
//   poses      x_p, p = 1..T: the caller passes the autoencoder's reconstructions of the
//              training frames (what the integrator can reach), at most max_poses of them
//              evenly spaced;
//   targets    b = [f_1/|f_1|; …; f_T/|f_T|] (T·d_pca), each pose's force normalised
//              (poses with |f_p| below 1e-12 of the largest carry no information: skipped);
//   columns    a_e = [U_eᵀ∇E_e(x_1)/|f_1|; …] for element e (U_e: its vertices' rows of U);
//   greedy     r = b; repeat: draw `candidates` unselected elements at random (seeded), add
//              the one with the largest a_eᵀr/|a_e|, solve the NNLS min_{w≥0}|A_C w − b|
//              (Lawson–Hanson, solver/nnls.hpp) for every selected column, r = b − A_C w;
//              stop when |r|/|b| ≤ tolerance, |C| = max_elements, or no candidate
//              correlates positively with r. Elements whose weight ended at 0 are dropped.
//
// The relative force error reported for a set of poses is |A_C w − b| / |b| with b and
// A built from those poses as above (so training_error is the final greedy residual).
#include <cstdint>
#include <string>
#include <vector>

#include "sim/physics_model.hpp"

namespace lb::h5 {
class File;
}

namespace lb {

class PcaSplitDecoder;

struct CubatureOptions {
    /// Stop when the relative force error on the training poses is at most this.
    double tolerance = 0.02;
    /// Stop at this many selected elements.
    int max_elements = 200;
    /// Random unselected elements scored per greedy iteration (all if fewer remain).
    int candidates = 500;
    /// At most this many training poses, evenly spaced over the given ones.
    int max_poses = 100;
    std::uint64_t seed = 0;
};

struct CubatureElement {
    int term = 0;        ///< index into PhysicsModel::elastic_terms()
    Index element = 0;   ///< element of that term
    double weight = 0.0; ///< w_e ≥ 0
};

struct Cubature {
    std::vector<CubatureElement> elements;
    double training_error = 0.0;  ///< relative force error on the training poses
    int training_poses = 0;       ///< poses used (after skipping force-free ones)
    double seconds = 0.0;         ///< training wall-clock time
    bool reached_tolerance = false;
    /// Why the greedy loop stopped: "tolerance", "element cap" (max_elements selected, some
    /// possibly at weight 0 and dropped), "no correlated element" or "every element".
    std::string stop_reason;

    /// Every element of every elastic term at unit weight: E exactly (for tests).
    static Cubature all_elements(const PhysicsModel& model);
    /// Into an open file: datasets cubature.terms, cubature.elements (int), cubature.weights;
    /// attributes cubature.format "latentbench.cubature/1", cubature.training_error,
    /// cubature.training_poses, cubature.seconds, cubature.reached_tolerance (0/1),
    /// cubature.stop_reason.
    void save(h5::File& file) const;
    /// IoError naming the file if it holds no cubature or an element does not exist in `model`.
    static Cubature load(const h5::File& file, const PhysicsModel& model);
};

/// Greedy cubature on the poses (3N × T positions). Never throws on missing the tolerance
/// (reached_tolerance says); ConfigError on bad options or fewer than one usable pose.
Cubature train_cubature(const PhysicsModel& model, const PcaSplitDecoder& decoder, const MatrixXd& poses,
                        const CubatureOptions& options);

/// How well a cubature reproduces the elastic energy and reduced force on poses (3N × T).
struct CubatureAccuracy {
    double force_error = 0.0;   ///< relative force error, as in training (normalised per pose)
    double energy_error = 0.0;  ///< Σ_p |Ê_p − E_p| / Σ_p |E_p|
};
CubatureAccuracy cubature_accuracy(const PhysicsModel& model, const PcaSplitDecoder& decoder, const Cubature& cubature,
                                   const MatrixXd& poses);

/// Σ_{e∈C} w_e E_e(x) and, if `gradient` is non-null, its gradient Σ w_e ∇E_e (3N, over
/// the elements' vertices only; the rest are zero).
double cubature_energy(const PhysicsModel& model, const Cubature& cubature, const VectorXd& x, VectorXd* gradient);

} // namespace lb
