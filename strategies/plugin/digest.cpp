#include "strategies/plugin/digest.hpp"

#include <xxhash.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <vector>

namespace ccd::plugin {
namespace {

std::string hex128(const XXH128_hash_t& hash) {
  char text[33];
  std::snprintf(text, sizeof text, "%016llx%016llx", static_cast<unsigned long long>(hash.high64), static_cast<unsigned long long>(hash.low64));
  return text;
}

void hash_file(XXH3_state_t* state, const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  char buffer[1 << 16];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) XXH3_128bits_update(state, buffer, static_cast<std::size_t>(in.gcount()));
}

}  // namespace

std::string bytes_digest(std::string_view bytes) { return hex128(XXH3_128bits(bytes.data(), bytes.size())); }

StreamDigest::StreamDigest() : state_(XXH3_createState()) { XXH3_128bits_reset(static_cast<XXH3_state_t*>(state_)); }

StreamDigest::~StreamDigest() { XXH3_freeState(static_cast<XXH3_state_t*>(state_)); }

void StreamDigest::update(std::string_view bytes) { XXH3_128bits_update(static_cast<XXH3_state_t*>(state_), bytes.data(), bytes.size()); }

std::string StreamDigest::hex() const { return hex128(XXH3_128bits_digest(static_cast<XXH3_state_t*>(state_))); }

std::string content_digest(const std::filesystem::path& path) {
  XXH3_state_t* state = XXH3_createState();
  XXH3_128bits_reset(state);
  if (std::filesystem::is_directory(path)) {
    std::vector<std::filesystem::path> files;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(path)) {
      if (entry.is_regular_file()) files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    for (const std::filesystem::path& file : files) {
      const std::string name = std::filesystem::relative(file, path).generic_string();
      XXH3_128bits_update(state, name.c_str(), name.size() + 1);
      hash_file(state, file);
      const char separator = '\0';
      XXH3_128bits_update(state, &separator, 1);
    }
  } else {
    hash_file(state, path);
  }
  const XXH128_hash_t hash = XXH3_128bits_digest(state);
  XXH3_freeState(state);
  return hex128(hash);
}

}  // namespace ccd::plugin
