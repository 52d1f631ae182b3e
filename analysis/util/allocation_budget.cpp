#include "analysis/util/allocation_budget.h"

#include <malloc.h>
#include <unistd.h>

#include <cstdlib>
#include <new>

#if defined(__SANITIZE_ADDRESS__)
#define PANDORA_NO_BUDGET 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PANDORA_NO_BUDGET 1
#endif
#endif

namespace pandora {
namespace {
thread_local AllocationBudget* t_budget = nullptr;
}  // namespace

AllocationBudget::AllocationBudget(std::uint64_t bytes)
    : left_(static_cast<std::int64_t>(bytes > (1ull << 62) ? (1ull << 62) : bytes)),
      limit_(static_cast<std::uint64_t>(left_)),
      outer_(t_budget) {
  t_budget = this;
}

AllocationBudget::~AllocationBudget() { t_budget = outer_; }

bool AllocationBudget::enforced() {
#ifdef PANDORA_NO_BUDGET
  return false;
#else
  return true;
#endif
}

bool AllocationBudget::Take(std::size_t bytes) {
  if (static_cast<std::uint64_t>(bytes) > static_cast<std::uint64_t>(left_ > 0 ? left_ : 0)) {
    exceeded_ = true;
    return false;
  }
  Charge(bytes);
  return true;
}

void AllocationBudget::Charge(std::size_t bytes) {
  left_ -= static_cast<std::int64_t>(bytes);
  const std::int64_t held = static_cast<std::int64_t>(limit_) - left_;
  if (held > 0 && static_cast<std::uint64_t>(held) > peak_)
    peak_ = static_cast<std::uint64_t>(held);
}

void AllocationBudget::Give(std::size_t bytes) { left_ += static_cast<std::int64_t>(bytes); }

std::uint64_t PhysicalMemoryBytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return 0;
  return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page);
}

void ReleaseFreedMemory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

}  // namespace pandora

#ifndef PANDORA_NO_BUDGET
// The replaced global allocation functions. Outside a budget they are malloc and free; inside one
// they count malloc_usable_size of each block, so frees are credited exactly.
namespace {

void* Allocate(std::size_t n, bool nothrow) {
  if (n == 0) n = 1;
  pandora::AllocationBudget* budget = pandora::t_budget;
  if (budget != nullptr && !budget->Take(n)) {
    if (nothrow) return nullptr;
    throw std::bad_alloc();
  }
  void* p = std::malloc(n);
  if (p == nullptr) {
    if (budget != nullptr) budget->Give(n);
    if (nothrow) return nullptr;
    throw std::bad_alloc();
  }
  // Count what malloc really handed out, so the matching free credits the same amount.
  if (budget != nullptr) {
    const std::size_t usable = malloc_usable_size(p);
    if (usable > n) budget->Charge(usable - n);
  }
  return p;
}

void Free(void* p) noexcept {
  if (p == nullptr) return;
  if (pandora::AllocationBudget* budget = pandora::t_budget) budget->Give(malloc_usable_size(p));
  std::free(p);
}

}  // namespace

void* operator new(std::size_t n) { return Allocate(n, false); }
void* operator new[](std::size_t n) { return Allocate(n, false); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return Allocate(n, true); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return Allocate(n, true); }
void operator delete(void* p) noexcept { Free(p); }
void operator delete[](void* p) noexcept { Free(p); }
void operator delete(void* p, std::size_t) noexcept { Free(p); }
void operator delete[](void* p, std::size_t) noexcept { Free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { Free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { Free(p); }
#endif
