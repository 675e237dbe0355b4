#include "strategies/plugin/query_batch.hpp"

#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

namespace ccd::plugin {
namespace {

/// The counter of done answers has a cache line of its own before the queries.
constexpr std::size_t kHeaderSize = 64;
constexpr std::size_t kRegionSize = kHeaderSize + kBatchCapacity * (sizeof(BatchQuery) + sizeof(BatchAnswer));
static_assert(sizeof(BatchQuery) % alignof(double) == 0 && sizeof(BatchAnswer) % alignof(double) == 0);
static_assert(std::atomic_ref<std::uint64_t>::is_always_lock_free, "the counter is shared between processes: it must not take a lock");

void* map_region(int fd) {
  void* base = ::mmap(nullptr, kRegionSize, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  return base == MAP_FAILED ? nullptr : base;
}

}  // namespace

BatchRegion BatchRegion::create() {
  const int fd = ::memfd_create("ccdbench-query-batch", MFD_CLOEXEC);
  if (fd < 0 || ::ftruncate(fd, static_cast<off_t>(kRegionSize)) != 0) {
    const std::string why = std::strerror(errno);
    if (fd >= 0) ::close(fd);
    throw std::runtime_error("plugin isolation: cannot make the memory shared with a child: " + why);
  }
  void* base = map_region(fd);
  if (base == nullptr) {
    ::close(fd);
    throw std::runtime_error("plugin isolation: cannot map the memory shared with a child: " + std::string(std::strerror(errno)));
  }
  return BatchRegion(fd, base);
}

BatchRegion BatchRegion::open(int fd) {
  struct stat status {};
  if (::fstat(fd, &status) != 0 || static_cast<std::size_t>(status.st_size) != kRegionSize) {
    throw std::runtime_error("plugin-host: no batch region on fd " + std::to_string(fd));
  }
  void* base = map_region(fd);
  if (base == nullptr) throw std::runtime_error("plugin-host: cannot map the batch region");
  return BatchRegion(fd, base);
}

BatchRegion::BatchRegion(BatchRegion&& other) noexcept : fd_(other.fd_), base_(other.base_) {
  other.fd_ = -1;
  other.base_ = nullptr;
}

BatchRegion& BatchRegion::operator=(BatchRegion&& other) noexcept {
  if (this != &other) {
    this->~BatchRegion();
    fd_ = other.fd_;
    base_ = other.base_;
    other.fd_ = -1;
    other.base_ = nullptr;
  }
  return *this;
}

BatchRegion::~BatchRegion() {
  if (base_ != nullptr) ::munmap(base_, kRegionSize);
  if (fd_ >= 0) ::close(fd_);
}

BatchQuery* BatchRegion::queries() const { return reinterpret_cast<BatchQuery*>(static_cast<char*>(base_) + kHeaderSize); }

BatchAnswer* BatchRegion::answers() const {
  return reinterpret_cast<BatchAnswer*>(static_cast<char*>(base_) + kHeaderSize + kBatchCapacity * sizeof(BatchQuery));
}

std::uint64_t BatchRegion::done() const {
  return std::atomic_ref<std::uint64_t>(*static_cast<std::uint64_t*>(base_)).load(std::memory_order_acquire);
}

void BatchRegion::set_done(std::uint64_t count) const {
  std::atomic_ref<std::uint64_t>(*static_cast<std::uint64_t*>(base_)).store(count, std::memory_order_release);
}

}  // namespace ccd::plugin
