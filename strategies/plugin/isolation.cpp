#include "strategies/plugin/isolation.hpp"

#include "ccd/config.hpp"
#include "strategies/plugin/child_protocol.hpp"
#include "strategies/plugin/query_batch.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

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

namespace {}  // namespace

namespace {

/// A child of this program, `PROGRAM plugin-host ARGUMENTS...`, with its request pipe on fd 3, its reply pipe on
/// fd 4 and the lifeline on fd 5; the parent's ends are close-on-exec, so that no other child holds them.
struct Child {
  pid_t pid = -1;
  int to_child = -1, from_child = -1, lifeline = -1;
};

Child spawn_child(const std::vector<std::string>& plugin_host_arguments, int batch_fd = -1) {
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
  // The child leads a process group of its own, so that killing it kills what it started too (unless that left the
  // group on purpose).
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  if (prepared == 0) prepared = posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
  if (prepared == 0) prepared = posix_spawnattr_setpgroup(&attributes, 0);
  Child child;
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
    for (int fd : {child.to_child, child.from_child, child.lifeline}) ::close(fd);
    throw std::runtime_error("plugin isolation: cannot start a child process: " + std::string(std::strerror(spawned)));
  }
  return child;
}

/// Reaps a child; what happened to it, in words.
std::string reap(pid_t pid, bool kill_it) {
  if (kill_it) ::kill(-pid, SIGKILL);  // its process group: the child and what it started
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFSIGNALED(status)) {
    return "it crashed with signal " + std::to_string(WTERMSIG(status)) + " (" + ::strsignal(WTERMSIG(status)) + ")";
  }
  if (WIFEXITED(status)) return "its process exited with status " + std::to_string(WEXITSTATUS(status));
  return "its process ended";
}

