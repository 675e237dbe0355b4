#pragma once
/// @file
/// Queries answered in batches by an isolated plugin (isolation.hpp), through memory the parent shares with its
/// child: the parent writes up to kBatchCapacity queries there and sends one request; the child answers them in
/// order, writing each answer beside its query and then counting it done. A pipe round trip per query (about
/// 15 µs) becomes a few copies, so that isolation can be the default; and since `done` is written after each answer,
/// the parent knows, when the child crashes or hangs, exactly which query it was answering: that query alone is the
/// error, the answers before it stand, and a fresh child takes the queries after it.
///
/// The parent trusts nothing it reads back: `done` is clamped to the batch, an answer counts only with this batch's
/// stamp, each answer is copied out once and checked as any plugin answer is (plugin_narrow_phase.hpp), and its
/// message is terminated.

#include "strategies/plugin/ccdbench_plugin.h"

#include <cstddef>
#include <cstdint>

namespace ccd::plugin {

/// One query of a batch, as the child reads it.
struct BatchQuery {
  double rows[24];
  double thickness;
  std::uint32_t vertex_face;
  std::uint32_t reserved;
};

/// One answer, as the child writes it, stamped with its batch's number (the low 32 bits of its request's): an answer
/// left from an earlier batch, or written by a process the plugin started, is never taken for this batch's.
struct BatchAnswer {
  std::int32_t outcome;
  std::uint32_t batch;
  double toi;
  char message[CCDBENCH_MESSAGE_SIZE];
};

/// Queries per batch at most: 4096 queries and answers take about 2 MB of the shared region.
inline constexpr std::size_t kBatchCapacity = 4096;

/// The shared region: how many answers are done, then the queries, then the answers.
class BatchRegion {
 public:
  /// The parent's: a new anonymous file of the region's size (close-on-exec; a child gets it by dup2), mapped.
  /// @throws std::runtime_error when the system refuses.
  static BatchRegion create();
  /// The child's: the region on `fd`, mapped. @throws std::runtime_error when it is not one.
  static BatchRegion open(int fd);
  BatchRegion(BatchRegion&& other) noexcept;
  BatchRegion& operator=(BatchRegion&& other) noexcept;
  BatchRegion(const BatchRegion&) = delete;
  BatchRegion& operator=(const BatchRegion&) = delete;
  ~BatchRegion();

  int fd() const { return fd_; }
  BatchQuery* queries() const;
  BatchAnswer* answers() const;
  /// Answers written so far in the current batch (release/acquire: an answer counted is whole).
  std::uint64_t done() const;
  void set_done(std::uint64_t count) const;

 private:
  BatchRegion(int fd, void* base) : fd_(fd), base_(base) {}
  int fd_ = -1;
  void* base_ = nullptr;
};

}  // namespace ccd::plugin
