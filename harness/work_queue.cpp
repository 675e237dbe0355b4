#include "harness/work_queue.hpp"

#include "ccd/config.hpp"
#include "core/error.hpp"
#include "strategies/backend.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <exception>
#include <filesystem>
#include <iostream>
#include <limits>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include <tbb/task_arena.h>

#include <unistd.h>
#include <csignal>

#if CCDBENCH_WITH_MPI
#include <mpi.h>
#endif

namespace ccd::harness {
namespace {

RankInfo g_ranks;
bool g_mpi_started = false;

/// Whether a launcher started this process as one rank of a job (OpenMPI's mpirun, or a PMI/PMIx launcher such as
/// srun). A plain `ccdbench` does not start MPI: a singleton MPI_Init would spawn OpenMPI's runtime for nothing.
bool launched_by_mpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"}) {
    if (const char* value = std::getenv(name); value && *value) return true;
  }
  return false;
}

/// The exit status main gives an exception (2: bad input, 1: anything else), and its text.
int exit_code_of(const std::exception_ptr& error, std::string& text) {
  try {
    std::rethrow_exception(error);
  } catch (const InputError& e) {
    text = e.what();
    return 2;
  } catch (const std::invalid_argument& e) {
    text = e.what();
    return 2;
  } catch (const std::filesystem::filesystem_error& e) {
    text = e.path1().string() + ": " + e.code().message();
    return 2;
  } catch (const std::bad_alloc&) {
    text = "out of memory: the input or a parameter asks for more than this machine has";
    return 2;
  } catch (const std::exception& e) {
    text = e.what();
    return 1;
  } catch (...) {
    text = "unknown exception";
    return 1;
  }
}

void run_in_plan_order(const std::vector<WorkItem>& items, const WorkFunction& work, const DoneFunction& done) {
  for (std::size_t i = 0; i < items.size(); ++i) {
    for (const std::size_t before : items[i].after) {
      if (before >= i) throw std::logic_error("work plan: item " + std::to_string(i) + " waits for a later item");
    }
    done(i, work(items[i].payload), 0);
  }
}

#if CCDBENCH_WITH_MPI

enum Tag : int { kRequest = 1, kFailure = 2, kAssign = 3, kStop = 4 };

/// How long an idle loop sleeps between polls: waiting in a blocking MPI call would spin a core that the rank's
/// own worker threads need (OpenMPI polls), and a millisecond is nothing beside an item's seconds.
constexpr auto kPollInterval = std::chrono::milliseconds(1);

void put_u64(std::string& buffer, std::uint64_t value) { buffer.append(reinterpret_cast<const char*>(&value), sizeof value); }

std::uint64_t get_u64(const std::string& buffer, std::size_t at) {
  std::uint64_t value = 0;
  if (buffer.size() < at + sizeof value) throw std::runtime_error("MPI work queue: a message is shorter than its header");
  std::memcpy(&value, buffer.data() + at, sizeof value);
  return value;
}

void send(int destination, int tag, const std::string& buffer) {
  if (buffer.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw std::runtime_error("MPI work queue: a message of " + std::to_string(buffer.size()) + " bytes exceeds MPI's int count");
  }
  MPI_Send(buffer.data(), static_cast<int>(buffer.size()), MPI_BYTE, destination, tag, MPI_COMM_WORLD);
}

struct Message {
  int source = 0, tag = 0;
  std::string bytes;
};

