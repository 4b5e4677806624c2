#include "solver/solve_summary.hpp"

#include <cstdio>

namespace lb {

std::string to_string(SolveTermination t)
{
    switch (t) {
    case SolveTermination::Converged: return "converged";
    case SolveTermination::SmallStep: return "small step";
    case SolveTermination::SmallDecrease: return "small decrease";
    case SolveTermination::MaxIterations: return "iteration cap reached";
    case SolveTermination::MaxEvaluations: return "evaluation cap reached";
    case SolveTermination::LineSearchFailed: return "line search failed";
    case SolveTermination::FactorizationFailed: return "factorisation failed";
    case SolveTermination::NonFinite: return "non-finite energy or gradient";
    case SolveTermination::RoundoffLimited: return "round-off limited";
    case SolveTermination::Stalled: return "stalled";
    case SolveTermination::Failed: return "failed";
    }
    return "unknown";
}

std::string SolveSummary::brief() const
{
    char buf[256];
    std::snprintf(buf, sizeof buf, "%s in %d it, residual %.3g, %d halvings, %d regularisations, %.2f ms",
                  to_string(termination).c_str(), iterations, residual, line_search_halvings, regularizations,
                  seconds * 1e3);
    return message.empty() ? buf : std::string(buf) + " (" + message + ")";
}

} // namespace lb
