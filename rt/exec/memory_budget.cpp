#include "rt/exec/memory_budget.hpp"

#include <cstdio>

namespace visvol::rt {

std::string mib_text(std::uint64_t bytes) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f MiB", static_cast<double>(bytes) / (1024.0 * 1024.0));
  return b;
}

void MemoryBudget::reserve(const std::string& what, std::uint64_t bytes) { items_.push_back({what, bytes}); }

std::uint64_t MemoryBudget::reserved_bytes() const {
  std::uint64_t sum = 0;
  for (const Item& i : items_) sum += i.bytes;
  return sum;
}

std::uint64_t MemoryBudget::remaining_bytes() const {
  const std::uint64_t r = reserved_bytes();
  return r >= budget_ ? 0 : budget_ - r;
}

std::string MemoryBudget::table() const {
  std::string t;
  char line[160];
  for (const Item& i : items_) {
    std::snprintf(line, sizeof line, "  %-34s %12s\n", i.what.c_str(), mib_text(i.bytes).c_str());
    t += line;
  }
  std::snprintf(line, sizeof line, "  %-34s %12s of %s\n", "reserved", mib_text(reserved_bytes()).c_str(),
                mib_text(budget_).c_str());
  t += line;
  return t;
}

Status MemoryBudget::check(std::uint64_t minimum_left, const std::string& left_for) const {
  if (reserved_bytes() > budget_) {
    return Status(Errc::resource, "memory budget " + mib_text(budget_) + " is smaller than what the console " +
                                      "reserves before any tile:\n" + table());
  }
  if (remaining_bytes() < minimum_left) {
    return Status(Errc::resource, "memory budget " + mib_text(budget_) + " leaves " + mib_text(remaining_bytes()) +
                                      " for " + left_for + ", which needs at least " + mib_text(minimum_left) + ":\n" +
                                      table());
  }
  return {};
}

}  // namespace visvol::rt
