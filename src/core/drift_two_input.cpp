// Extremal flow of Remsing's drift + two-input system (seed 001, eqs. 3.8, 3.15–3.17).
#include "attitude_planner/drift_two_input.hpp"

#include <cmath>
#include <sstream>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {

void validateDriftTwoInputWeights(const DriftTwoInputWeights& w) {
  for (const auto& [name, value] : {std::pair<const char*, double>{"c1", w.c1}, {"c2", w.c2}}) {
    if (!std::isfinite(value) || value <= 0.0) {
      std::ostringstream os;
      os << "cost weight " << name << " must be finite and > 0, got " << value;
      throw InvalidInput(os.str());
    }
  }
}

DriftTwoInputTrajectory integrateDriftTwoInputExtremal(const Matrix3& g0, const Vector3& p0,
                                                       double T, int steps,
                                                       const DriftTwoInputWeights& w,
                                                       const DriftTwoInputIntegration& opts) {
  validateDriftTwoInputWeights(w);
  if (!std::isfinite(T) || T <= 0.0) {
    throw InvalidInput("duration T must be finite and > 0, got " + std::to_string(T));
  }
  if (steps < 1) throw InvalidInput("steps must be >= 1, got " + std::to_string(steps));
  if (opts.substeps < 1) {
    throw InvalidInput("substeps must be >= 1, got " + std::to_string(opts.substeps));
  }
  if (opts.order != 2 && opts.order != 4) {
    throw InvalidInput("order must be 2 or 4, got " + std::to_string(opts.order));
  }
  if (!p0.allFinite()) throw InvalidInput("initial costate p0 must be finite");

  DriftTwoInputTrajectory out;
  out.t.reserve(steps + 1);
  out.p.reserve(steps + 1);
  out.g.reserve(steps + 1);
  out.u.reserve(steps + 1);
  Matrix3 g = g0;
  Vector3 p = p0;
  const double h = T / (static_cast<double>(steps) * opts.substeps);
  auto record = [&](int k) {
    out.t.push_back(T * k / steps);
    out.p.push_back(p);
    out.g.push_back(g);
    out.u.emplace_back(p.x() / w.c1, p.y() / w.c2);
  };
  record(0);
  for (int k = 1; k <= steps; ++k) {
    for (int j = 0; j < opts.substeps; ++j) {
      double dc = 0.0;
      if (!drift_two_input::stepOfOrder<double>(g, p, h, w, opts.order, &dc)) {
        std::ostringstream os;
        os << "implicit midpoint step " << k << " (h = " << h << " s, |p| = " << p.norm()
           << ") did not converge: reduce the step";
        throw StepTooLarge(os.str());
      }
      out.cost += dc;
    }
    record(k);
  }
  return out;
}

}  // namespace attitude_planner
