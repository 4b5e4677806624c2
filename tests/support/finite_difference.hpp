#pragma once
// The one generic derivative test, used for every energy and every network
// layer: central finite differences at a point, compared entrywise with
//   |a − b| ≤ tol · max(|a|, |b|, scale)
// and on failure a message naming the worst entry.
#include <functional>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "core/types.hpp"

namespace lb::testing {

struct FdOptions {
    double step = 1e-6;   ///< central-difference step h
    double tol = 1e-5;    ///< relative tolerance
    double scale = 1.0;   ///< absolute floor in the denominator (the "1" of max(|a|,|b|,1))
};

/// Central-difference Jacobian of f: R^n -> R^m at x (m×n).
inline MatrixXd fd_jacobian(const std::function<VectorXd(const VectorXd&)>& f, const VectorXd& x,
                            double step)
{
    const VectorXd f0 = f(x);
    MatrixXd J(f0.size(), x.size());
    VectorXd xp = x;
    for (Index j = 0; j < x.size(); ++j) {
        xp[j] = x[j] + step;
        const VectorXd fp = f(xp);
        xp[j] = x[j] - step;
        const VectorXd fm = f(xp);
        xp[j] = x[j];
        J.col(j) = (fp - fm) / (2.0 * step);
    }
    return J;
}

/// Compare two matrices entrywise; returns success or a failure naming the worst entry.
inline ::testing::AssertionResult matrices_close(const MatrixXd& analytic, const MatrixXd& numeric,
                                                 const FdOptions& opt, const std::string& what)
{
    if (analytic.rows() != numeric.rows() || analytic.cols() != numeric.cols()) {
        return ::testing::AssertionFailure() << what << ": shape " << analytic.rows() << "x"
                                             << analytic.cols() << " vs " << numeric.rows() << "x"
                                             << numeric.cols();
    }
    double worst = -1.0;
    Index wi = 0, wj = 0;
    for (Index j = 0; j < analytic.cols(); ++j) {
        for (Index i = 0; i < analytic.rows(); ++i) {
            const double a = analytic(i, j), b = numeric(i, j);
            const double denom = std::max({std::abs(a), std::abs(b), opt.scale});
            const double err = std::abs(a - b) / denom;
            if (!(err <= worst) || std::isnan(err)) {
                worst = std::isnan(err) ? std::numeric_limits<double>::infinity() : err;
                wi = i;
                wj = j;
            }
        }
    }
    if (worst <= opt.tol) return ::testing::AssertionSuccess();
    std::ostringstream msg;
    msg << what << ": worst entry (" << wi << "," << wj << ") analytic " << analytic(wi, wj)
        << " vs finite difference " << numeric(wi, wj) << ", relative error " << worst
        << " > tol " << opt.tol;
    return ::testing::AssertionFailure() << msg.str();
}

/// Gradient check of a scalar function.
inline ::testing::AssertionResult check_gradient(const std::function<double(const VectorXd&)>& f,
                                                 const std::function<VectorXd(const VectorXd&)>& grad,
                                                 const VectorXd& x, const FdOptions& opt = {},
                                                 const std::string& what = "gradient")
{
    const MatrixXd numeric = fd_jacobian(
        [&](const VectorXd& y) { return VectorXd::Constant(1, f(y)); }, x, opt.step);
    const MatrixXd analytic = grad(x).transpose();
    return matrices_close(analytic, numeric, opt, what);
}

/// Jacobian check of a vector function (e.g. Hessian = Jacobian of the gradient).
inline ::testing::AssertionResult check_jacobian(const std::function<VectorXd(const VectorXd&)>& f,
                                                 const MatrixXd& analytic, const VectorXd& x,
                                                 const FdOptions& opt = {},
                                                 const std::string& what = "jacobian")
{
    return matrices_close(analytic, fd_jacobian(f, x, opt.step), opt, what);
}

} // namespace lb::testing
