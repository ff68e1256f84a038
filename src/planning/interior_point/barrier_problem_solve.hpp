// One barrier problem over a stage transcription, solved by the primal–dual loop: what the
// interior point at a fixed h (grid_solve.cpp) and free time (free_time_solver.cpp) share. The
// constraint block (BarrierRowBlock<TimeStep>), the Newton system its assembly fills through a
// KktSink (KktBlocks, factored by the KktSystem of the time step's global unknowns), the barrier μ
// with the μ rule's scales, the elastic penalty ρ, the step d, the count of passes and how the
// solve ended. A profile derives from it for what differs: the objective (C, or T/T₀ + ε C), the
// assembly's choices (AssemblyChoices: one assembly, BarrierRowBlock::assemble), the trial point
// (the node unknowns, or h and then the nodes), the merit's penalty (ν, ρ), the start and the
// outcome.
#pragma once

#include <memory>
#include <string>
#include <utility>

#include <Eigen/Core>

#include "attitude_planner/planning/interior_point_parameters.hpp"
#include "planning/interior_point/barrier_forms.hpp"
#include "planning/interior_point/barrier_problem.hpp"
#include "planning/interior_point/kkt_system.hpp"
#include "planning/interior_point/primal_dual_loop.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

/// The words a solve's message ends with where the loop stops it (user-facing: each profile
/// keeps its own).
struct SolveWords {
  const char* iteration_limit;
  const char* out_of_time;  ///< TimedOut (Cancelled says "cancelled")
};

template <typename TimeStep, typename Scalar>
class BarrierProblemSolve : public PrimalDualProblem {
 public:
  /// `factor_polls`: polled inside the band's factorization (null: never).
  BarrierProblemSolve(ReducedProblem& np, const InteriorPointParameters& parameters,
                      BarrierRowBlock<TimeStep>& block, const Interruption* factor_polls,
                      SolveWords words)
      : np_(np),
        p_(parameters),
        block_(block),
        kkt_blocks_(np.unknowns()),
        kkt_(makeKkt<Scalar>(TimeStep::globals(np))),
        factorization_(*kkt_, kkt_blocks_, factor_polls),
        words_(words),
        reason_(words.iteration_limit) {}

  /// The passes counted, the barrier problem's place on its path; the profile adds its own.
  BarrierState state() const override {
    BarrierState s;
    s.iteration = iteration_;
    s.at_final_barrier = mu_ <= scales_.mu_final;
    describe(&s);
    return s;
  }
  BarrierAccess barrier() override {
    return {&mu_, scales_, barrierRows(), rho_, previousDecrement()};
  }
  NewtonSystem newtonSystem() override { return {&factorization_, &rhs_, &d_}; }
  void iterationLimit() override { end(Termination::NotConverged, words_.iteration_limit); }
  /// Interrupted inside a pass, the profile may restore what the interruption left half done.
  void stopped(Termination t, bool inside_pass) override {
    if (inside_pass) interruptedInsidePass();
    end(t, t == Termination::Cancelled ? "cancelled" : words_.out_of_time);
  }

 protected:
  /// The loop over this problem until it stops; the termination and why in termination_, reason_.
  void solve(LoopStrategies strategies, const LoopProfile& profile, SolveContext& context,
             int max_iterations) {
    PrimalDualLoop(*this, std::move(strategies), profile, context).run(max_iterations, &iteration_);
  }
  Pass end(Termination t, std::string why) {
    termination_ = t;
    reason_ = std::move(why);
    return Pass::Stop;
  }
  /// The rows' dual steps for d_ at this barrier problem (the largest step in (0, 1]).
  double dualStep() { return block_.dualStep(d_, mu_, rho_); }

  /// The profile's part of the state the stopping test and the μ rule read.
  virtual void describe(BarrierState*) const {}
  /// The rows a μ rule reads (Mehrotra's predictor; null: none).
  virtual BarrierRows* barrierRows() { return nullptr; }
  /// The last step's relative Newton decrement, for the μ rule (fixed h's decrement test).
  virtual double previousDecrement() const { return 0.0; }
  virtual void interruptedInsidePass() {}

  ReducedProblem& np_;
  const InteriorPointParameters& p_;
  BarrierRowBlock<TimeStep>& block_;
  /// The Newton system at the iterate: the band, bordered by the global unknowns in force.
  KktBlocks<Scalar> kkt_blocks_;
  std::unique_ptr<KktSystem<Scalar>> kkt_;  ///< the last step's factor (reused by solves after it)
  KktFactorization<Scalar> factorization_;  ///< kkt_ over kkt_blocks_, as the loop factors it
  Eigen::VectorXd rhs_, d_;                 ///< the system's right-hand side, the step
  BarrierScales scales_;
  double mu_ = 0.0;    ///< the barrier of this pass
  double rho_ = 0.0;   ///< the elastic penalty
  int iteration_ = 0;  ///< counted passes (the loop advances them)
  const SolveWords words_;
  Termination termination_ = Termination::NotConverged;
  std::string reason_;
};

}  // namespace attitude_planner
