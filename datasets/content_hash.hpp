#pragma once
/// @file
/// Content digests for cache keys, resumed cells and checksums: XXH3 from libxxhash (Debian's libxxhash-dev), a
/// well-kept non-cryptographic hash. It guards against accidents (other inputs, edited or truncated files, bit
/// rot), not against someone forging a file on purpose.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <type_traits>

namespace ccd::datasets {

/// A streaming 128-bit digest (XXH3-128). Feed bytes in a fixed order; equal streams give equal digests.
class ContentHash {
 public:
  ContentHash();
  ~ContentHash();
  ContentHash(const ContentHash&) = delete;
  ContentHash& operator=(const ContentHash&) = delete;

  void bytes(const void* data, std::size_t size);
  /// A value's object representation: only for types without padding (integers, doubles, packed arrays of them).
  template <class T>
  void value(const T& v) {
    static_assert((std::is_trivially_copyable_v<T> && std::has_unique_object_representations_v<T>) || std::is_floating_point_v<T>,
                  "hash only types whose bytes are their value");
    bytes(&v, sizeof v);
  }
  /// Text, prefixed with its length so that ("ab", "c") and ("a", "bc") differ.
  void text(std::string_view text);
  /// The digest so far, as 32 hex digits.
  std::string hex() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// XXH3-64 of a buffer: the checksum stored in binary caches.
std::uint64_t checksum64(const void* data, std::size_t size);

/// XXH3-128 of a whole file's bytes, as 32 hex digits. @throws InputError when the file cannot be read.
std::string file_digest(const std::filesystem::path& path);

}  // namespace ccd::datasets
