// The console's memory budget: what it reserves at start-up, item by item,
// against one configured figure. The tile cache gets what is left; start-up
// refuses, with the table, when the budget cannot hold the minimum.
//
// The process's own baseline (code, libraries, DDS threads) is measured as
// resident memory before anything is reserved; the other items are the sizes
// the console allocates for them. Resident memory is measured again while
// running (rt/exec/realtime.hpp resident_bytes()) and reported against the
// budget.
//
// Thread-safety: start-up only, one thread. Allocates.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "base/status.hpp"

namespace visvol::rt {

class MemoryBudget {
 public:
  explicit MemoryBudget(std::uint64_t budget_bytes) : budget_(budget_bytes) {}

  // Records an item; never fails (check() does).
  void reserve(const std::string& what, std::uint64_t bytes);
  std::uint64_t budget_bytes() const { return budget_; }
  std::uint64_t reserved_bytes() const;
  // What is left for the tile cache (0 when over).
  std::uint64_t remaining_bytes() const;
  // Errc::resource when the items alone exceed the budget, or leave less than
  // `minimum_left` for `left_for`; the message carries the table.
  Status check(std::uint64_t minimum_left = 0, const std::string& left_for = "") const;
  // "what  12.3 MiB" lines and the total.
  std::string table() const;

  struct Item {
    std::string what;
    std::uint64_t bytes;
  };
  const std::vector<Item>& items() const { return items_; }

 private:
  std::uint64_t budget_;
  std::vector<Item> items_;
};

std::string mib_text(std::uint64_t bytes);

}  // namespace visvol::rt
