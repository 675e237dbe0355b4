// The child's side of an isolated plugin (isolation.hpp): `ccdbench plugin-host ...`, started by the parent, loads the
// plugin and answers the parent's requests (child_protocol.hpp), or describes the plugin and exits.
#include "ccd/config.hpp"
#include "strategies/plugin/child_protocol.hpp"
#include "strategies/plugin/isolation.hpp"
#include "strategies/plugin/query_batch.hpp"

#include <poll.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <thread>

namespace ccd::plugin {

using namespace child_protocol;

namespace {

/// The child's collected contacts of a step, as sent back.
struct StepReply {
  std::vector<char> vertex_face, edge_edge;
  std::uint64_t vertex_face_count = 0, edge_edge_count = 0;
};

/// Ends the process group this child was started to lead (itself and whatever the plugin started in it), and
/// itself. Async-signal-safe. The group is named by this process's id, never as "the caller's group" (kill(0)):
/// another thread may just have moved this process into its parent's group (end_rest_of_group).
void end_own_group(int status = 3) {
  ::kill(-::getpid(), SIGKILL);
  // The system call itself: the program's _exit is interposed, and a lookup there could wait for ever on the
  // loader's lock, which a plugin whose constructor hangs inside dlopen holds.
  ::syscall(SYS_exit_group, status);
}

/// Whether the parent is gone: the lifeline's only writer was the parent (its end is close-on-exec), which never
/// writes, so the pipe is readable only once that end is closed. Async-signal-safe.
bool parent_gone() {
  pollfd lifeline{kLifelineFd, POLLIN, 0};
  return ::poll(&lifeline, 1, 0) > 0;
}

/// Ends every other process of the group this child leads (what the plugin started), and leaves this one to end with
/// its own status, which the parent reads: it moves into its parent's group first (the same session), then kills the
/// group it led. Where it cannot move, the whole group ends, this process with it.
void end_rest_of_group() {
  const pid_t self = ::getpid();
  if (::getpgrp() != self) return;
  const pid_t parents_group = ::getpgid(::getppid());
  if (parents_group < 0 || ::setpgid(0, parents_group) != 0) end_own_group();
  ::kill(-self, SIGKILL);
}

/// The signal the kernel sends when the parent dies (PR_SET_PDEATHSIG): caught to end the whole group, where SIGKILL
/// would end the child alone and leave what the plugin started running.
const int kParentDeathSignal = SIGRTMIN + 1;

/// Ends the child's group when its parent is gone, even while the plugin hangs in a call on the main thread: the
/// kernel's parent-death signal, and a thread watching the lifeline (a plugin can change a signal's handler, or stop
/// a thread, but not both by accident).
void watch_the_parent() {
#if CCDBENCH_GUARD_LIFELINE
  struct sigaction ending {};
  ending.sa_handler = [](int) { end_own_group(); };
  ::sigaction(kParentDeathSignal, &ending, nullptr);
  ::prctl(PR_SET_PDEATHSIG, kParentDeathSignal);
  // A parent that died before the line above sends no signal; the thread below would notice, but only when it is
  // scheduled, and under load this process could load the plugin (whose constructor may fork) and end first.
  if (parent_gone()) end_own_group();
  std::thread([] {
    pollfd lifeline{kLifelineFd, POLLIN, 0};
    while (::poll(&lifeline, 1, -1) < 0 && errno == EINTR) {
    }
    end_own_group();
  }).detach();
#endif
}

/// Whether this process is a copy of the child that the plugin forked (fork, or clone without CLONE_VM): a page the
/// child marks at its start is zero in any such copy (MADV_WIPEONFORK, Linux 4.14), which costs no system call per
/// plugin call (Debian 12's glibc makes one of getpid). Where the kernel refuses the advice, the process id the child
/// had at its start is compared instead.
pid_t g_child_pid = 0;
volatile std::uint64_t* g_original_mark = nullptr;

void mark_the_original() {
  g_child_pid = ::getpid();
  const auto page_size = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
  void* page = ::mmap(nullptr, page_size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (page == MAP_FAILED) return;
  if (::madvise(page, page_size, MADV_WIPEONFORK) != 0) {
    ::munmap(page, page_size);
    return;
  }
  g_original_mark = static_cast<volatile std::uint64_t*>(page);
  *g_original_mark = 1;
}

/// A copy of this child that the plugin forked (a fork whose copy returns, as a careless fork/exec does) ends here,
/// before it writes a reply or an answer or reads a request: it would answer on this child's pipes and in its batch
/// memory beside it, and a reply it wrote late (after the run read its last) would go unseen. Called after every
/// call into the plugin, its load included. The system call itself, as in end_own_group: the copy ends alone (the
/// group is this child's), without exit handlers. It stays a zombie until the child ends: the child reaping it could
/// take a process the plugin itself waits for.
void end_if_a_copy() {
#if CCDBENCH_GUARD_FORK
  const bool copy = g_original_mark != nullptr ? *g_original_mark == 0 : ::getpid() != g_child_pid;
  if (copy) ::syscall(SYS_exit_group, 0);
#endif
}

/// Describes the plugin: its description as the payload, or a refusal with its whole text as the payload.
int describe_plugin(const char* path) {
  std::vector<char> reply;
  try {
    const Library library(path);
    end_if_a_copy();
    const std::vector<char> description = encode(library.description());
    reply = status_reply(0, "");
    put(reply, static_cast<std::uint64_t>(description.size()));
    reply.insert(reply.end(), description.begin(), description.end());
  } catch (const std::exception& error) {
    const std::string why = error.what();
    reply = status_reply(1, why.c_str());
    put(reply, static_cast<std::uint64_t>(why.size()));
    reply.insert(reply.end(), why.begin(), why.end());
  }
  return write_all(kReplyFd, reply.data(), reply.size()) ? 0 : 1;
}

/// A call into the plugin as the child makes it, held to what an in-process call is held to: a C++ exception
/// thrown through its C functions, or a floating-point environment left otherwise than its load left it, is the
/// call's error (the environment is put back), so that a plugin gets the same verdicts isolated as in-process.
template <class Call>
std::string child_call(const Library& library, Call&& call) {
  std::string fault;
  try {
    call();
  } catch (const std::exception& error) {
    fault = std::string("it threw a C++ exception through the C ABI: ") + error.what();
  } catch (...) {
    fault = "it threw an exception through the C ABI";
  }
  end_if_a_copy();
#if CCDBENCH_GUARD_FENV
  const FpEnvironment after = FpEnvironment::current();
  if (after != library.environment()) {
    library.environment().install();
    const std::string change = "it left the floating-point environment changed: " + describe_change(library.environment(), after);
    fault = fault.empty() ? change : fault + "; " + change;
  }
#else
  (void)library;
#endif
  return fault;
}

/// One query, answered in the child: no outcome until the plugin writes one, so a plugin that writes none is caught
/// here too, not taken for "apart"; a fault of the call is its answer.
ccdbench_answer answer_query(const Library& library, void* context, bool vertex_face, const double* rows, double thickness) {
  ccdbench_answer answer{};
  answer.outcome = -1;
  answer.toi = std::nan("");
  const std::string fault =
      child_call(library, [&] { (vertex_face ? library.table().vertex_face : library.table().edge_edge)(context, rows, thickness, &answer); });
  if (!fault.empty()) {
    answer.outcome = CCDBENCH_ERROR;
    std::snprintf(answer.message, CCDBENCH_MESSAGE_SIZE, "%s", fault.c_str());
  }
  answer.message[CCDBENCH_MESSAGE_SIZE - 1] = '\0';
  return answer;
}

/// A call's fault as its status and message: 1 and the fault where there is one.
void take_fault(const std::string& fault, int& status, char* message) {
  if (fault.empty()) return;
  status = 1;
  std::snprintf(message, CCDBENCH_MESSAGE_SIZE, "%s", fault.c_str());
}

/// The child's requests served, one at a time, until the parent closes the pipe: each reply carries the number of the
/// request it answers, in one write with the reply.
class Server {
 public:
  Server(const Library& library, void* context) : library_(library), context_(context) {}

  /// Serves until the requests end (0) or one cannot be read or answered (1); destroys the context at the end.
  int run() {
    for (char kind = 0; read_all(kRequestFd, &kind, 1);) {
      if (!read_all(kRequestFd, reinterpret_cast<char*>(&sequence_), sizeof sequence_)) return 1;
      const bool served = kind == kBatch   ? batch()
                          : kind == kQuery ? query()
                          : kind == kBegin ? begin()
                          : kind == kStep  ? step()
                                           : kind == kEnd && end();
      if (!served) return 1;
    }
    child_call(library_, [&] { library_.table().destroy(context_); });
    return 0;
  }

 private:
  bool reply(const std::vector<char>& reply) {
    std::vector<char> numbered;
    put(numbered, sequence_);
    numbered.insert(numbered.end(), reply.begin(), reply.end());
    return write_all(kReplyFd, numbered.data(), numbered.size());
  }

  /// Queries in the shared memory: each answer stamped with the batch's number and counted done as it is written.
  bool batch() {
    std::uint64_t count = 0;
    if (!read_all(kRequestFd, reinterpret_cast<char*>(&count), sizeof count) || count > kBatchCapacity) return false;
    if (!region_) region_.emplace(BatchRegion::open(kBatchFd));
    for (std::uint64_t k = 0; k < count; ++k) {
      const BatchQuery query = region_->queries()[k];
      const ccdbench_answer answer = answer_query(library_, context_, query.vertex_face != 0, query.rows, query.thickness);
      BatchAnswer& out = region_->answers()[k];
      out.outcome = answer.outcome;
      out.batch = static_cast<std::uint32_t>(sequence_);
      out.toi = answer.toi;
      std::memcpy(out.message, answer.message, CCDBENCH_MESSAGE_SIZE);
      region_->set_done(k + 1);
    }
    return reply({kBatchDone});
  }

  bool query() {
    char payload[1 + 25 * sizeof(double)];
    if (!read_all(kRequestFd, payload, sizeof payload)) return false;
    const char* at = payload;
    const bool vertex_face = take<std::uint8_t>(at) != 0;
    double rows[24];
    std::memcpy(rows, at, sizeof rows);
    at += sizeof rows;
    const double thickness = take<double>(at);
    const ccdbench_answer answer = answer_query(library_, context_, vertex_face, rows, thickness);
    std::vector<char> answered = status_reply(answer.outcome, answer.message);
    put(answered, answer.toi);
    return reply(answered);
  }

  /// The scene, kept for the step calls.
  bool begin() {
    auto read_array = [&](auto& out) {
      std::uint64_t count = 0;
      if (!read_all(kRequestFd, reinterpret_cast<char*>(&count), sizeof count)) return false;
      out.resize(count);
      return read_all(kRequestFd, reinterpret_cast<char*>(out.data()), count * sizeof(out[0]));
    };
    std::uint64_t vertices = 0;
    if (!read_all(kRequestFd, reinterpret_cast<char*>(&vertices), sizeof vertices) || !read_array(faces_) || !read_array(edges_) ||
        !read_array(face_object_) || !read_array(self_) || !read_array(collidable_)) {
      return false;
    }
    scene_ = {vertices,     faces_.size() / 3,   faces_.data(), edges_.size() / 2,      edges_.data(),
              self_.size(), face_object_.data(), self_.data(),  collidable_.size() / 2, collidable_.data()};
    char message[CCDBENCH_MESSAGE_SIZE] = {};
    int status = 0;
    if (library_.table().begin)
      take_fault(child_call(library_, [&] { status = library_.table().begin(context_, &scene_, message); }), status, message);
    message[CCDBENCH_MESSAGE_SIZE - 1] = '\0';
    return reply(status_reply(status, message));
  }

  bool step() {
    std::uint64_t index = 0, vertices = 0;
    double thickness = 0;
    if (!read_all(kRequestFd, reinterpret_cast<char*>(&index), sizeof index) ||
        !read_all(kRequestFd, reinterpret_cast<char*>(&thickness), sizeof thickness) ||
        !read_all(kRequestFd, reinterpret_cast<char*>(&vertices), sizeof vertices)) {
      return false;
    }
    std::vector<double> x0(3 * vertices), x1(3 * vertices);
    if (!read_all(kRequestFd, reinterpret_cast<char*>(x0.data()), x0.size() * sizeof(double)) ||
        !read_all(kRequestFd, reinterpret_cast<char*>(x1.data()), x1.size() * sizeof(double))) {
      return false;
    }
    StepReply collected;
    ccdbench_contacts contacts{&collected,
                               [](void* host, std::uint32_t v, std::uint32_t f, double toi) {
                                 auto* out = static_cast<StepReply*>(host);
                                 put(out->vertex_face, v);
                                 put(out->vertex_face, f);
                                 put(out->vertex_face, toi);
                                 ++out->vertex_face_count;
                               },
                               [](void* host, std::uint32_t a0, std::uint32_t a1, std::uint32_t b0, std::uint32_t b1, double toi) {
                                 auto* out = static_cast<StepReply*>(host);
                                 for (std::uint32_t v : {a0, a1, b0, b1}) put(out->edge_edge, v);
                                 put(out->edge_edge, toi);
                                 ++out->edge_edge_count;
                               }};
    const ccdbench_step request{index, x0.data(), x1.data(), thickness};
    char message[CCDBENCH_MESSAGE_SIZE] = {};
    int status = 0;
    take_fault(child_call(library_, [&] { status = library_.table().step(context_, &request, &contacts, message); }), status, message);
    message[CCDBENCH_MESSAGE_SIZE - 1] = '\0';
    std::vector<char> answered = status_reply(status, message);
    put(answered, collected.vertex_face_count);
    answered.insert(answered.end(), collected.vertex_face.begin(), collected.vertex_face.end());
    put(answered, collected.edge_edge_count);
    answered.insert(answered.end(), collected.edge_edge.begin(), collected.edge_edge.end());
    return reply(answered);
  }

  bool end() {
    if (library_.table().end) child_call(library_, [&] { library_.table().end(context_); });
    return reply(status_reply(0, ""));
  }

  const Library& library_;
  void* context_;
  std::vector<std::uint32_t> faces_, edges_, face_object_, collidable_;
  std::vector<std::uint8_t> self_;
  ccdbench_scene scene_{};
  std::optional<BatchRegion> region_;
  std::uint64_t sequence_ = 0;
};

/// The child's work: describes the plugin, or loads it and serves the parent's requests. Its exit status.
int serve(int argc, char** argv) {
  // Whatever the plugin prints goes to the standard error (never into ccdbench's own output, which a script may be
  // reading); its answers go to fd 4 alone.
  ::dup2(STDERR_FILENO, STDOUT_FILENO);
  if (std::string(argv[2]) == "--describe") return argc == 4 ? describe_plugin(argv[3]) : 2;
  // PATH DIGEST N (OBJECT OBJECT_DIGEST) x N VALUE...
  if (argc < 5) return 2;
  const std::string expected_digest = argv[3];
  const std::size_t object_count = std::strtoull(argv[4], nullptr, 10);
  if (object_count > static_cast<std::size_t>(argc - 5) / 2) return 2;
  std::vector<LoadedObject> expected;
  for (std::size_t k = 0; k < object_count; ++k) expected.push_back({argv[5 + 2 * k], argv[6 + 2 * k]});
  auto greet = [&](std::int32_t status, const std::string& message, const std::string& digest) {
    std::vector<char> greeting = status_reply(status, message.c_str());
    greeting.insert(greeting.end(), digest.begin(), digest.end());
    greeting.resize(kGreetingSize, '0');
    return write_all(kReplyFd, greeting.data(), greeting.size());
  };
  // Before anything of it is loaded (a constructor runs at load): its files must hold the run's bytes.
  if (const std::string differs = differs_on_disk(expected); !differs.empty()) {
    greet(kChangedStatus, differs, std::string(kDigestSize, '0'));
    return 1;
  }
  std::unique_ptr<Library> loaded;
  try {
    loaded = std::make_unique<Library>(argv[2]);
    end_if_a_copy();
  } catch (const std::exception& error) {
    std::vector<char> greeting = status_reply(kUnloadableStatus, error.what());
    greeting.resize(kGreetingSize, '0');
    write_all(kReplyFd, greeting.data(), greeting.size());
    return 1;
  }
  const Library& library = *loaded;
  // The plugin runs in its own process: the environment its load left stays its own (as in-process calls get it).
  library.environment().install();
  // And as loaded: the objects that came in are those the run digested, as they were (the files may have changed
  // between the check above and the load). "-": none asked.
  const std::string& digest = library.description().digest;
  if (expected_digest != "-") {
    const std::string differs = differs_from_loaded(expected, library.description().objects);
    if (!differs.empty()) {
      greet(kChangedStatus, differs, digest);
      return 1;
    }
  }
  std::vector<std::string> values(argv + 5 + 2 * object_count, argv + argc);
  std::vector<const char*> pointers;
  for (const std::string& value : values) pointers.push_back(value.c_str());
  char error[CCDBENCH_MESSAGE_SIZE] = {};
  void* context = nullptr;
  // Held to what an in-process create is held to (a floating-point environment left changed, an exception): its
  // fault refuses the plugin, as in-process, where it would otherwise be blamed on its first query.
  const std::string create_fault = child_call(library, [&] { context = library.table().create(pointers.data(), error); });
  if (!create_fault.empty()) {
    if (context != nullptr) child_call(library, [&] { library.table().destroy(context); });
    greet(kCreateFailedStatus, create_fault, digest);
    return 1;
  }
  error[CCDBENCH_MESSAGE_SIZE - 1] = '\0';
  if (!greet(context != nullptr ? 0 : 1, context != nullptr ? "" : error, digest) || context == nullptr) return 1;
  return Server(library, context).run();
}

}  // namespace

int serve_plugin(int argc, char** argv) {
  if (argc < 3) return 2;
  // This process runs the plugin, and nothing here is ccdbench's own work to guard: its exits are its own.
  set_plugin_host_process();
  mark_the_original();
  watch_the_parent();
  const int status = serve(argc, argv);
#if CCDBENCH_GUARD_LIFELINE
  // Whatever the plugin started in this group ends here, before this process does: the parent ends the group too
  // once this process has ended (end_child), but a parent killed between the two (kill -9 of ccdbench, which may
  // come just as it ends a child) would leave it running with nobody to end it.
  if (parent_gone()) end_own_group(status);
  end_rest_of_group();
#endif
  return status;
}

}  // namespace ccd::plugin
