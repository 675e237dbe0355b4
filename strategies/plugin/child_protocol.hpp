#pragma once
/// @file
/// What an isolated plugin's child process and its parent say to each other (isolation.hpp): the requests on the
/// child's fd 3, its replies on fd 4, the lifeline on fd 5 and the batch memory on fd 6, and the helpers both sides
/// write and read them with. Internal to isolation.cpp and plugin_host.cpp.

#include "strategies/plugin/ccdbench_plugin.h"

#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <vector>

namespace ccd::plugin::child_protocol {

// Requests: one byte, the request's number (64 bits, counting up from 1 for each parent), then their payload.
// Replies: the number of the request they answer, then a 32-bit status or outcome and a message (a batch's: its
// number and kBatchDone). A reply with another number is not this request's: a process the plugin started wrote it.
inline constexpr char kQuery = 'Q';
inline constexpr char kBegin = 'B';
inline constexpr char kStep = 'S';
inline constexpr char kEnd = 'E';
inline constexpr char kBatch = 'M';
/// The child's ends of the two pipes.
inline constexpr int kRequestFd = 3;
inline constexpr int kReplyFd = 4;

inline constexpr std::size_t kStatusSize = sizeof(std::int32_t) + CCDBENCH_MESSAGE_SIZE;

inline double now_seconds() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

template <class T>
void put(std::vector<char>& out, const T& value) {
  const char* bytes = reinterpret_cast<const char*>(&value);
  out.insert(out.end(), bytes, bytes + sizeof(T));
}
template <class T>
void put_array(std::vector<char>& out, const T* values, std::size_t count) {
  put(out, static_cast<std::uint64_t>(count));
  const char* bytes = reinterpret_cast<const char*>(values);
  out.insert(out.end(), bytes, bytes + count * sizeof(T));
}

template <class T>
T take(const char*& at) {
  T value;
  std::memcpy(&value, at, sizeof(T));
  at += sizeof(T);
  return value;
}

inline bool write_all(int fd, const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t written = ::write(fd, data, size);
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0) return false;
    data += written;
    size -= static_cast<std::size_t>(written);
  }
  return true;
}

/// Reads exactly `size` bytes; false at the end of the stream or an error.
inline bool read_all(int fd, char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t got = ::read(fd, data, size);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return false;
    data += got;
    size -= static_cast<std::size_t>(got);
  }
  return true;
}

inline std::vector<char> status_reply(std::int32_t status, const char* message) {
  std::vector<char> reply;
  put(reply, status);
  char text[CCDBENCH_MESSAGE_SIZE] = {};
  std::strncpy(text, message, CCDBENCH_MESSAGE_SIZE - 1);
  reply.insert(reply.end(), text, text + CCDBENCH_MESSAGE_SIZE);
  return reply;
}

/// The child's greeting: a status, a message, and the digest of the code it loaded (32 hex digits). Status 0: ready;
/// 1: the plugin refused its configuration; kChangedStatus: its code is not the code the run was planned with (the
/// child then calls nothing of it); kUnloadableStatus: it could not be loaded.
inline constexpr std::size_t kDigestSize = 32;
inline constexpr std::size_t kGreetingSize = kStatusSize + kDigestSize;
inline constexpr std::int32_t kChangedStatus = 2;
/// A child that could not load the plugin at all (removed, half-written by a build): its code changed too.
inline constexpr std::int32_t kUnloadableStatus = 3;
/// A child whose plugin's create call failed (it left the floating-point environment changed, or threw): the plugin
/// is refused, as in-process.
inline constexpr std::int32_t kCreateFailedStatus = 4;

/// The child's end of the lifeline (docs/DESIGN.md §10): the parent holds the other end open and never writes, so
/// the pipe reports its end only when the parent is gone.
inline constexpr int kLifelineFd = 5;
/// The memory of query batches (query_batch.hpp), when the parent shares one.
inline constexpr int kBatchFd = 6;
/// A batch says it is done with its request's number and one byte on the reply pipe.
inline constexpr char kBatchDone = 'D';
inline constexpr std::size_t kBatchDoneSize = sizeof(std::uint64_t) + 1;
/// While a batch is answered, the parent looks this often at how many answers are done (each moves the deadline on).
inline constexpr double kBatchWatchSeconds = 0.1;
/// How long a child whose requests ended (its pipe closed) may take to end by itself (its plugin's destroy) before it
/// is killed.
inline constexpr double kEndSeconds = 10;

}  // namespace ccd::plugin::child_protocol
