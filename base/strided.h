#pragma once
/// Strided<T>: a read-only view of items of T that lie a fixed number of bytes apart, as
/// Embree's buffer views (byte offset, byte stride, item count) describe vertex and index
/// data: positions interleaved with normals and uvs, a column of an array of structs, or a
/// plain array (stride = sizeof(T)).

#include <cstddef>
#include <cstdint>
#include <iterator>
#include <span>
#include <vector>

namespace rp {

template <typename T>
class Strided {
 public:
  Strided() = default;
  /// `count` items at data, data + stride bytes, ... The view does not own them. Whether
  /// `data` and `stride` suit T (aligned, stride >= sizeof(T)) is for the taker to check:
  /// fits() says.
  Strided(const T* data, size_t count, size_t stride = sizeof(T))
      : data_(reinterpret_cast<const std::byte*>(data)), size_(count), stride_(stride) {}
  Strided(std::span<const T> items) : Strided(items.data(), items.size()) {}
  Strided(const std::vector<T>& items) : Strided(items.data(), items.size()) {}

  const T& operator[](size_t i) const { return *reinterpret_cast<const T*>(data_ + i * stride_); }
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  /// Bytes from one item to the next.
  size_t stride() const { return stride_; }
  const T* data() const { return reinterpret_cast<const T*>(data_); }
  /// True when the items can be read as T: none, or a non-null, aligned start and an aligned
  /// stride of at least sizeof(T).
  bool fits() const {
    if (size_ == 0) return true;
    return data_ != nullptr && reinterpret_cast<uintptr_t>(data_) % alignof(T) == 0 && stride_ >= sizeof(T) &&
           stride_ % alignof(T) == 0;
  }

  class iterator {
   public:
    using iterator_category = std::forward_iterator_tag;
    using value_type = T;
    using difference_type = std::ptrdiff_t;
    using pointer = const T*;
    using reference = const T&;
    iterator() = default;
    iterator(const std::byte* p, size_t stride) : p_(p), stride_(stride) {}
    const T& operator*() const { return *reinterpret_cast<const T*>(p_); }
    const T* operator->() const { return reinterpret_cast<const T*>(p_); }
    iterator& operator++() {
      p_ += stride_;
      return *this;
    }
    iterator operator++(int) {
      iterator before = *this;
      p_ += stride_;
      return before;
    }
    bool operator==(const iterator& o) const { return p_ == o.p_; }

   private:
    const std::byte* p_ = nullptr;
    size_t stride_ = 0;
  };
  iterator begin() const { return {data_, stride_}; }
  iterator end() const { return {data_ + size_ * stride_, stride_}; }

 private:
  const std::byte* data_ = nullptr;
  size_t size_ = 0;
  size_t stride_ = sizeof(T);
};

}  // namespace rp
