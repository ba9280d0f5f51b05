#pragma once
/// Memory for unwinding after an allocation fails.
///
/// nlohmann::json's destructor is noexcept, and it allocates: it moves the children of an
/// array or object onto a stack of its own so that deep documents cannot overflow the call
/// stack. When a load runs out of memory with a large document alive, std::bad_alloc unwinds
/// into that destructor, its own allocation fails too, and the process ends in
/// std::terminate (exit 134) instead of the one-line message. While a MemoryReserve lives, a
/// block is held back and a new-handler is installed: the first allocation that fails frees
/// the block and throws std::bad_alloc as it would have, so what unwinds has the block's
/// memory to finish in.

#include <cstddef>

namespace rp {

/// The reserve a parsed JSON document of `text_bytes` may need to be destroyed: its walk
/// stack holds at most one 16-byte value per value in the document (at most one per two
/// bytes of text: values are separated) and grows by doubling, old and new buffers alive at
/// once: 24 bytes per byte of text, and 1 MiB at least. Address space, mostly: the block is
/// never written, so it costs memory only where address space is what is limited (ulimit -v).
size_t json_unwind_reserve(size_t text_bytes);

/// Holds `bytes` back for as long as it lives (see the top of this file). Reserves may nest
/// or overlap across threads: the block is the largest asked for by any live one, freed when
/// the last one ends or at the first failed allocation. Throws std::bad_alloc when the block
/// itself cannot be had (before the handler is installed).
class MemoryReserve {
 public:
  explicit MemoryReserve(size_t bytes);
  ~MemoryReserve();
  MemoryReserve(const MemoryReserve&) = delete;
  MemoryReserve& operator=(const MemoryReserve&) = delete;
};

}  // namespace rp