/// A message from `source` (MPI_ANY_SOURCE: anyone) if one has arrived.
std::optional<Message> poll(int source) {
  int arrived = 0;
  MPI_Status status;
  MPI_Iprobe(source, MPI_ANY_TAG, MPI_COMM_WORLD, &arrived, &status);
  if (!arrived) return std::nullopt;
  int count = 0;
  MPI_Get_count(&status, MPI_BYTE, &count);
  Message message{status.MPI_SOURCE, status.MPI_TAG, std::string(static_cast<std::size_t>(count), '\0')};
  MPI_Recv(message.bytes.data(), count, MPI_BYTE, status.MPI_SOURCE, status.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return message;
}

Message wait_for(int source) {
  for (;;) {
    if (auto message = poll(source)) return std::move(*message);
    std::this_thread::sleep_for(kPollInterval);
  }
}

/// A rank other than 0: asks for work, does it, sends the result with the next request, until told to stop.
void serve(const WorkFunction& work) {
  std::string request(1, '\0');  // first byte: whether a result follows
  for (;;) {
    send(0, kRequest, request);
    const Message message = wait_for(0);
    if (message.tag == kStop) return;
    const std::uint64_t index = get_u64(message.bytes, 0);
    try {
      const std::string result = work(message.bytes.substr(sizeof index));
      request.assign(1, '\1');
      put_u64(request, index);
      request += result;
    } catch (...) {
      std::string text;
      const int code = exit_code_of(std::current_exception(), text);
      std::string failure;
      put_u64(failure, static_cast<std::uint64_t>(code));
      failure += text;
      send(0, kFailure, failure);
      wait_for(0);  // rank 0 ends the run; it never answers
      return;
    }
  }
}

/// Rank 0's own worker: a thread fed through this channel by the thread that talks MPI.
struct LocalChannel {
  std::mutex mutex;
  std::condition_variable wake;
  std::optional<std::pair<std::size_t, std::string>> assignment, result;
  bool stop = false, wants_work = true;
  std::exception_ptr error;
};

void local_worker(LocalChannel& channel, const std::vector<WorkItem>& items, const WorkFunction& work) {
  for (;;) {
    std::size_t index = 0;
    {
      std::unique_lock lock(channel.mutex);
      channel.wake.wait(lock, [&] { return channel.stop || channel.assignment.has_value(); });
      if (!channel.assignment) return;
      index = channel.assignment->first;
      channel.assignment.reset();
    }
    try {
      std::string result = work(items[index].payload);
      std::lock_guard lock(channel.mutex);
      channel.result.emplace(index, std::move(result));
    } catch (...) {
      std::lock_guard lock(channel.mutex);
      channel.error = std::current_exception();
      return;
    }
  }
}

/// Hands `rank` (0: rank 0's own worker thread) its next item, or tells it to stop (nullopt).
void hand_out(int rank, const std::vector<WorkItem>& items, std::optional<std::size_t> item, LocalChannel& channel) {
  if (rank == 0) {
    std::lock_guard lock(channel.mutex);
    if (item) {
      channel.assignment.emplace(*item, std::string());
    } else {
      channel.stop = true;
    }
    channel.wake.notify_one();
  } else if (!item) {
    send(rank, kStop, {});
  } else {
    std::string assignment;
    put_u64(assignment, *item);
    assignment += items[*item].payload;
    send(rank, kAssign, assignment);
  }
}

void coordinate(const std::vector<WorkItem>& items, const WorkFunction& work, const DoneFunction& done) {
  // Each item waiting (not handed out yet), then running, then finished: what next_ready_item reads.
  std::vector<bool> waiting(items.size(), true), finished(items.size(), false);
  std::size_t unassigned = items.size();
  std::deque<int> idle;  // ranks asking for work; 0 is rank 0's own worker thread
  std::vector<std::optional<std::size_t>> last_group(static_cast<std::size_t>(g_ranks.size));  // of each rank's last item
  int stopped = 0;
  LocalChannel channel;
  std::thread local([&] { local_worker(channel, items, work); });
  // Results whose `done` (the outputs rank 0 writes: 10-30 ms a cell, more for the first) waits until the ranks that
  // asked have their next item: a rank never waits on another's outputs.
  struct Finished {
    std::size_t index;
    std::string result;
    int rank;
  };
  std::vector<Finished> results;
  // Each result to `done`, in order, each once: also before the run ends on an error, so that the cells finished
  // before it are written (a rerun does only the rest).
  auto write_results = [&] {
    while (!results.empty()) {
      const Finished result = std::move(results.front());
      results.erase(results.begin());
      done(result.index, result.result, result.rank);
    }
  };
  try {
    while (stopped < g_ranks.size) {
      bool progressed = false;
      while (auto message = poll(MPI_ANY_SOURCE)) {
        progressed = true;
        if (message->tag == kFailure) {
          const int code = static_cast<int>(get_u64(message->bytes, 0));
          std::cerr << "ccdbench: error: (rank " << message->source << ") " << message->bytes.substr(8) << '\n';
          write_results();
          RankSession::end_all_ranks(code);
        }
        if (message->bytes.at(0) == '\1') {
          const std::size_t index = get_u64(message->bytes, 1);
          finished.at(index) = true;
          results.push_back({index, message->bytes.substr(9), message->source});
        }
        idle.push_back(message->source);
      }
      std::exception_ptr local_error;
      {
        std::lock_guard lock(channel.mutex);
        local_error = channel.error;
        if (channel.result) {
          progressed = true;
          finished.at(channel.result->first) = true;
          results.push_back({channel.result->first, std::move(channel.result->second), 0});
          channel.result.reset();
          channel.wants_work = true;
        }
        if (channel.wants_work && !channel.assignment) {
          channel.wants_work = false;
          idle.push_back(0);
          progressed = true;
        }
      }
      if (local_error) {
        write_results();
        local.join();
        std::rethrow_exception(local_error);
      }
      for (auto rank = idle.begin(); rank != idle.end();) {
        const std::optional<std::size_t> item = next_ready_item(items, waiting, finished, last_group[static_cast<std::size_t>(*rank)]);
        if (!item && unassigned > 0) break;  // the rest waits for running items
        progressed = true;
        if (!item) {
          ++stopped;
        } else {
          waiting[*item] = false;
          --unassigned;
          last_group[static_cast<std::size_t>(*rank)] = items[*item].group;
        }
        hand_out(*rank, items, item, channel);
        rank = idle.erase(rank);
      }
      write_results();
      if (!progressed) std::this_thread::sleep_for(kPollInterval);
    }
  } catch (...) {
    // Rank 0 cannot go on handing out work. Joining the local worker would wait for its item (hours, on a large
    // cell) before anyone hears of the error: say it now and end every rank.
    std::string text;
    const int code = exit_code_of(std::current_exception(), text);
    std::cerr << "ccdbench: error: " << text << '\n';
    try {
      write_results();  // what finished before the error (one that `done` itself threw is no longer among them)
    } catch (...) {
    }
    RankSession::end_all_ranks(code);  // does not return: coordinate runs only with more than one rank
    std::abort();
  }
  local.join();
}

#endif

}  // namespace

