#include "planning/problem/solve_context.hpp"

#include <algorithm>
#include <atomic>
#include <deque>
#include <exception>
#include <limits>
#include <locale>
#include <thread>

#include "planning/problem/worker_threads.hpp"

namespace attitude_planner {

SolveContext::SolveContext(const SolverOptions& request)
    : request_(request),
      call_(&request_),
      start_(Clock::now()),
      shared_(std::make_shared<Shared>()) {
  cone_clearings_.pause();
}

SolveContext::SolveContext(SolveContext& parent, Branch)
    : request_(parent.request_),
      call_(parent.call_),
      start_(parent.start_),
      shared_(parent.shared_),
      work_before_(parent.work()),
      attempt_(parent.attempt_),
      scope_names_nested_(parent.scope_names_nested_) {
  cone_clearings_.pause();
}

void SolveContext::join(SolveContext& branch) {
  // The branch's clearings join the request's tally; while it counts, the branch's whole count
  // below is in it already.
  if (!cone_clearings_.counting()) cone_clearings_.addCountedApart(branch.coneClearingIterations());
  iterations_ += branch.iterations_;
  work_ += branch.work_;
  for (Attempt& a : branch.attempts_) {
    if (a.kept) {
      for (Attempt& b : attempts_) b.kept = false;
    }
    attempts_.push_back(std::move(a));
  }
  levels_.insert(levels_.end(), branch.levels_.begin(), branch.levels_.end());
  branch.attempts_.clear();
  branch.levels_.clear();
  branch.iterations_ = 0;
  branch.cone_clearings_ = IterationTally(branch);
  branch.cone_clearings_.pause();
}

namespace {

/// The machine's cores, asked once per process: std::thread::hardware_concurrency reads the
/// system's CPU list on every call (measured: 7.5 us a call, several a request, some on the seed
/// request's critical path), and the cores a process sees do not change while it serves.
int machineCores() {
  static const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  return cores;
}

}  // namespace

int SolveContext::threads() const {
  if (request_.threads > 0) return request_.threads;
  return machineCores();
}

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
  if (shared_->refused_by_callback) return Termination::Cancelled;
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
  work_ += std::max(info.steps, 1);
  const std::lock_guard<std::mutex> one_at_a_time(shared_->report);
  // A caller that refused hears nothing more: branches on other threads may still report until
  // they next poll.
  if (shared_->refused_by_callback) return false;
  const int number = ++shared_->reported;
  if (!request_.on_iteration) return true;
  IterationInfo numbered = info;
  numbered.iteration = number;
  numbered.attempt = attempt_;
  if (!request_.on_iteration(numbered)) shared_->refused_by_callback = true;
  return !shared_->refused_by_callback;
}

