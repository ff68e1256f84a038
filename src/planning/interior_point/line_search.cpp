// The line search (line_search.hpp).
#include "planning/interior_point/line_search.hpp"

#include <cmath>

namespace attitude_planner {

LineSearchProfile fixedStepLineSearch(const InteriorPointParameters& parameters) {
  LineSearchProfile profile;
  profile.armijo = parameters.armijo;
  profile.max_halvings = parameters.fixed_step.max_halvings;
  profile.floor_halvings = parameters.fixed_step.floor_halvings;
  profile.merit_round_off = parameters.merit_round_off;
  return profile;
}

LineSearchProfile freeTimeLineSearch(const InteriorPointParameters& parameters) {
  LineSearchProfile profile = fixedStepLineSearch(parameters);
  profile.max_halvings = parameters.free_time.max_halvings;
  profile.floor_halvings = parameters.free_time.floor_halvings;
  profile.take_round_off_step = false;
  profile.second_order_correction = true;
  return profile;
}

LineSearchResult ArmijoBacktracking::search(BarrierProblem& problem,
                                            const LineSearchRequest& request,
                                            Eigen::VectorXd* d) const {
  const double phi = problem.merit();
  LineSearchResult result;
  result.alpha = request.alpha0;
  result.at_round_off = -request.slope <= profile_.merit_round_off * std::abs(phi);
  if (request.take_outright || (profile_.take_round_off_step && result.at_round_off)) {
    problem.moveTo(*d, result.alpha);
    result.accepted = true;
    return result;
  }
  if (profile_.second_order_correction && request.late) {
    if (correctedFullStep(problem, phi, request.slope, d)) {
      result.alpha = 1.0;
      result.accepted = true;
      return result;
    }
    result.alpha = 0.5;  // the full step was just tried
  }
  const int halvings = request.at_floor ? profile_.floor_halvings : profile_.max_halvings;
  for (int i = 0; i < halvings; ++i, result.alpha *= 0.5) {
    const double trial = problem.trialMerit(*d, result.alpha, nullptr);
    if (std::isfinite(trial) && trial <= phi + profile_.armijo * result.alpha * request.slope) {
      result.accepted = true;
      return result;
    }
  }
  problem.restore();
  return result;
}

/// The full step, then (the iterate at x + d) its second-order correction, which replaces *d when
/// it is accepted. Where neither is, the correction's terms are cleared.
bool ArmijoBacktracking::correctedFullStep(BarrierProblem& problem, double phi, double slope,
                                           Eigen::VectorXd* d) const {
  const double threshold = phi + profile_.armijo * slope;
  bool moved = false;
  if (problem.trialMerit(*d, 1.0, &moved) <= threshold) return true;
  Eigen::VectorXd corrected;
  if (moved && problem.correctedStep(*d, &corrected) &&
      problem.trialMerit(corrected, 1.0, nullptr) <= threshold) {
    *d = corrected;
    return true;
  }
  problem.clearCorrection();
  return false;
}

}  // namespace attitude_planner
