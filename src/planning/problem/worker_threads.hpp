// Threads kept between requests for the solves that run at once (runBranches, runSlidingWindow).
// A thread started per call costs its start, and its caller's join waits until it has run, which
// on a loaded machine can be a scheduler tick away; a kept thread only wakes. A work handed over
// that no thread has taken yet can be taken back and run by the caller, so a caller never waits
// for a thread to start. Waking a thread asleep is slow on the 2-core machine (measured: the
// waker's notify 30-45 us, the woken thread running 75-110 us later), so a caller waiting for a
// work that runs stays awake a while first (kCallerStaysAwake: it is on the request's critical
// path), and so does a thread that ended a work (kThreadStaysAwake: a request's works come in
// bursts, e.g. the Newton walk's class surveys, then its own class's check beside its replay,
// which then starts at once). Both yield while awake, and sleep after.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <list>
#include <mutex>

namespace attitude_planner {

/// One work handed to the worker threads (WorkerThreads::handOver); it lives with the caller, who
/// must call takeBackOrWait on it before it goes away.
class HandedWork {
 public:
  explicit HandedWork(std::function<void()> run) : run_(std::move(run)) {}
  HandedWork(const HandedWork&) = delete;
  HandedWork& operator=(const HandedWork&) = delete;
  /// Runs it on the calling thread (a work taken back before any thread began it).
  void runHere() { run_(); }

 private:
  friend class WorkerThreads;
  enum class State { Queued, Running, Done };
  std::function<void()> run_;  ///< must not throw
  State state_ = State::Queued;
  std::atomic<bool> finished_{false};  ///< state_ is Done: read without the lock by a caller awake
  std::list<HandedWork*>::iterator queued_at_;  ///< while Queued
};

/// The process's worker threads: a work handed over runs on a waiting thread, or on a new one
/// kept afterwards when none waits, so every work handed over may start at once (as on a thread
/// of its own); the threads are as many as the most works ever running at once.
class WorkerThreads {
 public:
  /// The one set of threads every request shares.
  static WorkerThreads& shared();

  /// Queues `work` for a worker thread (its run must not throw).
  void handOver(HandedWork& work);
  /// Ends the hand-over of `work`: takes it back if no thread has begun it (returns false: it
  /// never ran, the caller may run it itself), else waits until it ended (returns true). What
  /// the work wrote is visible to the caller after either.
  bool takeBackOrWait(HandedWork& work);

 private:
  /// How long a caller waiting for a work that runs stays awake (yielding) before it sleeps.
  static constexpr std::chrono::microseconds kCallerStaysAwake{150};
  /// How long a thread that ended a work stays awake (yielding) for the next before it sleeps.
  static constexpr std::chrono::microseconds kThreadStaysAwake{100};

  WorkerThreads() = default;
  /// A worker thread's life: runs queued works, waits while none is queued.
  void serve();
  /// Stays awake (yielding) until a work is queued or kThreadStaysAwake has passed; `lock` is
  /// held on entry and on return, released in between.
  void stayAwakeForWork(std::unique_lock<std::mutex>& lock);

  std::mutex mutex_;                     ///< guards everything below and every work's state
  std::condition_variable work_queued_;  ///< a work was queued
  std::condition_variable ended_;        ///< a work ended
  std::list<HandedWork*> queue_;         ///< works handed over, not yet begun, oldest first
  int waiting_ = 0;                      ///< threads asleep waiting for a work
  int awake_ = 0;                        ///< threads awake waiting for a work (stayAwakeForWork)
  std::atomic<std::size_t> queued_{0};   ///< queue_.size(), read by the threads awake
};

}  // namespace attitude_planner