SolveContext::Scope::Scope(SolveContext& context, AttemptStage stage, const HomotopyClass& homotopy,
                           Nested nested)
    : context_(context),
      previous_(context.attempt_),
      previous_names_nested_(context.scope_names_nested_),
      tally_(context) {
  const bool inside = previous_.number > 0;
  const bool renamed = inside && (previous_names_nested_ || stage == AttemptStage::Solve);
  int number = 0;
  {
    const std::lock_guard<std::mutex> one_at_a_time(context_.shared_->report);
    number = ++context_.shared_->attempts_begun;
  }
  context_.attempt_ = {number, renamed ? previous_.stage : stage, homotopy};
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

void SolveContext::planChecked(std::size_t index, Termination termination) {
  attempts_[index].plan_checked = true;
  attempts_[index].termination = termination;
}

std::optional<std::size_t> SolveContext::keptAttempt() const {
  for (std::size_t i = 0; i < attempts_.size(); ++i) {
    if (attempts_[i].kept) return i;
  }
  return std::nullopt;
}

std::optional<std::size_t> SolveContext::keptSince(std::size_t first) const {
  const std::optional<std::size_t> kept = keptAttempt();
  if (kept && *kept >= first) return kept;
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

namespace {

/// libstdc++ fills the locale's ctype widen table on its first use (number formatting in a
/// message); a first use from two threads at once is a data race (benign, but Helgrind and TSan
/// report it), so it is filled before any branch's thread starts.
void fillLocaleTablesBeforeThreads() {
  std::use_facet<std::ctype<char>>(std::locale()).widen('0');
}

}  // namespace

void runBranches(SolveContext& context, int count,
                 const std::function<void(int, SolveContext&)>& work) {
  const int at_once = std::max(1, std::min(context.threads(), count));
  fillLocaleTablesBeforeThreads();
  std::vector<std::unique_ptr<SolveContext>> branches;
  for (int i = 0; i < count; ++i) {
    branches.push_back(std::make_unique<SolveContext>(context, SolveContext::Branch{}));
  }
  std::vector<std::exception_ptr> failures(count);
  std::atomic<int> next{0};
  const auto take = [&] {  // each thread takes the next work as soon as its last one ended
    for (int i = next++; i < count; i = next++) {
      try {
        work(i, *branches[i]);
      } catch (...) {
        failures[i] = std::current_exception();
      }
    }
  };
  // The calling thread takes works too; a helper no thread has begun when the caller finds no
  // work left is taken back (it would find none either), so the caller never waits for a start.
  std::vector<std::unique_ptr<HandedWork>> helpers;
  for (int t = 1; t < at_once; ++t) {
    helpers.push_back(std::make_unique<HandedWork>(take));
    WorkerThreads::shared().handOver(*helpers.back());
  }
  take();
  for (const auto& helper : helpers) WorkerThreads::shared().takeBackOrWait(*helper);
  for (int i = 0; i < count; ++i) {
    context.join(*branches[i]);
    if (failures[i]) std::rethrow_exception(failures[i]);
  }
}

namespace {

/// One work of runSlidingWindow between its begin and its end.
struct OpenWork {
  int index = 0;
  std::unique_ptr<SolveContext> branch;  ///< none: begin(index) returned no work
  std::unique_ptr<HandedWork> run;       ///< none: run on the calling thread at its begin
  std::exception_ptr failure;
};

}  // namespace

void runSlidingWindow(SolveContext& context, int count, const std::function<BranchWork(int)>& begin,
                      const std::function<void(int)>& end) {
  const int at_once = std::max(1, context.threads());
  if (at_once > 1) fillLocaleTablesBeforeThreads();
  std::deque<OpenWork> open;  // in the order of index; references stay valid as it grows
  int running = 0;
  std::exception_ptr failure;
  // A work no worker thread has begun by its end is taken back and run on the calling thread.
  const auto finish = [](OpenWork& w) {
    if (w.run && !WorkerThreads::shared().takeBackOrWait(*w.run)) w.run->runHere();
    w.run.reset();
  };
  const auto endFirst = [&] {
    OpenWork& w = open.front();
    finish(w);
    if (w.branch) {
      context.join(*w.branch);
      --running;
    }
    if (!failure && w.failure) failure = w.failure;
    if (!failure) end(w.index);
    open.pop_front();
  };
  try {
    for (int i = 0; i < count && !failure; ++i) {
      while (running >= at_once) endFirst();
      if (failure) break;
      BranchWork work = begin(i);
      OpenWork& w = open.emplace_back();
      w.index = i;
      if (!work) continue;
      w.branch = std::make_unique<SolveContext>(context, SolveContext::Branch{});
      ++running;
      const auto run = [&w, work = std::move(work)] {
        try {
          work(*w.branch);
        } catch (...) {
          w.failure = std::current_exception();
        }
      };
      if (at_once == 1) {
        run();
      } else {
        w.run = std::make_unique<HandedWork>(run);
        WorkerThreads::shared().handOver(*w.run);
      }
    }
    while (!open.empty()) endFirst();
  } catch (...) {  // from begin or end, on this thread: the works handed over end first
    for (OpenWork& w : open) {
      if (w.run) WorkerThreads::shared().takeBackOrWait(*w.run);
    }
    throw;
  }
  if (failure) std::rethrow_exception(failure);
}

}  // namespace attitude_planner
