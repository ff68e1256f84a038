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
  std::unique_lock<std::mutex> lock(mutex_);
  work.state_ = HandedWork::State::Queued;
  work.finished_ = false;
  work.queued_at_ = queue_.insert(queue_.end(), &work);
  queued_ = queue_.size();
  const int queued = static_cast<int>(queue_.size());
  if (queued <= awake_ + waiting_) {
    // A thread awake takes it; else one asleep is woken, after the lock is released (a thread
    // woken under it would find it held and wait again: measured 35 us a hand-over).
    const bool wake = queued > awake_;
    lock.unlock();
    if (wake) work_queued_.notify_one();
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
    queued_ = queue_.size();
    work.state_ = HandedWork::State::Done;
    return false;
  }
  if (work.state_ != HandedWork::State::Done) {
    lock.unlock();
    const auto until = std::chrono::steady_clock::now() + kCallerStaysAwake;
    while (!work.finished_ && std::chrono::steady_clock::now() < until) std::this_thread::yield();
    lock.lock();
  }
  ended_.wait(lock, [&] { return work.state_ == HandedWork::State::Done; });
  return true;
}

void WorkerThreads::stayAwakeForWork(std::unique_lock<std::mutex>& lock) {
  ++awake_;
  lock.unlock();
  const auto until = std::chrono::steady_clock::now() + kThreadStaysAwake;
  while (queued_ == 0 && std::chrono::steady_clock::now() < until) std::this_thread::yield();
  lock.lock();
  --awake_;
}

void WorkerThreads::serve() {
  std::unique_lock<std::mutex> lock(mutex_);
  bool ended_one = false;  // this thread ended a work: the request may hand over another soon
  for (;;) {
    if (queue_.empty() && ended_one) stayAwakeForWork(lock);
    while (queue_.empty()) {
      ++waiting_;
      work_queued_.wait(lock);
      --waiting_;
    }
    HandedWork& work = *queue_.front();
    queue_.pop_front();
    queued_ = queue_.size();
    work.state_ = HandedWork::State::Running;
    lock.unlock();
    work.run_();
    lock.lock();
    // The caller may destroy `work` as soon as it reads Done: it is not touched after this.
    work.state_ = HandedWork::State::Done;
    work.finished_ = true;
    ended_one = true;
    // The waiting caller is woken with the lock released, as in handOver.
    lock.unlock();
    ended_.notify_all();
    lock.lock();
  }
}

}  // namespace attitude_planner
