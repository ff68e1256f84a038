#include "planning/problem/worker_threads.hpp"

#include <system_error>
#include <thread>

namespace attitude_planner {

WorkerThreads& WorkerThreads::shared() {
  // Never destroyed: its threads wait for works until the process ends, and a destructor run at
  // exit would have to join them (behind any solve still running on one).
  static WorkerThreads* const threads = new WorkerThreads;
  return *threads;
}

void WorkerThreads::handOver(HandedWork& work) {
  const std::lock_guard<std::mutex> lock(mutex_);
  work.state_ = HandedWork::State::Queued;
  work.queued_at_ = queue_.insert(queue_.end(), &work);
  queued_hint_.store(queue_.size(), std::memory_order_relaxed);
  const int queued = static_cast<int>(queue_.size());
  if (queued <= waiting_) {
    if (queued > polling_) queued_.notify_one();  // a polling thread finds it unwoken
    return;
  }
  try {  // every queued work has a thread of its own to start at once
    std::thread([this] { serve(); }).detach();
  } catch (const std::system_error&) {
    // No thread to be had: the work waits for a thread that ends its work, or for its caller
    // (takeBackOrWait), which runs it itself.
  }
}

bool WorkerThreads::takeBackOrWait(HandedWork& work) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (work.state_ == HandedWork::State::Queued) {
    queue_.erase(work.queued_at_);
    queued_hint_.store(queue_.size(), std::memory_order_relaxed);
    work.state_ = HandedWork::State::Done;
    return false;
  }
  ended_.wait(lock, [&] { return work.state_ == HandedWork::State::Done; });
  return true;
}

void WorkerThreads::waitForWork(std::unique_lock<std::mutex>& lock) {
  ++waiting_;
  ++polling_;
  const auto until = std::chrono::steady_clock::now() + kPollBeforeSleep;
  while (queue_.empty() && std::chrono::steady_clock::now() < until) {
    lock.unlock();
    while (queued_hint_.load(std::memory_order_relaxed) == 0 &&
           std::chrono::steady_clock::now() < until) {
      std::this_thread::yield();  // a loaded machine's other threads run meanwhile
    }
    lock.lock();
  }
  --polling_;  // under the same lock as the test of queue_: a later hand-over wakes this thread
  while (queue_.empty()) queued_.wait(lock);
  --waiting_;
}

void WorkerThreads::serve() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    if (queue_.empty()) waitForWork(lock);
    HandedWork& work = *queue_.front();
    queue_.pop_front();
    queued_hint_.store(queue_.size(), std::memory_order_relaxed);
    work.state_ = HandedWork::State::Running;
    lock.unlock();
    work.run_();
    lock.lock();
    // The caller may destroy `work` as soon as it reads Done: it is not touched after this.
    work.state_ = HandedWork::State::Done;
    ended_.notify_all();
  }
}

}  // namespace attitude_planner
