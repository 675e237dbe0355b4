#pragma once
/// @file
/// The digests that name a plugin's code and an answer folder's content (XXH3-128, 32 hex digits).

#include <filesystem>
#include <string>
#include <string_view>

namespace ccd::plugin {

/// XXH3-128 of bytes, as 32 hex digits.
std::string bytes_digest(std::string_view bytes);

/// XXH3-128 of bytes given in parts: the digest of their concatenation (bytes_digest of it), without holding it.
class StreamDigest {
 public:
  StreamDigest();
  ~StreamDigest();
  StreamDigest(const StreamDigest&) = delete;
  StreamDigest& operator=(const StreamDigest&) = delete;
  void update(std::string_view bytes);
  std::string hex() const;

 private:
  void* state_;
};

/// XXH3-128 of a file's bytes, or of every file under a folder (their relative paths and bytes, in path order), as
/// 32 hex digits, read apart from any use of them: what builds with the identity and read-once guards left out
/// record (CCDBENCH_PLUGIN_GUARDS_OFF), where it stands for the earlier, weaker digests.
std::string content_digest(const std::filesystem::path& path);

}  // namespace ccd::plugin
