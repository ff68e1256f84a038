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
  // At the floor a trial of a round-off step would be accepted or not by the merit's round-off
  // alone: none is taken (the stopping test then ends the solve where it is).
  if (request.at_floor && result.at_round_off) return result;
  const bool correct = profile_.second_order_correction && request.late;
  // The corrected full step is one trial more than the halvings.
  const int trials = (request.at_floor ? profile_.floor_halvings : profile_.max_halvings) + correct;
  for (int i = 0; i < trials; ++i, result.alpha *= 0.5) {
    if (correct) {
      result.accepted = correctedTrial(problem, phi, request.slope, &result.alpha, d);
      if (result.accepted) return result;
      continue;
    }
    const double trial = problem.trialMerit(*d, result.alpha, nullptr);
    if (std::isfinite(trial) && trial <= phi + profile_.armijo * result.alpha * request.slope) {
      result.accepted = true;
      return result;
    }
  }
  problem.restore();
  return result;
}

/// The trial x + α d, then (the iterate there) its second-order correction α d + v, which
/// replaces *d, taken whole (*alpha = 1), when it is accepted: both are held to the Armijo
/// condition at α. Where neither is, the correction's terms are cleared.
bool ArmijoBacktracking::correctedTrial(BarrierProblem& problem, double phi, double slope,
                                        double* alpha, Eigen::VectorXd* d) const {
  const double threshold = phi + profile_.armijo * *alpha * slope;
  bool moved = false;
  if (problem.trialMerit(*d, *alpha, &moved) <= threshold) return true;
  Eigen::VectorXd corrected;
  if (moved && problem.correctedStep(*alpha * *d, &corrected) &&
      problem.trialMerit(corrected, 1.0, nullptr) <= threshold) {
    *d = corrected;
    *alpha = 1.0;
    return true;
  }
  problem.clearCorrection();
  return false;
}

}  // namespace attitude_planner
