#pragma once
// The network layer interface of lb::nn: explicit forward / backward passes on
// double-precision batches, forward-mode tangents, and named parameter access
// in PyTorch state_dict style.
//
// Data layout everywhere in lb::nn: features × batch (one column = one sample).
//
// Contract of a layer:
//   Y  = forward(X, training)      caches what backward/tangent need (the last call wins)
//                                  Y and dX are views of buffers the layer owns (storage
//                                  that only grows: no allocation once a layer has seen
//                                  its batch sizes), valid until its next forward/backward
//   dX = backward(dY, param_grads) reverse mode at the cached point; if
//                                  param_grads, parameter gradients are ACCUMULATED
//                                  (+=) into the gradient buffers (call zero_grad first).
//                                  Without param_grads, and after a single-sample
//                                  forward, dY may have any number of columns (several
//                                  adjoint seeds at one sample: rows of a Jacobian)
//   dY = tangent(dX)               forward mode at the cached point (eval mode only);
//                                  dX has either as many columns as the cached batch
//                                  (one tangent per sample) or, when the cached batch
//                                  is a single sample, any number of columns (all
//                                  tangents taken at that one sample)
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/types.hpp"
#include "nn/workspace.hpp"

namespace lb::nn {

/// A trainable tensor: its value and its gradient, both viewed as matrices
/// (a bias is an n×1 matrix). Maps point into the owning layer's storage and stay
/// valid while that layer is alive. (The same holds for code that keeps a Map to a
/// plain MatrixXd: never move-assign a temporary into such a matrix, which swaps its
/// storage away from the Map; assign through the Map or use .noalias().)
struct ParameterRef {
    std::string name;              ///< state_dict name, e.g. "decoder.0.weight"
    Eigen::Map<MatrixXd> value;
    Eigen::Map<MatrixXd> grad;
    bool vector = false;           ///< a 1-d tensor (bias, BatchNorm weight): saved with shape (n,)
};

/// A non-trainable state tensor (BatchNorm running statistics).
struct BufferRef {
    std::string name;              ///< e.g. "decoder.1.running_mean"
    Eigen::Map<MatrixXd> value;
    bool integer = false;          ///< stored as an integer dataset (num_batches_tracked)
};

/// What forward and backward return: a view of a buffer the layer owns.
using BatchView = Eigen::Map<const MatrixXd>;

class Layer {
public:
    virtual ~Layer() = default;

    /// PyTorch-like type name used in the architecture description ("Linear", ...).
    virtual std::string type_name() const = 0;
    /// Input / output feature counts; 0 means "any" (element-wise layers).
    virtual Index in_features() const = 0;
    virtual Index out_features() const = 0;

    /// @param X  in × B batch.  @return out × B, valid until the layer's next forward.
    virtual BatchView forward(const Eigen::Ref<const MatrixXd>& X, bool training) = 0;
    /// @param dY  out × B adjoint of the last forward's output.  @return in × B, valid until
    /// the layer's next backward.
    virtual BatchView backward(const Eigen::Ref<const MatrixXd>& dY, bool accumulate_parameter_gradients = true) = 0;
    /// Forward-mode derivative at the last forward input (which must have been in eval mode
    /// for layers whose training behaviour differs, i.e. BatchNorm).
    virtual MatrixXd tangent(const MatrixXd& dX) const = 0;

    /// Append this layer's parameters, names prefixed by `prefix` (e.g. "encoder.0.").
    virtual void collect_parameters(const std::string& /*prefix*/, std::vector<ParameterRef>& /*out*/) { }
    virtual void collect_buffers(const std::string& /*prefix*/, std::vector<BufferRef>& /*out*/) { }

    /// One JSON object describing the layer's hyper-parameters (not its weights).
    virtual void describe(std::ostream& os) const = 0;

    virtual std::unique_ptr<Layer> clone() const = 0;
};

} // namespace lb::nn
