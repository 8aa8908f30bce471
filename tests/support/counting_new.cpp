// Replaces every form of the global operator new with one that counts while `counting` is set
// (on the thread `only_thread` names, when it names one: tests/support/counting_new.hpp), so that
// a test can check that a stretch of code does not touch the heap. Every form is replaced so that
// each allocation pairs with its deallocation, also under AddressSanitizer. Link it only into a
// test binary of its own.

#include "counting_new.hpp"

#include <algorithm>
#include <cstdlib>
#include <new>

namespace arbiter::test {
std::atomic<bool> counting{false};
std::atomic<std::size_t> allocations{0};
std::atomic<std::thread::id> only_thread{};
}  // namespace arbiter::test

using arbiter::test::allocations;
using arbiter::test::counts_here;

void* operator new(std::size_t size) {
  if (counts_here()) allocations.fetch_add(1);
  if (void* memory = std::malloc(size == 0 ? 1 : size)) return memory;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
  return operator new(size);
}
void operator delete(void* memory) noexcept {
  std::free(memory);
}
void operator delete[](void* memory) noexcept {
  std::free(memory);
}
void operator delete(void* memory, std::size_t) noexcept {
  std::free(memory);
}
void operator delete[](void* memory, std::size_t) noexcept {
  std::free(memory);
}
// The nothrow forms (std::stable_sort's buffer) must pair with the delete above, and count too.
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  if (counts_here()) allocations.fetch_add(1);
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept {
  return operator new(size, tag);
}
void operator delete(void* memory, const std::nothrow_t&) noexcept {
  std::free(memory);
}
void operator delete[](void* memory, const std::nothrow_t&) noexcept {
  std::free(memory);
}
// Over-aligned types have operators of their own; they count too.
void* operator new(std::size_t size, std::align_val_t align) {
  if (counts_here()) allocations.fetch_add(1);
  const auto alignment = static_cast<std::size_t>(align);
  const std::size_t rounded =
      (std::max<std::size_t>(size, 1) + alignment - 1) / alignment * alignment;
  if (void* memory = std::aligned_alloc(alignment, rounded)) return memory;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size, std::align_val_t align) {
  return operator new(size, align);
}
void operator delete(void* memory, std::align_val_t) noexcept {
  std::free(memory);
}
void operator delete[](void* memory, std::align_val_t) noexcept {
  std::free(memory);
}
void operator delete(void* memory, std::size_t, std::align_val_t) noexcept {
  std::free(memory);
}
void operator delete[](void* memory, std::size_t, std::align_val_t) noexcept {
  std::free(memory);
}
void* operator new(std::size_t size, std::align_val_t align, const std::nothrow_t&) noexcept {
  try {
    return operator new(size, align);
  } catch (const std::bad_alloc&) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, std::align_val_t align, const std::nothrow_t& tag) noexcept {
  return operator new(size, align, tag);
}
void operator delete(void* memory, std::align_val_t, const std::nothrow_t&) noexcept {
  std::free(memory);
}
void operator delete[](void* memory, std::align_val_t, const std::nothrow_t&) noexcept {
  std::free(memory);
}
