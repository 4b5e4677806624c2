// minimize_newton (dense and sparse Hessians) and minimize_lbfgs on analytic
// objectives: exact minimisers, the projected / regularised Hessian path on an
// indefinite objective, non-finite objectives reported (not thrown), and the
// gradient-tolerance and iteration-cap terminations.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <set>

#include "solver/lbfgs.hpp"
#include "solver/newton.hpp"

namespace lb {
namespace {

/// f(x) = ½ xᵀAx − bᵀx with A symmetric positive definite: minimiser A⁻¹b.
class Quadratic final : public Objective {
public:
    Quadratic(MatrixXd A, VectorXd b, HessianKind kind) : m_A(std::move(A)), m_b(std::move(b)), m_kind(kind)
    {
        m_sparse = m_A.sparseView();
        m_sparse = SparseMatrixd(m_sparse.triangularView<Eigen::Lower>());
        m_sparse.makeCompressed();
    }
    Index dimension() const override { return m_b.size(); }
    double value(const Eigen::Ref<const VectorXd>& x) override { return 0.5 * x.dot(m_A * x) - m_b.dot(x); }
    void gradient(const Eigen::Ref<const VectorXd>& x, Eigen::Ref<VectorXd> g) override { g = m_A * x - m_b; }
    HessianKind hessian_kind() const override { return m_kind; }
    void dense_hessian(const Eigen::Ref<const VectorXd>&, bool, MatrixXd& H) override { H = m_A; }
    SparseMatrixd& sparse_hessian(const Eigen::Ref<const VectorXd>&, bool) override
    {
        // Restore the values (the minimiser may have shifted the diagonal).
        m_sparse = SparseMatrixd(SparseMatrixd(m_A.sparseView()).triangularView<Eigen::Lower>());
        m_sparse.makeCompressed();
        return m_sparse;
    }
    VectorXd minimiser() const { return m_A.ldlt().solve(m_b); }

private:
    MatrixXd m_A;
    VectorXd m_b;
    HessianKind m_kind;
    SparseMatrixd m_sparse;
};

/// A random SPD matrix (well conditioned) and right-hand side.
Quadratic random_quadratic(Index n, HessianKind kind, unsigned seed = 7)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    MatrixXd M = MatrixXd::NullaryExpr(n, n, [&]() { return u(rng); });
    MatrixXd A = M * M.transpose() + double(n) * MatrixXd::Identity(n, n);
    VectorXd b = VectorXd::NullaryExpr(n, [&]() { return u(rng); });
    return Quadratic(A, b, kind);
}

/// 1-D Laplacian plus identity (tridiagonal SPD), sparse Hessian.
Quadratic tridiagonal_quadratic(Index n)
{
    MatrixXd A = MatrixXd::Zero(n, n);
    for (Index i = 0; i < n; ++i) {
        A(i, i) = 3.0;
        if (i + 1 < n) A(i, i + 1) = A(i + 1, i) = -1.0;
    }
    return Quadratic(A, VectorXd::LinSpaced(n, -1.0, 2.0), HessianKind::Sparse);
}

/// Rosenbrock f = (1 − x)² + 100 (y − x²)², minimum 0 at (1, 1); the Hessian is
/// indefinite in part of the valley's surroundings.
class Rosenbrock final : public Objective {
public:
    Index dimension() const override { return 2; }
    double value(const Eigen::Ref<const VectorXd>& p) override
    {
        return std::pow(1.0 - p[0], 2) + 100.0 * std::pow(p[1] - p[0] * p[0], 2);
    }
    void gradient(const Eigen::Ref<const VectorXd>& p, Eigen::Ref<VectorXd> g) override
    {
        g[0] = -2.0 * (1.0 - p[0]) - 400.0 * p[0] * (p[1] - p[0] * p[0]);
        g[1] = 200.0 * (p[1] - p[0] * p[0]);
    }
    HessianKind hessian_kind() const override { return HessianKind::Dense; }
    void dense_hessian(const Eigen::Ref<const VectorXd>& p, bool project_psd, MatrixXd& H) override
    {
        H.resize(2, 2);
        H(0, 0) = 2.0 - 400.0 * (p[1] - 3.0 * p[0] * p[0]);
        H(0, 1) = H(1, 0) = -400.0 * p[0];
        H(1, 1) = 200.0;
        if (project_psd) {
            Eigen::SelfAdjointEigenSolver<MatrixXd> eig(H);
            H = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
        }
    }
};

/// f = Σ_i (x_i² − 1)², separable double wells: minima at x_i = ±1; the Hessian
/// 12 x_i² − 4 is negative definite near 0, where its PSD projection is singular.
class DoubleWell final : public Objective {
public:
    DoubleWell(Index n, HessianKind kind) : m_n(n), m_kind(kind)
    {
        m_H.resize(n, n);
        m_H.setIdentity();  // diagonal pattern, values overwritten
        m_H.makeCompressed();
    }
    Index dimension() const override { return m_n; }
    double value(const Eigen::Ref<const VectorXd>& x) override
    {
        return (x.array().square() - 1.0).square().sum();
    }
    void gradient(const Eigen::Ref<const VectorXd>& x, Eigen::Ref<VectorXd> g) override
    {
        g = (4.0 * x.array() * (x.array().square() - 1.0)).matrix();
    }
    HessianKind hessian_kind() const override { return m_kind; }
    VectorXd diagonal(const Eigen::Ref<const VectorXd>& x, bool project_psd) const
    {
        VectorXd d = (12.0 * x.array().square() - 4.0).matrix();
        return project_psd ? VectorXd(d.cwiseMax(0.0)) : d;
    }
    void dense_hessian(const Eigen::Ref<const VectorXd>& x, bool project_psd, MatrixXd& H) override
    {
        H = diagonal(x, project_psd).asDiagonal();
    }
    SparseMatrixd& sparse_hessian(const Eigen::Ref<const VectorXd>& x, bool project_psd) override
    {
        const VectorXd d = diagonal(x, project_psd);
        for (Index i = 0; i < m_n; ++i) m_H.valuePtr()[i] = d[i];
        return m_H;
    }

private:
    Index m_n;
    HessianKind m_kind;
    SparseMatrixd m_H;
};

/// f = x − log x (1-D), minimum at x = 1; NaN for x < 0 and +inf at 0: a full
/// Newton step from x = 3 lands at −3, so the line search must reject non-finite values.
class LogBarrier final : public Objective {
public:
    Index dimension() const override { return 1; }
    double value(const Eigen::Ref<const VectorXd>& x) override { return x[0] - std::log(x[0]); }
    void gradient(const Eigen::Ref<const VectorXd>& x, Eigen::Ref<VectorXd> g) override { g[0] = 1.0 - 1.0 / x[0]; }
    HessianKind hessian_kind() const override { return HessianKind::Dense; }
    void dense_hessian(const Eigen::Ref<const VectorXd>& x, bool, MatrixXd& H) override
    {
        H = MatrixXd::Constant(1, 1, 1.0 / (x[0] * x[0]));
    }
};

/// NaN everywhere.
class NotANumber final : public Objective {
public:
    Index dimension() const override { return 3; }
    double value(const Eigen::Ref<const VectorXd>&) override { return std::numeric_limits<double>::quiet_NaN(); }
    void gradient(const Eigen::Ref<const VectorXd>&, Eigen::Ref<VectorXd> g) override
    {
        g.setConstant(std::numeric_limits<double>::quiet_NaN());
    }
    HessianKind hessian_kind() const override { return HessianKind::Dense; }
    void dense_hessian(const Eigen::Ref<const VectorXd>&, bool, MatrixXd& H) override
    {
        H = MatrixXd::Identity(3, 3);
    }
};

/// Gradient-only version of any objective (for Newton's no-Hessian path).
class GradientOnly final : public Objective {
public:
    explicit GradientOnly(Objective& f) : m_f(f) { }
    Index dimension() const override { return m_f.dimension(); }
    double value(const Eigen::Ref<const VectorXd>& x) override { return m_f.value(x); }
    void gradient(const Eigen::Ref<const VectorXd>& x, Eigen::Ref<VectorXd> g) override { m_f.gradient(x, g); }

private:
    Objective& m_f;
};

double gradient_norm(Objective& f, const VectorXd& x)
{
    VectorXd g(x.size());
    f.gradient(x, g);
    return g.norm();
}

TEST(MinimizeNewton, DenseQuadraticInOneStep)
{
    Quadratic f = random_quadratic(6, HessianKind::Dense);
    VectorXd x = VectorXd::Zero(6);
    const SolveSummary s = minimize_newton(f, x, NewtonOptions{});
    EXPECT_EQ(s.termination, SolveTermination::Converged) << s.brief();
    EXPECT_EQ(s.iterations, 1) << "Newton is exact on a quadratic";
    EXPECT_EQ(s.projected_iterations, 0);
    EXPECT_LT((x - f.minimiser()).norm(), 1e-12 * f.minimiser().norm());
    EXPECT_NEAR(s.residual, gradient_norm(f, x), 1e-15) << "residual is ||g|| / force_scale with force_scale 1";
}

TEST(MinimizeNewton, SparseQuadraticInOneStepAndWorkspaceReuse)
{
    Quadratic f = tridiagonal_quadratic(50);
    NewtonWorkspace ws;
    for (int pass = 0; pass < 2; ++pass) {  // the second pass reuses the analysis
        VectorXd x = VectorXd::Constant(50, 0.3);
        const SolveSummary s = minimize_newton(f, x, NewtonOptions{}, &ws);
        EXPECT_EQ(s.termination, SolveTermination::Converged) << s.brief();
        EXPECT_EQ(s.iterations, 1);
        EXPECT_LT((x - f.minimiser()).norm(), 1e-12 * f.minimiser().norm());
    }
}

TEST(MinimizeNewton, RosenbrockFromTheClassicStart)
{
    Rosenbrock f;
    VectorXd x(2);
    x << -1.2, 1.0;
    NewtonOptions o;
    o.gradient_tolerance = 1e-10;
    const SolveSummary s = minimize_newton(f, x, o);
    EXPECT_TRUE(s.converged()) << s.brief();
    EXPECT_NEAR(x[0], 1.0, 1e-8);
    EXPECT_NEAR(x[1], 1.0, 1e-8);
    EXPECT_GT(s.line_search_halvings, 0) << "the full Newton step overshoots the curved valley";
}

/// Two unknowns start near the local maximum at 0: the exact Hessian is indefinite
/// (no descent direction) and its projection singular, so only projection plus μI
/// gives a direction. Dense and sparse Hessians must take the same path.
TEST(MinimizeNewton, IndefiniteNeedsProjectionAndRegularisation)
{
    for (HessianKind kind : {HessianKind::Dense, HessianKind::Sparse}) {
        DoubleWell f(3, kind);
        VectorXd x(3);
        x << 0.1, -0.2, 1.5;
        NewtonOptions o;
        // CHOLMOD's simplicial factorisation (chosen for a factor this sparse) is LDLᵀ
        // and accepts this indefinite matrix; it gives a descent direction toward the
        // saddle at 0. Adaptive would take it, so the sparse path is tested projected.
        if (kind == HessianKind::Sparse) o.projection = NewtonOptions::Projection::Always;
        const SolveSummary s = minimize_newton(f, x, o);
        const char* label = kind == HessianKind::Dense ? "dense" : "sparse";
        EXPECT_EQ(s.termination, SolveTermination::Converged) << label << ": " << s.brief();
        EXPECT_GT(s.projected_iterations, 0) << label;
        EXPECT_GT(s.regularizations, 0) << label;
        EXPECT_NEAR(x[0], 1.0, 1e-9) << label;
        EXPECT_NEAR(x[1], -1.0, 1e-9) << label;
        EXPECT_NEAR(x[2], 1.0, 1e-9) << label;
    }
    // Without projection the exact Hessian is regularised until positive definite.
    DoubleWell f(3, HessianKind::Dense);
    VectorXd x(3);
    x << 0.1, -0.2, 1.5;
    NewtonOptions o;
    o.projection = NewtonOptions::Projection::Never;
    const SolveSummary s = minimize_newton(f, x, o);
    EXPECT_EQ(s.termination, SolveTermination::Converged) << s.brief();
    EXPECT_EQ(s.projected_iterations, 0);
    EXPECT_GT(s.regularizations, 0);
    EXPECT_NEAR(x.cwiseAbs().minCoeff(), 1.0, 1e-9);
}

TEST(MinimizeNewton, IndefiniteFailsWithoutRegularisationRoom)
{
    DoubleWell f(2, HessianKind::Sparse);
    VectorXd x = VectorXd::Constant(2, 0.1);
    const VectorXd x0 = x;
    NewtonOptions o;
    o.max_regularizations = 0;
    const SolveSummary s = minimize_newton(f, x, o);
    EXPECT_EQ(s.termination, SolveTermination::FactorizationFailed) << s.brief();
    EXPECT_FALSE(s.converged());
    EXPECT_FALSE(s.message.empty());
    EXPECT_EQ(x, x0) << "no step is taken without a direction";
}

TEST(MinimizeNewton, LineSearchRejectsNonFiniteTrialPoints)
{
    LogBarrier f;
    VectorXd x = VectorXd::Constant(1, 3.0);
    const SolveSummary s = minimize_newton(f, x, NewtonOptions{});
    EXPECT_EQ(s.termination, SolveTermination::Converged) << s.brief();
    EXPECT_GT(s.line_search_halvings, 0);
    EXPECT_NEAR(x[0], 1.0, 1e-8);
}

TEST(MinimizeNewton, NonFiniteObjectiveIsReportedNotThrown)
{
    NotANumber f;
    VectorXd x = VectorXd::Ones(3);
    SolveSummary s;
    EXPECT_NO_THROW(s = minimize_newton(f, x, NewtonOptions{}));
    EXPECT_EQ(s.termination, SolveTermination::NonFinite) << s.brief();
    EXPECT_FALSE(s.converged());
    EXPECT_EQ(s.iterations, 0);
}

TEST(MinimizeNewton, IterationCapIsReported)
{
    Rosenbrock f;
    VectorXd x(2);
    x << -1.2, 1.0;
    NewtonOptions o;
    o.max_iterations = 2;
    const SolveSummary s = minimize_newton(f, x, o);
    EXPECT_EQ(s.termination, SolveTermination::MaxIterations) << s.brief();
    EXPECT_EQ(s.iterations, 2);
    EXPECT_FALSE(s.converged());
    EXPECT_GT(s.residual, o.gradient_tolerance);
}

TEST(MinimizeNewton, ObjectiveWithoutHessianIsAFailureNotAThrow)
{
    Rosenbrock r;
    GradientOnly f(r);
    VectorXd x = VectorXd::Zero(2);
    const SolveSummary s = minimize_newton(f, x, NewtonOptions{});
    EXPECT_EQ(s.termination, SolveTermination::Failed);
    EXPECT_NE(s.message.find("Hessian"), std::string::npos) << s.message;
}

TEST(MinimizeLbfgs, QuadraticToTheGradientTolerance)
{
    Quadratic f = random_quadratic(8, HessianKind::None);
    int loose_evaluations = 0;
    // force_scale 100 keeps both tests above NLopt's own absolute gradient test (1e-8).
    for (double tol : {1e-4, 1e-8}) {
        VectorXd x = VectorXd::Zero(8);
        LbfgsOptions o;
        o.gradient_tolerance = tol;
        o.force_scale = 100.0;
        const SolveSummary s = minimize_lbfgs(f, x, o);
        EXPECT_EQ(s.termination, SolveTermination::Converged) << s.brief();
        // The test is on ||g|| ≤ tol · force_scale at the returned x, and the residual
        // reported is that x's ||g|| / force_scale.
        EXPECT_LE(gradient_norm(f, x), tol * o.force_scale);
        EXPECT_NEAR(s.residual, gradient_norm(f, x) / o.force_scale, 1e-15);
        EXPECT_LT((x - f.minimiser()).norm(), 10.0 * tol * o.force_scale);
        if (tol == 1e-4) {
            loose_evaluations = s.evaluations;
        } else {
            EXPECT_GT(s.evaluations, loose_evaluations) << "a tighter tolerance must take more evaluations";
        }
    }
}

TEST(MinimizeLbfgs, RosenbrockConvergesToOneOne)
{
    Rosenbrock f;
    VectorXd x(2);
    x << -1.2, 1.0;
    LbfgsOptions o;
    o.gradient_tolerance = 1e-7;
    LbfgsWorkspace ws;
    const SolveSummary s = minimize_lbfgs(f, x, o, &ws);
    EXPECT_EQ(s.termination, SolveTermination::Converged) << s.brief();
    EXPECT_NEAR(x[0], 1.0, 1e-5);
    EXPECT_NEAR(x[1], 1.0, 1e-5);
    EXPECT_GT(s.iterations, 5);
    EXPECT_GE(s.evaluations, s.iterations);

    // The workspace's NLopt handle is reused (same dimension) and replaced (another).
    VectorXd y(2);
    y << -1.2, 1.0;
    const SolveSummary again = minimize_lbfgs(f, y, o, &ws);
    EXPECT_EQ(again.evaluations, s.evaluations) << "a reused handle must not carry state over";
    EXPECT_EQ(y, x);
    Quadratic q = random_quadratic(5, HessianKind::None);
    VectorXd z = VectorXd::Zero(5);
    EXPECT_EQ(minimize_lbfgs(q, z, o, &ws).termination, SolveTermination::Converged);
}

TEST(MinimizeLbfgs, DoubleWellFromNearTheMaximum)
{
    DoubleWell f(4, HessianKind::None);
    VectorXd x(4);
    x << 0.1, -0.2, 0.05, 2.0;
    LbfgsOptions o;
    o.gradient_tolerance = 1e-6;
    const SolveSummary s = minimize_lbfgs(f, x, o);
    EXPECT_EQ(s.termination, SolveTermination::Converged) << s.brief();
    EXPECT_NEAR(x.cwiseAbs().minCoeff(), 1.0, 1e-6);
    EXPECT_NEAR(x.cwiseAbs().maxCoeff(), 1.0, 1e-6);
}

TEST(MinimizeLbfgs, NonFiniteObjectiveIsReportedNotThrown)
{
    NotANumber f;
    VectorXd x = VectorXd::Ones(3);
    SolveSummary s;
    EXPECT_NO_THROW(s = minimize_lbfgs(f, x, LbfgsOptions{}));
    EXPECT_EQ(s.termination, SolveTermination::NonFinite) << s.brief();
    EXPECT_EQ(s.evaluations, 1) << "the solve stops at the first non-finite evaluation";
    EXPECT_EQ(x, VectorXd::Ones(3)) << "no finite point was seen: x stays the start";
}

/// Rosenbrock, recording the lowest value any evaluation saw.
class RecordingRosenbrock final : public Objective {
public:
    double lowest = std::numeric_limits<double>::infinity();
    Index dimension() const override { return 2; }
    double value(const Eigen::Ref<const VectorXd>& p) override { return record(m_f.value(p)); }
    void gradient(const Eigen::Ref<const VectorXd>& p, Eigen::Ref<VectorXd> g) override { m_f.gradient(p, g); }

private:
    Rosenbrock m_f;
    double record(double v)
    {
        lowest = std::min(lowest, v);
        return v;
    }
};

TEST(MinimizeLbfgs, EvaluationCapIsReported)
{
    RecordingRosenbrock f;
    VectorXd x(2);
    x << -1.2, 1.0;
    LbfgsOptions o;
    o.max_evaluations = 5;
    const SolveSummary s = minimize_lbfgs(f, x, o);
    EXPECT_EQ(s.termination, SolveTermination::MaxEvaluations) << s.brief();
    EXPECT_EQ(s.evaluations, 5);
    EXPECT_FALSE(s.converged());
    // Whether five evaluations find a point below the start depends on the last bits of
    // the line search (they do at -O3, not under the sanitizers' -O1); what must hold is
    // that the point returned is the lowest one seen.
    Rosenbrock fresh;
    EXPECT_EQ(fresh.value(x), f.lowest) << "x is the lowest point seen";
}

TEST(SolveSummary, EveryTerminationHasItsOwnName)
{
    std::set<std::string> names;
    for (int t = int(SolveTermination::Converged); t <= int(SolveTermination::Failed); ++t) {
        const std::string name = to_string(SolveTermination(t));
        EXPECT_NE(name, "unknown");
        names.insert(name);
    }
    EXPECT_EQ(names.size(), size_t(SolveTermination::Failed) + 1);
    SolveSummary s;
    s.termination = SolveTermination::LineSearchFailed;
    s.message = "why";
    EXPECT_NE(s.brief().find("line search failed"), std::string::npos) << s.brief();
    EXPECT_NE(s.brief().find("(why)"), std::string::npos) << s.brief();
    EXPECT_FALSE(s.converged());
    s.termination = SolveTermination::SmallStep;
    EXPECT_TRUE(s.converged());
}

} // namespace
} // namespace lb
