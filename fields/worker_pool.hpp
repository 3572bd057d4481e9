// A fixed pool of worker threads for the offline field builders.
//
// run(n, fn) calls fn(item, worker) for every item in [0, n) on the pool's
// workers (the calling thread is worker 0) and returns when all calls are done.
// Items are handed out dynamically; results must not depend on which worker ran
// which item (the builders use integer sums or disjoint outputs).
//
// Thread-safety: run() is called from one thread at a time. Not real-time safe
// (threads, locks).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace visvol::fields {

class WorkerPool {
 public:
  // threads == 0: one worker per hardware thread.
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int size() const { return static_cast<int>(helpers_.size()) + 1; }
  void run(int items, const std::function<void(int item, int worker)>& fn);

  static int resolve_threads(int threads);

 private:
  void helper_main(int worker);
  void drain(int worker);

  std::vector<std::thread> helpers_;
  std::mutex mutex_;
  std::condition_variable start_cv_;
  std::condition_variable done_cv_;
  std::uint64_t generation_ = 0;  // guarded by mutex_
  int busy_ = 0;                  // helpers still in the current job; guarded by mutex_
  bool stop_ = false;             // guarded by mutex_
  const std::function<void(int, int)>* job_ = nullptr;
  int items_ = 0;
  std::atomic<int> next_{0};
};

}  // namespace visvol::fields
