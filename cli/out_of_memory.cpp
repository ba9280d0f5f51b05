// The replaceable global allocation functions of the raypack executable (C++20
// [new.delete]): malloc and free as the library's own, plus the size of a failed request,
// which std::bad_alloc does not carry. Every form is replaced, so new and delete always pair.

#include "cli/out_of_memory.h"

#include <atomic>
#include <cstdlib>

namespace rp::cli {

namespace {

std::atomic<size_t> g_failed_bytes{0};

/// malloc (or aligned_alloc) with the new-handler loop of [new.delete.single].
void* allocate(size_t n, size_t alignment) {
  if (n == 0) n = 1;
  for (;;) {
    void* p = alignment <= alignof(std::max_align_t) ? std::malloc(n)
                                                      : std::aligned_alloc(alignment, (n + alignment - 1) / alignment * alignment);
    if (p) return p;
    g_failed_bytes.store(n, std::memory_order_relaxed);  // a handler may throw too
    std::new_handler handler = std::get_new_handler();
    if (!handler) throw std::bad_alloc();
    handler();
  }
}

}  // namespace

size_t failed_allocation_bytes() { return g_failed_bytes.load(std::memory_order_relaxed); }

}  // namespace rp::cli

void* operator new(std::size_t n) { return rp::cli::allocate(n, 0); }
void* operator new[](std::size_t n) { return rp::cli::allocate(n, 0); }
void* operator new(std::size_t n, std::align_val_t a) { return rp::cli::allocate(n, size_t(a)); }
void* operator new[](std::size_t n, std::align_val_t a) { return rp::cli::allocate(n, size_t(a)); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return rp::cli::allocate(n, 0);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return rp::cli::allocate(n, 0);
  } catch (...) {
    return nullptr;
  }
}
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  try {
    return rp::cli::allocate(n, size_t(a));
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  try {
    return rp::cli::allocate(n, size_t(a));
  } catch (...) {
    return nullptr;
  }
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
