#pragma once
// Growable storage whose elements never move: fixed-size chunks reached through a table of
// atomic pointers. Appends from several threads are safe (an atomic size counter plus a mutex
// taken only when a new chunk is needed); reads of indices below the size need no lock.
// This is what lets parallel local operations allocate vertices and cells while other threads
// read unrelated parts of the mesh.

#include <atomic>
#include <cstddef>
#include <memory>
#include <mutex>

#include "meshing/core/error.hpp"

namespace curvefem::meshing::editing {

template <class T>
class ChunkedVector {
 public:
  static constexpr std::size_t k_chunk_bits = 12;
  static constexpr std::size_t k_chunk_size = std::size_t{1} << k_chunk_bits;
  static constexpr std::size_t k_max_chunks = std::size_t{1} << 16;  // 268 M elements

  explicit ChunkedVector(T fill = T{})
      : m_fill(std::move(fill)), m_chunks(std::make_unique<std::atomic<T*>[]>(k_max_chunks)) {}
  ChunkedVector(const ChunkedVector&) = delete;
  ChunkedVector& operator=(const ChunkedVector&) = delete;
  ~ChunkedVector() { release(); }

  std::size_t size() const { return m_size.load(std::memory_order_acquire); }

  T& operator[](std::size_t i) {
    return m_chunks[i >> k_chunk_bits].load(std::memory_order_acquire)[i & (k_chunk_size - 1)];
  }
  const T& operator[](std::size_t i) const {
    return m_chunks[i >> k_chunk_bits].load(std::memory_order_acquire)[i & (k_chunk_size - 1)];
  }

  // Reserves `count` new consecutive indices and returns the first; thread-safe.
  std::size_t append(std::size_t count = 1) {
    const std::size_t first = m_size.fetch_add(count, std::memory_order_acq_rel);
    ensure_storage(first, first + count);
    return first;
  }

  // Makes indices below n addressable (filled with the fill value); thread-safe, never shrinks
  // the size counter.
  void grow_to(std::size_t n) {
    ensure_storage(0, n);
    std::size_t cur = m_size.load(std::memory_order_acquire);
    while (cur < n && !m_size.compare_exchange_weak(cur, n, std::memory_order_acq_rel)) {
    }
  }

  // Serial only: drops every element and resets the size to n (filled with the fill value).
  void reset(std::size_t n) {
    release();
    m_size.store(0);
    grow_to(n);
  }

 private:
  void ensure_storage(std::size_t begin, std::size_t end) {
    if (end <= begin) return;
    const std::size_t last_chunk = (end - 1) >> k_chunk_bits;
    CF_VERIFY(last_chunk < k_max_chunks, "ChunkedVector: capacity exceeded");
    for (std::size_t c = begin >> k_chunk_bits; c <= last_chunk; ++c) {
      if (m_chunks[c].load(std::memory_order_acquire) != nullptr) continue;
      std::lock_guard<std::mutex> guard(m_grow_mutex);
      if (m_chunks[c].load(std::memory_order_relaxed) != nullptr) continue;
      T* chunk = new T[k_chunk_size];
      for (std::size_t i = 0; i < k_chunk_size; ++i) chunk[i] = m_fill;
      m_chunks[c].store(chunk, std::memory_order_release);
    }
  }
  void release() {
    for (std::size_t c = 0; c < k_max_chunks; ++c) {
      T* chunk = m_chunks[c].exchange(nullptr);
      delete[] chunk;
    }
  }

  T m_fill;
  std::unique_ptr<std::atomic<T*>[]> m_chunks;
  std::atomic<std::size_t> m_size{0};
  std::mutex m_grow_mutex;
};

}  // namespace curvefem::meshing::editing
