// Solver module: summaries of solve reports.
#include "texgrad/solver/solve_report.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace texgrad {

double SolveReport::convergenceFactor(int window) const {
  const int n = static_cast<int>(residuals.size()) - 1;
  const int w = std::min(window, n);
  if (w <= 0) return 0.0;
  const double first = residuals[static_cast<size_t>(n - w)], last = residuals[static_cast<size_t>(n)];
  if (!(first > 0.0)) return 0.0;
  return std::pow(last / first, 1.0 / w);
}

std::string SolveReport::toString() const {
  std::ostringstream os;
  os << "iterations " << iterations
     << (converged  ? " (converged)"
         : diverged ? " (diverged)"
                    : " (not converged)")
     << "\n";
  os << std::scientific << std::setprecision(3);
  for (size_t i = 0; i < residuals.size(); ++i) {
    os << "  " << std::setw(3) << i << "  residual " << residuals[i];
    if (i > 0 && i - 1 < rmsChange.size()) os << "  rms change " << rmsChange[i - 1];
    os << "\n";
  }
  os << std::fixed << std::setprecision(4) << "  seconds: relaxation " << times.relaxation
     << ", boundary " << times.boundary << ", coarse " << times.coarse << ", transfer "
     << times.transfer << ", matvec " << times.matvec << ", preconditioner "
     << times.preconditioner << ", other " << times.other << "\n";
  return os.str();
}

double solveFraction(const SolveReport& report, int maxIterations, double tolerance) {
  if (report.converged || report.iterations >= maxIterations) return 1.0;
  double fraction = maxIterations > 0 ? double(report.iterations) / maxIterations : 0.0;
  if (tolerance > 0.0 && !report.residuals.empty()) {
    const double first = report.residuals.front();
    // The best residual so far, so a residual that rises for a cycle never moves the bar back.
    double best = first;
    for (const double r : report.residuals)
      if (r < best) best = r;  // NaN compares false and is skipped
    if (first > tolerance && best > 0.0 && std::isfinite(first))
      fraction = std::max(fraction, std::log(first / best) / std::log(first / tolerance));
  }
  return std::clamp(fraction, 0.0, 1.0);
}

void reportSolveProgress(const ProgressCallback& progress, const SolveReport& report,
                         int maxIterations, double tolerance, bool finished) {
  if (!progress) return;
  const double fraction = finished ? 1.0 : solveFraction(report, maxIterations, tolerance);
  reportProgress(progress, Progress{"solve", fraction, report.iterations, maxIterations});
}

}  // namespace texgrad
