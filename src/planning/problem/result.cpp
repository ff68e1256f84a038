#include "attitude_planner/planning/result.hpp"

namespace attitude_planner {

std::string attemptStageName(AttemptStage stage) {
  return nameIn(kAttemptStageNames, stage);
}

std::string attemptStartName(AttemptStart start) {
  return nameIn(kAttemptStartNames, start);
}

std::string formulationName(Formulation formulation) {
  return nameIn(kFormulationNames, formulation);
}

}  // namespace attitude_planner