/// Reads exactly `size` bytes from `fd` before `deadline` (seconds, steady clock); false at the end of the stream,
/// an error, or the deadline (`timed_out` then says so).
bool read_until(int fd, char* data, std::size_t size, double deadline, bool& timed_out) {
  timed_out = false;
  while (size > 0) {
    const double left = deadline - now_seconds();
    pollfd ready{fd, POLLIN, 0};
    const int polled = left > 0 ? ::poll(&ready, 1, static_cast<int>(std::ceil(left * 1000))) : 0;
    if (polled < 0 && errno == EINTR) continue;
    if (polled == 0) {
      timed_out = true;
      return false;
    }
    const ssize_t n = ::read(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

/// A description's reply is at most this long: a table with a thousand keys of long help texts fits many times.
constexpr std::uint64_t kMaxDescriptionBytes = 16u << 20;

}  // namespace

PluginDescription describe_in_child(const std::string& given) {
  std::error_code error;
  const std::filesystem::path absolute = std::filesystem::weakly_canonical(std::filesystem::absolute(given), error);
  const std::string path = (error ? std::filesystem::absolute(given) : absolute).string();
  if (!std::filesystem::is_regular_file(path)) throw std::invalid_argument("plugin " + path + ": no such file");
  // A broken pipe is an answer here (the child died), never a reason for this process to die.
  ::signal(SIGPIPE, SIG_IGN);
  Child child = spawn_child({"--describe", path});
  const double deadline = now_seconds() + kLoadSeconds;
  char head[kStatusSize + sizeof(std::uint64_t)];
  bool timed_out = false;
  std::string failure;
  std::string bytes;
  if (read_until(child.from_child, head, sizeof head, deadline, timed_out)) {
    const char* at = head;
    const auto status = take<std::int32_t>(at);
    const std::string message(at, strnlen(at, CCDBENCH_MESSAGE_SIZE));
    at += CCDBENCH_MESSAGE_SIZE;
    const auto size = take<std::uint64_t>(at);
    // The payload is the description, or a refusal's whole text (the status message holds only its start).
    if (size > kMaxDescriptionBytes) {
      failure = "its child process sent a reply of " + std::to_string(size) + " bytes";
    } else {
      bytes.resize(size);
      if (!read_until(child.from_child, bytes.data(), size, deadline, timed_out)) {
        failure = "its child process stopped while describing it";
      } else if (status != 0) {
        failure = !bytes.empty() ? bytes : message.empty() ? "it was refused" : message;
      }
    }
  } else {
    failure = "its child process ended while loading it";
  }
  for (int fd : {child.to_child, child.from_child, child.lifeline}) ::close(fd);
  const std::string ended = reap(child.pid, timed_out);
  if (timed_out) {
    throw std::invalid_argument("plugin " + path + ": loading it did not finish within " + narrowphase::format_spec_number(kLoadSeconds) + " s");
  }
  if (!failure.empty()) {
    // A refusal names the plugin already; a child that died says how.
    if (failure.rfind("plugin ", 0) == 0) throw std::invalid_argument(failure);
    throw std::invalid_argument("plugin " + path + ": " + failure + " (" + ended + ")");
  }
  return decode_description(path, bytes);
}

PluginInstance::PluginInstance(const PluginDescription& description_, const narrowphase::SpecReader& keys)
    : description(description_), values(plugin_values(keys, description)), host(read_host_settings(keys, description)) {
  if (host.isolate) {
    isolated = std::make_unique<IsolatedPlugin>(description, values, host.timeout_seconds, host.batch);
  } else {
    library = load_library(description);
    context = std::make_unique<Context>(library, values, host.timeout_seconds);
  }
}

std::string PluginInstance::name() const { return resolved_name(description, values, host); }

std::vector<std::pair<std::string, std::string>> PluginInstance::provenance() const {
  std::vector<std::pair<std::string, std::string>> notes{{"plugin", description.table.name + " " + description.table.version},
                                                         {"plugin_digest", description.digest}};
  std::string objects;
  for (const LoadedObject& object : description.objects) objects += (objects.empty() ? "" : "; ") + object.path + " " + object.digest;
  notes.emplace_back("plugin_objects", objects);
  notes.emplace_back("plugin_isolated", host.isolate ? "yes (a child process)" : "no (in-process)");
  if (!description.environment_at_load.empty()) notes.emplace_back("plugin_environment_at_load", description.environment_at_load);
  return notes;
}

IsolatedPlugin::IsolatedPlugin(const PluginDescription& description, std::vector<std::string> values, double timeout_seconds, std::size_t batch)
    : path_(description.path),
      digest_(description.digest),
      objects_(description.objects),
      values_(std::move(values)),
      timeout_seconds_(timeout_seconds),
      batch_(std::clamp<std::size_t>(batch, 1, kBatchCapacity)) {
  // A broken pipe is an answer here (the child died), never a reason for this process to die.
  ::signal(SIGPIPE, SIG_IGN);
  if (batch_ > 1) region_ = std::make_unique<BatchRegion>(BatchRegion::create());
}

IsolatedPlugin::~IsolatedPlugin() {
  if (child_ > 0) stop(false);
}

bool IsolatedPlugin::start(std::string& why) {
  // PATH DIGEST N (OBJECT OBJECT_DIGEST) x N VALUE...: the child loads nothing that is not the run's code.
#if CCDBENCH_GUARD_CHILD_IDENTITY
  std::vector<std::string> arguments{path_, digest_, std::to_string(objects_.size())};
  for (const LoadedObject& object : objects_) arguments.insert(arguments.end(), {object.path, object.digest});
#else
  std::vector<std::string> arguments{path_, "-", "0"};
#endif
  arguments.insert(arguments.end(), values_.begin(), values_.end());
  const Child child = spawn_child(arguments, region_ ? region_->fd() : -1);
  child_ = child.pid;
  to_child_ = child.to_child;
  from_child_ = child.from_child;
  lifeline_ = child.lifeline;
  std::vector<char> greeting;
  deadline_ = now_seconds() + timeout_seconds_ + 10;  // loading and configuring may take longer than one query
  if (!read_more(greeting, kGreetingSize, why)) {
    why = "its child process did not start: " + why;
    return false;
  }
  const char* at = greeting.data();
  const auto status = take<std::int32_t>(at);
  const std::string message(at, strnlen(at, CCDBENCH_MESSAGE_SIZE));
  if (status == kChangedStatus) {
    stop(true);
    changed_ = "its code changed during the run (" + message + "; the run's digest is " + digest_ +
               "): the plugin or a library it loads was replaced or rebuilt, and no answer of other code stands for the run's";
    why = changed_;
    return false;
  }
  if (status == kUnloadableStatus) {
    stop(true);
    changed_ = "a child started again could not load it any more (" + message + "): it changed during the run";
    why = changed_;
    return false;
  }
  if (status != 0) {
    stop(true);
    throw std::invalid_argument("plugin " + path_ + ": its configuration was refused: " + (message.empty() ? "no reason given" : message));
  }
  return true;
}

std::string IsolatedPlugin::stop(bool kill_it) {
  for (int* fd : {&to_child_, &from_child_, &lifeline_}) {
    if (*fd >= 0) ::close(*fd);
    *fd = -1;
  }
  if (child_ <= 0) return "it was not running";
  const std::string ended = reap(child_, kill_it);
  child_ = -1;
  return ended;
}

bool IsolatedPlugin::read_more(std::vector<char>& reply, std::size_t size, std::string& why) {
  const std::size_t start = reply.size();
  reply.resize(start + size);
  bool timed_out = false;
  if (read_until(from_child_, reply.data() + start, size, deadline_, timed_out)) return true;
  if (timed_out) {
    stop(true);
    why = "it did not answer within its timeout of " + narrowphase::format_spec_number(timeout_seconds_) + " s (killed)";
  } else {
    why = stop(false);
  }
  return false;
}

bool IsolatedPlugin::exchange(const std::vector<char>& request, std::vector<char>& reply, std::size_t reply_size, std::string& why) {
  if (!changed_.empty()) {
    why = changed_;
    return false;
  }
  if (child_ <= 0) {
    // A child that dies while starting (the plugin's constructor or create crashed) is this request's error.
    if (!start(why)) return false;
    if (!scene_request_.empty() && request.front() != kBegin && !send_scene(why)) return false;
  }
  deadline_ = now_seconds() + timeout_seconds_;
  if (!write_all(to_child_, request.data(), request.size())) {
    why = stop(false);
    return false;
  }
  reply.clear();
  return read_more(reply, reply_size, why);
}

bool IsolatedPlugin::send_scene(std::string& message) {
  std::vector<char> reply;
  deadline_ = now_seconds() + timeout_seconds_;
  if (!write_all(to_child_, scene_request_.data(), scene_request_.size())) {
    message = stop(false);
    return false;
  }
  if (!read_more(reply, kStatusSize, message)) return false;
  const char* at = reply.data();
  if (take<std::int32_t>(at) != 0) {
    message = "begin failed again after a restart: " + std::string(at, strnlen(at, CCDBENCH_MESSAGE_SIZE));
    return false;
  }
  return true;
}

ccdbench_answer IsolatedPlugin::query(bool vertex_face, const double* rows, double thickness) {
  std::lock_guard lock(mutex_);
  std::vector<char> request{kQuery};
  put(request, static_cast<std::uint8_t>(vertex_face ? 1 : 0));
  for (int i = 0; i < 24; ++i) put(request, rows[i]);
  put(request, thickness);
  ccdbench_answer answer{};
  answer.toi = std::nan("");
  std::vector<char> reply;
  std::string why;
  if (!exchange(request, reply, kStatusSize + sizeof(double), why)) {
    answer.outcome = CCDBENCH_ERROR;
    std::strncpy(answer.message, ("isolated: " + why).c_str(), CCDBENCH_MESSAGE_SIZE - 1);
    return answer;
  }
  const char* at = reply.data();
  answer.outcome = take<std::int32_t>(at);
  std::memcpy(answer.message, at, CCDBENCH_MESSAGE_SIZE);
  at += CCDBENCH_MESSAGE_SIZE;
  answer.toi = take<double>(at);
  return answer;
}

std::vector<ccdbench_answer> IsolatedPlugin::queries(const std::vector<Query>& asked) {
  std::vector<ccdbench_answer> answers(asked.size());
  if (!region_) {
    for (std::size_t q = 0; q < asked.size(); ++q) answers[q] = query(asked[q].vertex_face, asked[q].rows, asked[q].thickness);
    return answers;
  }
  std::lock_guard lock(mutex_);
  auto error = [](ccdbench_answer& answer, const std::string& why) {
    answer = {};
    answer.outcome = CCDBENCH_ERROR;
    answer.toi = std::nan("");
    std::strncpy(answer.message, ("isolated: " + why).c_str(), CCDBENCH_MESSAGE_SIZE - 1);
  };
  for (std::size_t next = 0; next < asked.size();) {
    std::string why;
    if (!changed_.empty()) {
      error(answers[next++], changed_);
      continue;
    }
    // A child that dies while starting is the error of the query it was started for.
    if (child_ <= 0 && !start(why)) {
      error(answers[next++], why);
      continue;
    }
    const std::size_t count = std::min(batch_, asked.size() - next);
    const std::size_t answered = batch(asked, next, count, answers, why);
    next += answered;
    // The query the child died or hung on is that query's error; the rest go to a fresh child.
    if (answered < count) error(answers[next++], why);
  }
  return answers;
}

std::size_t IsolatedPlugin::batch(const std::vector<Query>& asked, std::size_t first, std::size_t count, std::vector<ccdbench_answer>& answers,
                                  std::string& why) {
  for (std::size_t k = 0; k < count; ++k) {
    BatchQuery& query = region_->queries()[k];
    std::memcpy(query.rows, asked[first + k].rows, sizeof query.rows);
    query.thickness = asked[first + k].thickness;
    query.vertex_face = asked[first + k].vertex_face ? 1 : 0;
  }
  region_->set_done(0);
  std::vector<char> request{kBatch};
  put(request, static_cast<std::uint64_t>(count));
  bool finished = false;
  if (!write_all(to_child_, request.data(), request.size())) {
    why = stop(false);
  } else {
    // Each query has its own timeout: the deadline moves on with every answer the child counts done.
    std::uint64_t seen = 0;
    double deadline = now_seconds() + timeout_seconds_;
    while (true) {
      const double left = deadline - now_seconds();
      if (left <= 0) {
        why = "it did not answer within its timeout of " + narrowphase::format_spec_number(timeout_seconds_) + " s (killed)";
        stop(true);
        break;
      }
      pollfd ready{from_child_, POLLIN, 0};
      const int polled = ::poll(&ready, 1, static_cast<int>(std::ceil(std::min(left, 0.1) * 1000)));
      if (polled < 0 && errno != EINTR) {
        why = stop(true);
        break;
      }
      if (polled > 0) {
        char done = 0;
        const ssize_t n = ::read(from_child_, &done, 1);
        if (n < 0 && errno == EINTR) continue;
        if (n == 1 && done == kBatchDone) {
          finished = true;
        } else {
          why = n == 1 ? "its reply was not one (killed)" : "";
          const std::string ended = stop(n == 1);
          if (why.empty()) why = ended;
        }
        break;
      }
      if (const std::uint64_t now_done = region_->done(); now_done != seen) {
        seen = now_done;
        deadline = now_seconds() + timeout_seconds_;
      }
    }
  }
  // What the child counted done, never more than was asked; on a clean finish, every query.
  const std::size_t answered = finished ? count : std::min<std::size_t>(region_->done(), count);
  for (std::size_t k = 0; k < answered; ++k) {
    const BatchAnswer& in = region_->answers()[k];
    ccdbench_answer& out = answers[first + k];
    out.outcome = in.outcome;
    out.toi = in.toi;
    std::memcpy(out.message, in.message, CCDBENCH_MESSAGE_SIZE);
    out.message[CCDBENCH_MESSAGE_SIZE - 1] = '\0';
  }
  return answered;
}

int IsolatedPlugin::begin(const ccdbench_scene& scene, std::string& message) {
  std::lock_guard lock(mutex_);
  // A reply may claim no more contacts than the mesh has pairs: a larger count is refused before any is read.
  most_vertex_face_ = static_cast<std::uint64_t>(scene.vertex_count) * scene.face_count;
  most_edge_edge_ = static_cast<std::uint64_t>(scene.edge_count) * scene.edge_count;
  scene_request_ = {kBegin};
  put(scene_request_, static_cast<std::uint64_t>(scene.vertex_count));
  put_array(scene_request_, scene.faces, 3 * scene.face_count);
  put_array(scene_request_, scene.edges, 2 * scene.edge_count);
  put_array(scene_request_, scene.face_object, scene.face_count);
  put_array(scene_request_, scene.object_self_collision, scene.object_count);
  put_array(scene_request_, scene.collidable, 2 * scene.collidable_count);
  std::vector<char> reply;
  if (!exchange(scene_request_, reply, kStatusSize, message)) return 1;
  const char* at = reply.data();
  const std::int32_t status = take<std::int32_t>(at);
  message.assign(at, strnlen(at, CCDBENCH_MESSAGE_SIZE));
  return status;
}

int IsolatedPlugin::step(const ccdbench_step& step, std::size_t vertex_count, const ccdbench_contacts& contacts, std::string& message) {
  std::lock_guard lock(mutex_);
  std::vector<char> request{kStep};
  put(request, static_cast<std::uint64_t>(step.index));
  put(request, step.thickness);
  put(request, static_cast<std::uint64_t>(vertex_count));
  const char* x0 = reinterpret_cast<const char*>(step.x0);
  const char* x1 = reinterpret_cast<const char*>(step.x1);
  request.insert(request.end(), x0, x0 + 3 * vertex_count * sizeof(double));
  request.insert(request.end(), x1, x1 + 3 * vertex_count * sizeof(double));
  std::vector<char> reply;
  if (!exchange(request, reply, kStatusSize + sizeof(std::uint64_t), message)) return 1;
  const char* at = reply.data();
  const std::int32_t status = take<std::int32_t>(at);
  message.assign(at, strnlen(at, CCDBENCH_MESSAGE_SIZE));
  at += CCDBENCH_MESSAGE_SIZE;
  // Contacts come in blocks, each read within the deadline: never an allocation from a count the child has not sent.
  constexpr std::size_t kVertexFaceBytes = 2 * sizeof(std::uint32_t) + sizeof(double);
  constexpr std::size_t kEdgeEdgeBytes = 4 * sizeof(std::uint32_t) + sizeof(double);
  constexpr std::uint64_t kBlock = 4096;
  std::uint64_t vertex_face = take<std::uint64_t>(at);
  auto flood = [&](std::uint64_t claimed, std::uint64_t most) {
    message = "its reply claims " + std::to_string(claimed) + " contacts, more than the mesh's " + std::to_string(most) + " pairs (killed)";
    stop(true);
    return 1;
  };
  if (vertex_face > most_vertex_face_) return flood(vertex_face, most_vertex_face_);
  std::vector<char> block;
  while (vertex_face > 0) {
    const std::uint64_t count = std::min(vertex_face, kBlock);
    block.clear();
    if (!read_more(block, count * kVertexFaceBytes, message)) return 1;
    const char* p = block.data();
    for (std::uint64_t i = 0; i < count; ++i) {
      const auto v = take<std::uint32_t>(p);
      const auto f = take<std::uint32_t>(p);
      contacts.vertex_face(contacts.host, v, f, take<double>(p));
    }
    vertex_face -= count;
  }
  block.clear();
  if (!read_more(block, sizeof(std::uint64_t), message)) return 1;
  const char* p = block.data();
  std::uint64_t edge_edge = take<std::uint64_t>(p);
  if (edge_edge > most_edge_edge_) return flood(edge_edge, most_edge_edge_);
  while (edge_edge > 0) {
    const std::uint64_t count = std::min(edge_edge, kBlock);
    block.clear();
    if (!read_more(block, count * kEdgeEdgeBytes, message)) return 1;
    p = block.data();
    for (std::uint64_t i = 0; i < count; ++i) {
      std::uint32_t v[4];
      for (std::uint32_t& id : v) id = take<std::uint32_t>(p);
      contacts.edge_edge(contacts.host, v[0], v[1], v[2], v[3], take<double>(p));
    }
    edge_edge -= count;
  }
  return status;
}

void IsolatedPlugin::end() {
  std::lock_guard lock(mutex_);
  if (child_ <= 0) return;
  std::vector<char> reply;
  std::string why;
  exchange({kEnd}, reply, kStatusSize, why);
}

}  // namespace ccd::plugin
