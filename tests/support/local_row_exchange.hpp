// The shares of a build split by observers as threads of one process (tests
// and the sanitizer trees, which have no Open MPI): rows travel through a
// mailbox, in the order they were sent between two shares, as MPI's messages
// do. A receive that waits a minute fails instead of hanging the test.
#pragma once

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <tuple>
#include <vector>

#include "base/status.hpp"
#include "fields/visibility_builder.hpp"

namespace visvol::test {

class LocalRowMail {
 public:
  explicit LocalRowMail(int shares) {
    for (int i = 0; i < shares; ++i) ends_.push_back(std::make_unique<End>(*this, i));
  }
  fields::RowExchange& share(int index) { return *ends_[static_cast<std::size_t>(index)]; }
  std::uint64_t rows_sent() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return rows_sent_;
  }

 private:
  using Key = std::tuple<int, int, int>;  // from, to, row

  class End final : public fields::RowExchange {
   public:
    End(LocalRowMail& mail, int index) : mail_(mail), index_(index) {}
    Status send(int to, int j, const std::int32_t* sums, std::size_t count) override {
      if (to < 0 || to >= static_cast<int>(mail_.ends_.size()) || to == index_) {
        return invalid_argument("share " + std::to_string(index_) + " sent row " + std::to_string(j) + " to share " +
                                std::to_string(to));
      }
      std::lock_guard<std::mutex> lock(mail_.mutex_);
      mail_.box_[Key{index_, to, j}].emplace_back(sums, sums + count);
      ++mail_.rows_sent_;
      mail_.arrived_.notify_all();
      return Status::ok_status();
    }
    Status receive(int from, int j, std::int32_t* sums, std::size_t count) override {
      std::unique_lock<std::mutex> lock(mail_.mutex_);
      std::deque<std::vector<std::int32_t>>& queue = mail_.box_[Key{from, index_, j}];
      if (!mail_.arrived_.wait_for(lock, std::chrono::minutes(1), [&] { return !queue.empty(); })) {
        return Status(Errc::output, "share " + std::to_string(index_) + " waited a minute for row " +
                                        std::to_string(j) + " from share " + std::to_string(from));
      }
      if (queue.front().size() != count) return Status(Errc::output, "row " + std::to_string(j) + ": wrong size");
      std::copy(queue.front().begin(), queue.front().end(), sums);
      queue.pop_front();
      return Status::ok_status();
    }
    Status finish() override { return Status::ok_status(); }

   private:
    LocalRowMail& mail_;
    int index_;
  };

  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::map<Key, std::deque<std::vector<std::int32_t>>> box_;
  std::uint64_t rows_sent_ = 0;
  std::vector<std::unique_ptr<End>> ends_;
};

}  // namespace visvol::test
