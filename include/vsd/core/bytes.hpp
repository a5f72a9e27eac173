#pragma once
// Minimal binary encoding for passing results between worker processes of the
// same binary (same layout on both ends, so no versioning or endianness work).

#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "vsd/core/error.hpp"

namespace vsd {

class ByteWriter {
 public:
  template <typename T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>, "put() takes trivially copyable values");
    const auto* bytes = reinterpret_cast<const char*>(&value);
    buffer_.insert(buffer_.end(), bytes, bytes + sizeof(T));
  }
  void putString(const std::string& text) {
    put<std::uint64_t>(text.size());
    buffer_.insert(buffer_.end(), text.begin(), text.end());
  }
  template <typename T>
  void putVector(const std::vector<T>& values) {
    static_assert(std::is_trivially_copyable_v<T>, "putVector() takes trivially copyable values");
    put<std::uint64_t>(values.size());
    const auto* bytes = reinterpret_cast<const char*>(values.data());
    buffer_.insert(buffer_.end(), bytes, bytes + values.size() * sizeof(T));
  }
  const std::vector<char>& bytes() const { return buffer_; }
  std::vector<char>& bytes() { return buffer_; }

 private:
  std::vector<char> buffer_;
};

class ByteReader {
 public:
  ByteReader(const char* data, std::size_t size) : data_(data), size_(size) {}
  explicit ByteReader(const std::vector<char>& bytes) : ByteReader(bytes.data(), bytes.size()) {}

  template <typename T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>, "get() returns trivially copyable values");
    need(sizeof(T));
    T value;
    std::memcpy(&value, data_ + offset_, sizeof(T));
    offset_ += sizeof(T);
    return value;
  }
  std::string getString() {
    const auto size = static_cast<std::size_t>(get<std::uint64_t>());
    need(size);
    std::string text(data_ + offset_, size);
    offset_ += size;
    return text;
  }
  template <typename T>
  std::vector<T> getVector() {
    const auto count = static_cast<std::size_t>(get<std::uint64_t>());
    need(count * sizeof(T));
    std::vector<T> values(count);
    std::memcpy(values.data(), data_ + offset_, count * sizeof(T));
    offset_ += count * sizeof(T);
    return values;
  }
  bool atEnd() const { return offset_ == size_; }

 private:
  void need(std::size_t bytes) const {
    if (offset_ + bytes > size_) throw Error("internal: truncated message between worker processes");
  }
  const char* data_;
  std::size_t size_;
  std::size_t offset_ = 0;
};

}  // namespace vsd
