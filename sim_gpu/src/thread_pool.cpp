#include "hapfluid/sim/thread_pool.hpp"

#include <stdexcept>

namespace hapfluid::sim {

ThreadPool::ThreadPool(int threads) : threads_(threads) {
  if (threads < 1) throw std::invalid_argument("thread count must be >= 1");
  for (int w = 1; w < threads; ++w) helpers_.emplace_back([this, w] { worker_loop(w); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  start_cv_.notify_all();
  for (auto& t : helpers_) t.join();
}

void ThreadPool::run(std::size_t count, const Job& fn) {
  if (threads_ == 1) {
    fn(0, count, 0);
    return;
  }
  {
    std::lock_guard lock(mutex_);
    job_ = &fn;
    count_ = count;
    pending_ = threads_ - 1;
    ++generation_;
  }
  start_cv_.notify_all();
  std::size_t begin, end;
  chunk(count, threads_, 0, begin, end);
  fn(begin, end, 0);
  std::unique_lock lock(mutex_);
  done_cv_.wait(lock, [this] { return pending_ == 0; });
  job_ = nullptr;
}

void ThreadPool::worker_loop(int w) {
  unsigned long seen = 0;
  for (;;) {
    const Job* job;
    std::size_t count;
    {
      std::unique_lock lock(mutex_);
      start_cv_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
      job = job_;
      count = count_;
    }
    std::size_t begin, end;
    chunk(count, threads_, w, begin, end);
    (*job)(begin, end, w);
    {
      std::lock_guard lock(mutex_);
      if (--pending_ == 0) done_cv_.notify_one();
    }
  }
}

}  // namespace hapfluid::sim
