#include "fields/worker_pool.hpp"

#include <algorithm>

namespace visvol::fields {

int WorkerPool::resolve_threads(int threads) {
  if (threads > 0) return threads;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

WorkerPool::WorkerPool(int threads) {
  const int n = resolve_threads(threads);
  helpers_.reserve(static_cast<std::size_t>(n - 1));
  for (int w = 1; w < n; ++w) helpers_.emplace_back([this, w] { helper_main(w); });
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  start_cv_.notify_all();
  for (std::thread& t : helpers_) t.join();
}

void WorkerPool::drain(int worker) {
  for (;;) {
    const int item = next_.fetch_add(1, std::memory_order_relaxed);
    if (item >= items_) return;
    (*job_)(item, worker);
  }
}

void WorkerPool::helper_main(int worker) {
  std::uint64_t seen = 0;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      start_cv_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
    }
    drain(worker);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      --busy_;
    }
    done_cv_.notify_one();
  }
}

void WorkerPool::run(int items, const std::function<void(int item, int worker)>& fn) {
  if (items <= 0) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = &fn;
    items_ = items;
    next_.store(0, std::memory_order_relaxed);
    busy_ = static_cast<int>(helpers_.size());
    ++generation_;
  }
  start_cv_.notify_all();
  drain(0);
  std::unique_lock<std::mutex> lock(mutex_);
  done_cv_.wait(lock, [&] { return busy_ == 0; });
  job_ = nullptr;
}

}  // namespace visvol::fields
