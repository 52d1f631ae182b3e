#pragma once
/// \file allocation_budget.h
/// A cap on what one thread may allocate while a scope is open, for third-party readers that trust
/// the sizes written in a damaged file (assimp). While an AllocationBudget is alive on a thread,
/// every `operator new` on that thread counts against it, and a request that would exceed it throws
/// std::bad_alloc instead of asking the system for the memory. Other threads are not affected.

#include <cstddef>
#include <cstdint>

namespace pandora {

class AllocationBudget {
 public:
  /// Opens a budget of `bytes` on the calling thread (nested budgets: the innermost one counts).
  explicit AllocationBudget(std::uint64_t bytes);
  ~AllocationBudget();
  AllocationBudget(const AllocationBudget&) = delete;
  AllocationBudget& operator=(const AllocationBudget&) = delete;

  /// True when a request was refused since the budget opened.
  bool exceeded() const { return exceeded_; }
  /// The largest number of bytes held at once under this budget so far.
  std::uint64_t peak_bytes() const { return peak_; }

  /// Whether the budget is enforced in this build (not under AddressSanitizer, which replaces
  /// operator new itself and has its own limits).
  static bool enforced();

  /// Internal: called by the replaced operator new / delete.
  bool Take(std::size_t bytes);    ///< Counts `bytes` when they fit; false otherwise.
  void Charge(std::size_t bytes);  ///< Counts `bytes` unconditionally.
  void Give(std::size_t bytes);    ///< Credits freed bytes.

 private:
  std::int64_t left_;
  std::uint64_t limit_;
  std::uint64_t peak_ = 0;
  bool exceeded_ = false;
  AllocationBudget* outer_;
};

/// Bytes of physical memory on this machine (sysconf); 0 when unknown.
std::uint64_t PhysicalMemoryBytes();

/// Hands the heap's free pages back to the system (glibc's malloc_trim; nothing elsewhere). For a
/// one-shot command between stages (after an import, after a field evaluation), where freed small
/// allocations would otherwise stay resident beside what the next stage allocates. Not inside
/// loops: the pages handed back are faulted in again by the next allocation that needs them (on
/// this project's VM a 4 KiB page fault costs about 12 us; one trim per evaluation cost the
/// trauma room's repeated evaluations a fifth of their time, docs/performance.md).
void ReleaseFreedMemory();

}  // namespace pandora
