#include "io/memory_reserve.h"

#include <atomic>
#include <mutex>
#include <new>

namespace rp {

namespace {

std::mutex g_mutex;                     ///< guards the fields below but g_block
int g_live = 0;                         ///< MemoryReserve objects alive
size_t g_size = 0;                      ///< bytes of the block asked for
std::new_handler g_previous = nullptr;  ///< the handler before the first reserve
std::atomic<void*> g_block{nullptr};    ///< the block; null once spent

/// The new-handler: the block is spent on the first failure, and every failure throws as
/// operator new would without a handler.
void spend_reserve() {
  ::operator delete(g_block.exchange(nullptr));
  throw std::bad_alloc();
}

}  // namespace

size_t json_unwind_reserve(size_t text_bytes) {
  constexpr size_t kPerByte = 24, kLeast = size_t(1) << 20;
  return text_bytes > (SIZE_MAX - kLeast) / kPerByte ? SIZE_MAX : kLeast + kPerByte * text_bytes;
}

MemoryReserve::MemoryReserve(size_t bytes) {
  const std::lock_guard lock(g_mutex);
  // The block first, by operator new: a failure is std::bad_alloc with its size (the CLI's
  // allocator records it for the message), before anything here has changed.
  void* block = bytes > g_size || g_block.load() == nullptr ? ::operator new(bytes) : nullptr;
  if (g_live++ == 0) g_previous = std::set_new_handler(spend_reserve);
  if (block) {
    ::operator delete(g_block.exchange(block));
    g_size = bytes;
  }
}

MemoryReserve::~MemoryReserve() {
  const std::lock_guard lock(g_mutex);
  if (--g_live > 0) return;
  ::operator delete(g_block.exchange(nullptr));
  g_size = 0;
  std::set_new_handler(g_previous);
}

}  // namespace rp
