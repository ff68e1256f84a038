#include "planning/problem/solve_context.hpp"

#include <algorithm>
#include <limits>

namespace attitude_planner {

SolveContext::SolveContext(const SolverOptions& request)
    : request_(request), call_(&request_), start_(Clock::now()) {}

double SolveContext::elapsedSeconds() const {
  return std::chrono::duration<double>(Clock::now() - start_).count();
}

double SolveContext::remainingSeconds() const {
  if (request_.time_budget_s <= 0) return std::numeric_limits<double>::infinity();
  return std::max(request_.time_budget_s - elapsedSeconds(), 0.0);
}

SolverOptions SolveContext::remainingOptions() const {
  SolverOptions remaining = *call_;
  remaining.on_iteration = request_.on_iteration;
  remaining.cancel_requested = request_.cancel_requested;
  remaining.time_budget_s =
      request_.time_budget_s > 0 ? std::max(remainingSeconds(), kSpentBudget) : 0.0;
  return remaining;
}

std::optional<Termination> SolveContext::stopReason() const {
  if (refused_by_callback_) return Termination::Cancelled;
  if (request_.cancel_requested && request_.cancel_requested->load(std::memory_order_relaxed)) {
    return Termination::Cancelled;
  }
  if (request_.time_budget_s > 0 && elapsedSeconds() >= request_.time_budget_s) {
    return Termination::TimedOut;
  }
  return std::nullopt;
}

void SolveContext::poll() const {
  if (const auto reason = stopReason()) throw SolveInterrupted{*reason};
}

bool SolveContext::reportIteration(const IterationInfo& info) {
  ++iterations_;
  if (!request_.on_iteration) return true;
  IterationInfo numbered = info;
  numbered.iteration = iterations_;
  numbered.attempt = attempt_;
  if (!request_.on_iteration(numbered)) refused_by_callback_ = true;
  return !refused_by_callback_;
}

SolveContext::Scope::Scope(SolveContext& context, AttemptStage stage, const HomotopyClass& homotopy,
                           Nested nested)
    : context_(context),
      previous_(context.attempt_),
      previous_names_nested_(context.scope_names_nested_),
      tally_(context) {
  const bool inside = previous_.number > 0;
  const bool renamed = inside && (previous_names_nested_ || stage == AttemptStage::Solve);
  context_.attempt_ = {++context_.attempts_begun_, renamed ? previous_.stage : stage, homotopy};
  context_.scope_names_nested_ = previous_names_nested_ || nested == Nested::ScopeStage;
}

void SolveContext::record(Attempt attempt) {
  // The rule of Scope's constructor, for an attempt that ends (rather than begins) inside it.
  const bool inside = attempt_.number > 0;
  if (inside && (scope_names_nested_ || attempt.stage == AttemptStage::Solve)) {
    attempt.stage = attempt_.stage;
  }
  if (attempt.kept) {
    for (Attempt& a : attempts_) a.kept = false;
  }
  attempts_.push_back(attempt);
}

void SolveContext::markKept(std::size_t index) {
  for (std::size_t i = 0; i < attempts_.size(); ++i) attempts_[i].kept = i == index;
}

std::optional<std::size_t> SolveContext::keptAttempt() const {
  for (std::size_t i = 0; i < attempts_.size(); ++i) {
    if (attempts_[i].kept) return i;
  }
  return std::nullopt;
}

void SolveContext::restoreKept(std::optional<std::size_t> index) {
  markKept(index.value_or(attempts_.size()));
}

void SolveContext::recordLevels(const std::vector<LevelSummary>& levels) {
  levels_.insert(levels_.end(), levels.begin(), levels.end());
}

void SolveContext::endLastLevelAs(Termination termination) {
  if (!levels_.empty()) levels_.back().termination = termination;
}

std::vector<LevelSummary> SolveContext::levelsFrom(std::size_t first) const {
  if (first >= levels_.size()) return {};
  return {levels_.begin() + static_cast<std::ptrdiff_t>(first), levels_.end()};
}

void SolveContext::posedAtTwist(std::size_t first, double twist) {
  for (std::size_t i = first; i < attempts_.size(); ++i) attempts_[i].start_detail.twist = twist;
}

std::vector<Attempt> SolveContext::attemptsFrom(std::size_t first) const {
  if (first >= attempts_.size()) return {};
  return {attempts_.begin() + static_cast<std::ptrdiff_t>(first), attempts_.end()};
}

}  // namespace attitude_planner
