#include "strategies/plugin/child_process.hpp"

#include "strategies/plugin/child_protocol.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <utility>

extern char** environ;

namespace ccd::plugin {

namespace {

std::mutex& host_program_mutex() {
  static std::mutex mutex;
  return mutex;
}

std::string& host_program_path() {
  static std::string path = "/proc/self/exe";
  return path;
}

}  // namespace

void set_host_program(const std::string& path) {
  std::lock_guard lock(host_program_mutex());
  host_program_path() = path;
}

std::string host_program() {
  std::lock_guard lock(host_program_mutex());
  return host_program_path();
}

using namespace child_protocol;

namespace {

/// How often a read that waits also looks whether the child itself is still there: the reply pipe ends only when
/// every process holding it is gone, and one the plugin forked may hold it for ever. A crash is seen within this.
constexpr int kChildWatchMilliseconds = 50;

std::atomic<std::size_t>& children_peak() {
  static std::atomic<std::size_t> peak{0};
  return peak;
}

void close_descriptors(ChildProcess& child) {
  for (int* fd : {&child.to_child, &child.from_child, &child.lifeline}) {
    if (*fd >= 0) ::close(*fd);
    *fd = -1;
  }
}

/// What ended a child, in words.
std::string ending(int status) {
  if (WIFSIGNALED(status)) {
    return "it crashed with signal " + std::to_string(WTERMSIG(status)) + " (" + ::strsignal(WTERMSIG(status)) + ")";
  }
  if (WIFEXITED(status)) return "its process exited with status " + std::to_string(WEXITSTATUS(status));
  return "its process ended";
}

}  // namespace

ChildProcess spawn_child(const std::vector<std::string>& plugin_host_arguments, int batch_fd) {
  int pipes[3][2] = {{-1, -1}, {-1, -1}, {-1, -1}};  // requests, replies, lifeline
  auto close_all = [&] {
    for (auto& pipe : pipes) {
      for (int& fd : pipe) {
        if (fd >= 0) ::close(fd);
        fd = -1;
      }
    }
  };
  for (auto& pipe : pipes) {
    if (::pipe2(pipe, O_CLOEXEC) != 0) {
      const std::string why = std::strerror(errno);
      close_all();
      throw std::runtime_error("plugin isolation: cannot make a pipe to a child: " + why);
    }
  }
  // The child's descriptors are moved above the numbers they get in the child first: dup2 of a descriptor onto its
  // own number does nothing, not even clear close-on-exec, and the child would start without it.
  constexpr int kAboveChildDescriptors = 16;
  auto above = [&](int& fd) {
    const int moved = ::fcntl(fd, F_DUPFD_CLOEXEC, kAboveChildDescriptors);
    if (moved >= 0) {
      ::close(fd);
      fd = moved;
    }
    return moved >= 0;
  };
  int batch = batch_fd >= 0 ? ::fcntl(batch_fd, F_DUPFD_CLOEXEC, kAboveChildDescriptors) : -1;
  const bool moved = above(pipes[0][0]) && above(pipes[1][1]) && above(pipes[2][0]) && (batch_fd < 0 || batch >= 0);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  int prepared = moved ? 0 : EMFILE;
  if (prepared == 0) prepared = posix_spawn_file_actions_adddup2(&actions, pipes[0][0], kRequestFd);
  if (prepared == 0) prepared = posix_spawn_file_actions_adddup2(&actions, pipes[1][1], kReplyFd);
  if (prepared == 0) prepared = posix_spawn_file_actions_adddup2(&actions, pipes[2][0], kLifelineFd);
  if (prepared == 0 && batch >= 0) prepared = posix_spawn_file_actions_adddup2(&actions, batch, kBatchFd);
  // Nothing else of this process goes to the child (descriptors not marked close-on-exec by the libraries).
  if (prepared == 0) prepared = posix_spawn_file_actions_addclosefrom_np(&actions, kBatchFd + 1);
  const std::string program = host_program();
  std::vector<std::string> arguments{program, kPluginHostCommand};
  arguments.insert(arguments.end(), plugin_host_arguments.begin(), plugin_host_arguments.end());
  std::vector<char*> argv;
  for (std::string& argument : arguments) argv.push_back(argument.data());
  argv.push_back(nullptr);
  // This program's own file through /proc/self/exe (unless set_host_program named another: a process using the C++
  // API names the ccdbench program), not a name looked up on PATH nor its path: the child is this very build, even
  // when the file was rebuilt or removed since this process started.
  // The child leads a process group of its own, so that ending it ends what it started too (unless that left the
  // group on purpose).
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  if (prepared == 0) prepared = posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
  if (prepared == 0) prepared = posix_spawnattr_setpgroup(&attributes, 0);
  ChildProcess child;
  const int spawned = prepared != 0 ? prepared : ::posix_spawn(&child.pid, program.c_str(), &actions, &attributes, argv.data(), environ);
  posix_spawnattr_destroy(&attributes);
  posix_spawn_file_actions_destroy(&actions);
  if (batch >= 0) ::close(batch);
  child.to_child = pipes[0][1];
  child.from_child = pipes[1][0];
  child.lifeline = pipes[2][1];
  pipes[0][1] = pipes[1][0] = pipes[2][1] = -1;
  close_all();  // the child's ends
  if (spawned != 0) {
    close_descriptors(child);
    throw std::runtime_error("plugin isolation: cannot start a child process: " + std::string(std::strerror(spawned)));
  }
  return child;
}

bool child_ended(const ChildProcess& child) {
  if (child.pid <= 0) return true;
  siginfo_t info{};
  // WNOWAIT: it stays a zombie, so its process group (named by its pid) stays its own until end_child reaps it.
  while (::waitid(P_PID, static_cast<id_t>(child.pid), &info, WEXITED | WNOHANG | WNOWAIT) < 0) {
    if (errno != EINTR) return true;
  }
  return info.si_pid == child.pid;
}

ChildRead read_from_child(const ChildProcess& child, char* data, std::size_t size, double deadline) {
  std::size_t filled = 0;
  return read_some_from_child(child, data, size, filled, deadline);
}

ChildRead read_some_from_child(const ChildProcess& child, char* data, std::size_t size, std::size_t& filled, double deadline) {
  while (filled < size) {
    const double left = deadline - now_seconds();
    if (left <= 0) return ChildRead::timed_out;
    pollfd ready{child.from_child, POLLIN, 0};
    const int polled = ::poll(&ready, 1, std::min(kChildWatchMilliseconds, static_cast<int>(std::ceil(left * 1000))));
    if (polled < 0 && errno == EINTR) continue;
    if (polled == 0) {
      // Nothing to read: the child may be gone while a process it started keeps the pipe open.
      if (child_ended(child)) return ChildRead::ended;
      continue;
    }
    const ssize_t n = ::read(child.from_child, data + filled, size - filled);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return ChildRead::ended;
    filled += static_cast<std::size_t>(n);
  }
  return ChildRead::whole;
}

std::string end_child(ChildProcess& child, bool kill_it, double grace_seconds) {
  // Its requests end; the lifeline stays open until it has ended, so that it ends as a child whose parent is there
  // (its plugin's destroy, then what the plugin started, then itself), not as one whose parent died.
  const int lifeline = std::exchange(child.lifeline, -1);
  close_descriptors(child);
  const auto close_lifeline = [&] {
    if (lifeline >= 0) ::close(lifeline);
  };
  if (child.pid <= 0) {
    close_lifeline();
    return "it was not running";
  }
  const pid_t pid = child.pid;
  child.pid = -1;
  // Its process group (the child and what it started), and the child itself, which may have left its group to end
  // the rest of it (plugin_host.cpp): until it is reaped, its pid names it.
  const auto kill_all = [pid] {
    ::kill(-pid, SIGKILL);
    ::kill(pid, SIGKILL);
  };
  if (kill_it) kill_all();
  // Its requests ended (the pipe closed): it ends by itself, or is killed after the grace.
  const double deadline = now_seconds() + grace_seconds;
  const ChildProcess watched{pid, -1, -1, -1};
  while (!child_ended(watched)) {
    if (now_seconds() >= deadline) {
      kill_all();
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  close_lifeline();
  // The child ended but is not reaped yet: its group still names only what it started, which goes with it.
  ::kill(-pid, SIGKILL);
  int status = 0;
  rusage usage{};
  while (::wait4(pid, &status, 0, &usage) < 0 && errno == EINTR) {
  }
  // ru_maxrss is in kilobytes on Linux.
  const std::size_t peak = static_cast<std::size_t>(usage.ru_maxrss) * 1024;
  std::size_t seen = children_peak().load();
  while (peak > seen && !children_peak().compare_exchange_weak(seen, peak)) {
  }
  return ending(status);
}

std::size_t children_peak_bytes() { return children_peak().load(); }

void reset_children_peak() { children_peak().store(0); }

}  // namespace ccd::plugin