std::optional<std::size_t> next_ready_item(const std::vector<WorkItem>& items, const std::vector<bool>& waiting, const std::vector<bool>& finished,
                                           std::optional<std::size_t> group) {
  std::optional<std::size_t> next;
  const auto in_group = [&](std::size_t i) { return group && items[i].group == group; };
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (!waiting[i]) continue;
    bool ready = true;
    for (const std::size_t before : items[i].after) ready = ready && finished.at(before);
    if (!ready) continue;
    if (!next || items[i].cost > items[*next].cost || (items[i].cost == items[*next].cost && in_group(i) && !in_group(*next))) next = i;
  }
  return next;
}

RankSession::RankSession(int& argc, char**& argv) {
#if CCDBENCH_WITH_MPI
  if (!launched_by_mpi()) return;
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  g_mpi_started = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &g_ranks.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &g_ranks.size);
  // The ranks of one node, from MPI itself (not a launcher's variable): they take the node's GPUs in turn.
  MPI_Comm node = MPI_COMM_NULL;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, g_ranks.rank, MPI_INFO_NULL, &node);
  MPI_Comm_rank(node, &g_ranks.node_rank);
  MPI_Comm_size(node, &g_ranks.node_size);
  MPI_Comm_free(&node);
  strategies::set_device_turn({g_ranks.node_rank, g_ranks.node_size});
  if (provided < MPI_THREAD_FUNNELED) {
    std::cerr << "ccdbench: error: this MPI library gives no thread support (MPI_THREAD_FUNNELED): rank 0's worker "
                 "thread could not run beside the thread that hands out work\n";
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
#else
  (void)argc;
  (void)argv;
#endif
}

RankSession::~RankSession() {
#if CCDBENCH_WITH_MPI
  if (g_mpi_started) MPI_Finalize();
#endif
}

void RankSession::end_all_ranks(int exit_code) {
#if CCDBENCH_WITH_MPI
  if (g_mpi_started && g_ranks.size > 1) {
    std::cout.flush();
    std::cerr.flush();
    MPI_Abort(MPI_COMM_WORLD, exit_code);
  }
#else
  (void)exit_code;
#endif
}

RankInfo rank_info() { return g_ranks; }

namespace {
char g_termination_message[4096];
volatile std::sig_atomic_t g_termination_length = 0;

extern "C" void on_terminate_signal(int signal) {
  // Only async-signal-safe calls here: write and _exit.
  if (g_termination_length > 0) {
    [[maybe_unused]] const auto written = ::write(STDERR_FILENO, g_termination_message, static_cast<std::size_t>(g_termination_length));
  }
  ::_exit(128 + signal);
}
}  // namespace

void say_on_termination(const std::string& message) {
  if (g_ranks.size <= 1 || g_ranks.rank != 0) return;
  g_termination_length = 0;  // never half a message: the handler reads the length last written
  const std::size_t length = std::min(message.size(), sizeof g_termination_message);
  std::memcpy(g_termination_message, message.data(), length);
  g_termination_length = static_cast<std::sig_atomic_t>(length);
  struct sigaction action {};
  action.sa_handler = on_terminate_signal;
  ::sigemptyset(&action.sa_mask);
  ::sigaction(SIGTERM, &action, nullptr);
}

void distribute(const std::vector<WorkItem>& items, const WorkFunction& work, const DoneFunction& done) {
#if CCDBENCH_WITH_MPI
  if (g_ranks.size > 1) {
    // OpenMPI binds each rank to one core unless told otherwise, and TBB then runs one thread in it.
    if (tbb::this_task_arena::max_concurrency() == 1 && ::sysconf(_SC_NPROCESSORS_ONLN) > 1) {
      std::cerr << "ccdbench: warning: rank " << g_ranks.rank << " may use one core of " << ::sysconf(_SC_NPROCESSORS_ONLN)
                << " (mpirun binds ranks to cores by default): launch with "
                << "--bind-to none to give each rank its --threads\n";
    }
    if (g_ranks.rank == 0) {
      coordinate(items, work, done);
    } else {
      serve(work);
    }
    return;
  }
#endif
  run_in_plan_order(items, work, done);
}

std::string mpi_library_version() {
#if CCDBENCH_WITH_MPI
  // Callable before MPI_Init (MPI 3.0 §8.1.1).
  char text[MPI_MAX_LIBRARY_VERSION_STRING] = {};
  int length = 0;
  if (MPI_Get_library_version(text, &length) != MPI_SUCCESS) return "unknown";
  std::string version(text, static_cast<std::size_t>(length));
  // The first line names the library and its version; the rest is its build's configuration.
  return version.substr(0, version.find_first_of(",\n"));
#else
  return "";
#endif
}

}  // namespace ccd::harness
