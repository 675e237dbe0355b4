#pragma once
/// @file
/// The child processes of isolated plugins (isolation.hpp) as processes: started, read from within a deadline, and
/// ended with everything they started. Internal to isolation.cpp.
///
/// What holds in every path (docs/DESIGN.md §10 "Isolated"):
/// - a child leads a process group of its own, and ending it ends the group: whatever the plugin started (a process
///   it forked at load or inside a call) is killed before the child is reaped, whether the child was killed, crashed
///   or ended normally;
/// - a child that dies is seen dead even while another process (one the plugin forked) holds its reply pipe open:
///   reading its replies also watches the child itself, so a crash is reported as a crash, never as a timeout;
/// - the peak resident memory of every child ended is kept (children_peak_bytes), so that a cell's memory counts its
///   plugin's process too.

#include <sys/types.h>

#include <cstddef>
#include <string>
#include <vector>

namespace ccd::plugin {

/// The program an isolated plugin's child runs: this process's own file (/proc/self/exe), the ccdbench program,
/// unless set otherwise. A process that is not ccdbench (a program using the C++ API) sets the ccdbench program
/// installed beside the library.
void set_host_program(const std::string& path);
std::string host_program();

/// The first argument that makes ccdbench a plugin's child process.
inline constexpr const char* kPluginHostCommand = "plugin-host";

/// A child of this program, `PROGRAM plugin-host ARGUMENTS...`, with its request pipe on fd 3, its reply pipe on
/// fd 4 and the lifeline on fd 5 (and the batch memory on fd 6 when given); the parent's ends are close-on-exec, so
/// that no other child holds them.
struct ChildProcess {
  pid_t pid = -1;
  int to_child = -1, from_child = -1, lifeline = -1;
};

/// Starts `host_program() plugin-host ARGUMENTS...` as the leader of a process group of its own.
/// @throws std::runtime_error when the system refuses.
ChildProcess spawn_child(const std::vector<std::string>& plugin_host_arguments, int batch_fd = -1);

/// How a read from a child ended.
enum class ChildRead { whole, ended, timed_out };

/// Reads exactly `size` bytes of the child's replies before `deadline` (seconds, now_seconds): whole, or ended (the
/// stream ended, or the child died with nothing more to read, whoever else holds the pipe), or timed_out.
ChildRead read_from_child(const ChildProcess& child, char* data, std::size_t size, double deadline);
/// The same, going on from `filled` bytes already read and counting those it reads: a read cut short by its deadline
/// is taken up again by the next call (a reply is never read from its middle).
ChildRead read_some_from_child(const ChildProcess& child, char* data, std::size_t size, std::size_t& filled, double deadline);

/// Whether the child has ended (it is then a zombie until end_child reaps it).
bool child_ended(const ChildProcess& child);

/// Closes the parent's ends and ends the child: killed first with `kill_it`, else given `grace_seconds` to end by
/// itself (the end of its requests) and killed after them. Every process left in its group is killed before the
/// child is reaped. Returns what happened to it ("it crashed with signal 11 (Segmentation fault)").
std::string end_child(ChildProcess& child, bool kill_it, double grace_seconds);

/// The largest peak resident memory of the plugin children this process ended since reset_children_peak, in bytes.
std::size_t children_peak_bytes();
void reset_children_peak();

}  // namespace ccd::plugin
