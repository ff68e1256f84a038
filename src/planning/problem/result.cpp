#include "attitude_planner/planning/result.hpp"

#include <cmath>
#include <sstream>

namespace attitude_planner {

std::string minimizedEffortName(MinimizedEffort effort) {
  return nameIn(kMinimizedEffortNames, effort);
}

std::string pointingInfeasibleBasisName(PointingInfeasibleBasis basis) {
  return nameIn(kPointingInfeasibleBasisNames, basis);
}

std::string attemptStageName(AttemptStage stage) {
  return nameIn(kAttemptStageNames, stage);
}

std::string attemptStartName(AttemptStart start) {
  return nameIn(kAttemptStartNames, start);
}

std::string formulationName(Formulation formulation) {
  return nameIn(kFormulationNames, formulation);
}

std::string globalizationName(Globalization globalization) {
  return nameIn(kGlobalizationNames, globalization);
}

AttemptStart originOf(const Attempt& attempt) {
  return attempt.start_detail.coarse_steps > 0 ? attempt.start_detail.origin : attempt.start;
}

namespace {

/// "the nearest lift", "the other way round + 1 extra turn(s)", ...
std::string describeClass(const HomotopyClass& homotopy) {
  std::string d = homotopy.long_way ? "the other way round" : "the nearest lift";
  if (homotopy.extra_revolutions > 0) {
    d += " + " + std::to_string(homotopy.extra_revolutions) + " extra turn(s)";
  }
  return d;
}

/// What distinguishes an attempt among the starts an extremal was chosen from.
std::string describeCandidate(const Attempt& a) {
  if (a.stage == AttemptStage::Solve) return "the first start";
  if (a.stage == AttemptStage::ClassSurvey) {
    return describeClass(a.homotopy) + " surveyed at N = " + std::to_string(a.steps);
  }
  if (a.stage == AttemptStage::ClassRefine) return describeClass(a.homotopy);
  if (a.stage == AttemptStage::ConstrainedClass) {
    return describeClass(a.homotopy) + " under the constraints";
  }
  if (a.homotopy.long_way || a.homotopy.extra_revolutions > 0) {
    return describeClass(a.homotopy) + ", " + attemptStageName(a.stage) + " from " +
           attemptStartName(a.start);
  }
  if (a.globalization == Globalization::LineSearch) {
    return "a line search instead of the trust region";
  }
  switch (a.start) {
    case AttemptStart::InertiaHomotopy:
      return "the inertia homotopy from the sphere";
    case AttemptStart::Coasting:
      return "the coasting start";
    case AttemptStart::Hermite:
      return "the requested grid directly";
    default:
      return attemptStageName(a.stage) + " from " + attemptStartName(a.start);
  }
}

}  // namespace

std::string describeExtremal(const ExtremalSummary& e) {
  if (!e.known) return "";
  std::ostringstream d;
  d << (e.homotopy.long_way ? "second-nearest lift (the other way round)" : "nearest lift");
  if (e.homotopy.extra_revolutions > 0) {
    d << " + " << e.homotopy.extra_revolutions << " extra turn(s)";
  }
  d << ": " << e.angle << " rad about [" << e.axis.x() << ", " << e.axis.y() << ", " << e.axis.z()
    << "] from R_1 to R_{N-1}";
  for (std::size_t i = 0; i < e.others.size(); ++i) {
    const Attempt& a = e.others[i];
    d << (i == 0 ? "; also solved: " : ", ") << describeCandidate(a) << " (";
    if (a.termination == Termination::Converged) {
      d.precision(10);
      d << "cost " << a.cost;
      d.precision(6);
    } else {
      d << terminationName(a.termination);
    }
    d << ")";
  }
  return d.str();
}

}  // namespace attitude_planner
