#include "attitude_planner/termination.hpp"

namespace attitude_planner {

std::string terminationName(Termination termination) {
  switch (termination) {
    case Termination::Converged:
      return "converged";
    case Termination::NotConverged:
      return "not_converged";
    case Termination::Infeasible:
      return "infeasible";
    case Termination::StepTooLarge:
      return "step_too_large";
    case Termination::TimedOut:
      return "timed_out";
    case Termination::Cancelled:
      return "cancelled";
    case Termination::InvalidInput:
      return "invalid_input";
  }
  return "unknown";
}

}  // namespace attitude_planner
