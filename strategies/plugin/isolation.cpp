#include "strategies/plugin/isolation.hpp"

#include "ccd/config.hpp"

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
#include <stdexcept>
#include <thread>

extern char** environ;

namespace ccd::plugin {
namespace {

// Requests (one byte, then their payload; replies start with a 32-bit status or outcome, then a message).
constexpr char kQuery = 'Q';
constexpr char kBegin = 'B';
constexpr char kStep = 'S';
constexpr char kEnd = 'E';
/// The child's ends of the two pipes.
constexpr int kRequestFd = 3;
constexpr int kReplyFd = 4;

constexpr std::size_t kStatusSize = sizeof(std::int32_t) + CCDBENCH_MESSAGE_SIZE;

double now_seconds() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

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

bool write_all(int fd, const char* data, std::size_t size) {
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
bool read_all(int fd, char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t got = ::read(fd, data, size);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return false;
    data += got;
    size -= static_cast<std::size_t>(got);
  }
  return true;
}

std::vector<char> status_reply(std::int32_t status, const char* message) {
  std::vector<char> reply;
  put(reply, status);
  char text[CCDBENCH_MESSAGE_SIZE] = {};
  std::strncpy(text, message, CCDBENCH_MESSAGE_SIZE - 1);
  reply.insert(reply.end(), text, text + CCDBENCH_MESSAGE_SIZE);
  return reply;
}

/// The child's collected contacts of a step, as sent back.
struct StepReply {
  std::vector<char> vertex_face, edge_edge;
  std::uint64_t vertex_face_count = 0, edge_edge_count = 0;
};

}  // namespace

namespace {

/// The child's greeting: a status, a message, and the digest of the code it loaded (32 hex digits). Status 0: ready;
/// 1: the plugin refused its configuration; kChangedStatus: its code is not the code the run was planned with (the
/// child then calls nothing of it).
constexpr std::size_t kDigestSize = 32;
constexpr std::size_t kGreetingSize = kStatusSize + kDigestSize;
constexpr std::int32_t kChangedStatus = 2;

/// The child's end of the lifeline (docs/DESIGN.md §10): the parent holds the other end open and never writes, so
/// the pipe reports its end only when the parent is gone.
constexpr int kLifelineFd = 5;

/// Ends the child when its parent is gone, even while the plugin hangs in a call on the main thread.
void watch_the_parent() {
#if CCDBENCH_GUARD_LIFELINE
  std::thread([] {
    pollfd lifeline{kLifelineFd, POLLIN, 0};
    while (::poll(&lifeline, 1, -1) < 0 && errno == EINTR) {
    }
    ::_exit(3);
  }).detach();
#endif
}

/// A child of this program, `PROGRAM plugin-host ARGUMENTS...`, with its request pipe on fd 3, its reply pipe on
/// fd 4 and the lifeline on fd 5; the parent's ends are close-on-exec, so that no other child holds them.
struct Child {
  pid_t pid = -1;
  int to_child = -1, from_child = -1, lifeline = -1;
};

Child spawn_child(const std::vector<std::string>& plugin_host_arguments) {
  int requests[2], replies[2], lifeline[2];
  if (::pipe2(requests, O_CLOEXEC) != 0 || ::pipe2(replies, O_CLOEXEC) != 0 || ::pipe2(lifeline, O_CLOEXEC) != 0) {
    throw std::runtime_error("plugin isolation: pipe failed");
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, requests[0], kRequestFd);
  posix_spawn_file_actions_adddup2(&actions, replies[1], kReplyFd);
  posix_spawn_file_actions_adddup2(&actions, lifeline[0], kLifelineFd);
  std::vector<std::string> arguments{"/proc/self/exe", kPluginHostCommand};
  arguments.insert(arguments.end(), plugin_host_arguments.begin(), plugin_host_arguments.end());
  std::vector<char*> argv;
  for (std::string& argument : arguments) argv.push_back(argument.data());
  argv.push_back(nullptr);
  // The program's own file, not a name looked up on PATH: the child is this build.
  char self[4096] = {};
  const ssize_t length = ::readlink("/proc/self/exe", self, sizeof self - 1);
  Child child;
  int spawned = ENOENT;
  if (length > 0) spawned = ::posix_spawn(&child.pid, self, &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(requests[0]);
  ::close(replies[1]);
  ::close(lifeline[0]);
  child.to_child = requests[1];
  child.from_child = replies[0];
  child.lifeline = lifeline[1];
  if (spawned != 0) {
    for (int fd : {child.to_child, child.from_child, child.lifeline}) ::close(fd);
    throw std::runtime_error("plugin isolation: cannot start a child process: " + std::string(std::strerror(spawned)));
  }
  return child;
}

/// Reaps a child; what happened to it, in words.
std::string reap(pid_t pid, bool kill_it) {
  if (kill_it) ::kill(pid, SIGKILL);
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
/// Loading a plugin (its libraries, its constructors) may take this long in a child before it is called hung.
constexpr double kDescribeSeconds = 120;

int describe_plugin(const char* path) {
  std::vector<char> reply;
  try {
    const Library library(path);
    const std::vector<char> description = encode(library.description());
    reply = status_reply(0, "");
    put(reply, static_cast<std::uint64_t>(description.size()));
    reply.insert(reply.end(), description.begin(), description.end());
  } catch (const std::exception& error) {
    reply = status_reply(1, error.what());
    put(reply, std::uint64_t{0});
  }
  return write_all(kReplyFd, reply.data(), reply.size()) ? 0 : 1;
}

}  // namespace

PluginDescription describe_in_child(const std::string& given) {
  std::error_code error;
  const std::filesystem::path absolute = std::filesystem::weakly_canonical(std::filesystem::absolute(given), error);
  const std::string path = (error ? std::filesystem::absolute(given) : absolute).string();
  if (!std::filesystem::is_regular_file(path)) throw std::invalid_argument("plugin " + path + ": no such file");
  // A broken pipe is an answer here (the child died), never a reason for this process to die.
  ::signal(SIGPIPE, SIG_IGN);
  Child child = spawn_child({"--describe", path});
  const double deadline = now_seconds() + kDescribeSeconds;
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
    if (status != 0) {
      failure = message.empty() ? "it was refused" : message;
    } else if (size > kMaxDescriptionBytes) {
      failure = "its child process sent a description of " + std::to_string(size) + " bytes";
    } else {
      bytes.resize(size);
      if (!read_until(child.from_child, bytes.data(), size, deadline, timed_out)) failure = "its child process stopped while describing it";
    }
  } else {
    failure = "its child process ended while loading it";
  }
  for (int fd : {child.to_child, child.from_child, child.lifeline}) ::close(fd);
  const std::string ended = reap(child.pid, timed_out);
  if (timed_out) throw std::invalid_argument("plugin " + path + ": loading it did not finish within " + std::to_string(kDescribeSeconds) + " s");
  if (!failure.empty()) {
    // A refusal names the plugin already; a child that died says how.
    if (failure.rfind("plugin ", 0) == 0) throw std::invalid_argument(failure);
    throw std::invalid_argument("plugin " + path + ": " + failure + " (" + ended + ")");
  }
  return decode_description(path, bytes);
}

int serve_plugin(int argc, char** argv) {
  if (argc < 3) return 2;
  watch_the_parent();
  // Whatever the plugin prints goes to the standard error (never into ccdbench's own output, which a script may be
  // reading); its answers go to fd 4 alone.
  ::dup2(STDERR_FILENO, STDOUT_FILENO);
  if (std::string(argv[2]) == "--describe") return argc == 4 ? describe_plugin(argv[3]) : 2;
  std::unique_ptr<Library> loaded;
  try {
    loaded = std::make_unique<Library>(argv[2]);
  } catch (const std::exception& error) {
    std::vector<char> greeting = status_reply(1, error.what());
    greeting.resize(kGreetingSize, '0');
    write_all(kReplyFd, greeting.data(), greeting.size());
    return 1;
  }
  const Library& library = *loaded;
  // The plugin runs in its own process: the environment its load left stays its own (as in-process calls get it).
  library.environment().install();
  // argv[3] is the digest of the code the run was planned with ("-": none asked): other code is never called.
  const std::string& digest = library.description().digest;
  if (argc < 4) return 2;
  if (std::string(argv[3]) != "-" && argv[3] != digest) {
    std::vector<char> greeting = status_reply(kChangedStatus, "its code changed since the run began");
    greeting.insert(greeting.end(), digest.begin(), digest.end());
    greeting.resize(kGreetingSize, '0');
    write_all(kReplyFd, greeting.data(), greeting.size());
    return 1;
  }
  std::vector<std::string> values(argv + 4, argv + argc);
  std::vector<const char*> pointers;
  for (const std::string& value : values) pointers.push_back(value.c_str());
  char error[CCDBENCH_MESSAGE_SIZE] = {};
  void* context = library.table().create(pointers.data(), error);
  error[CCDBENCH_MESSAGE_SIZE - 1] = '\0';
  std::vector<char> greeting = status_reply(context != nullptr ? 0 : 1, context != nullptr ? "" : error);
  greeting.insert(greeting.end(), digest.begin(), digest.end());
  greeting.resize(kGreetingSize, '0');
  if (!write_all(kReplyFd, greeting.data(), greeting.size()) || context == nullptr) return 1;
  // The scene of `begin`, kept for the step calls.
  std::vector<std::uint32_t> faces, edges, face_object, collidable;
  std::vector<std::uint8_t> self;
  ccdbench_scene scene{};
  for (char kind = 0; read_all(kRequestFd, &kind, 1);) {
    if (kind == kQuery) {
      char payload[1 + 25 * sizeof(double)];
      if (!read_all(kRequestFd, payload, sizeof payload)) return 1;
      const char* at = payload;
      const bool vertex_face = take<std::uint8_t>(at) != 0;
      double rows[24];
      std::memcpy(rows, at, sizeof rows);
      at += sizeof rows;
      const double thickness = take<double>(at);
      // As in-process (plugin_narrow_phase.cpp): no outcome until the plugin writes one, so a plugin that writes
      // none is caught here too, not taken for "apart".
      ccdbench_answer answer{};
      answer.outcome = -1;
      answer.toi = std::nan("");
      (vertex_face ? library.table().vertex_face : library.table().edge_edge)(context, rows, thickness, &answer);
      answer.message[CCDBENCH_MESSAGE_SIZE - 1] = '\0';
      std::vector<char> reply = status_reply(answer.outcome, answer.message);
      put(reply, answer.toi);
      if (!write_all(kReplyFd, reply.data(), reply.size())) return 1;
    } else if (kind == kBegin) {
      auto read_array = [&](auto& out) {
        std::uint64_t count = 0;
        if (!read_all(kRequestFd, reinterpret_cast<char*>(&count), sizeof count)) return false;
        out.resize(count);
        return read_all(kRequestFd, reinterpret_cast<char*>(out.data()), count * sizeof(out[0]));
      };
      std::uint64_t vertices = 0;
      if (!read_all(kRequestFd, reinterpret_cast<char*>(&vertices), sizeof vertices) || !read_array(faces) || !read_array(edges) ||
          !read_array(face_object) || !read_array(self) || !read_array(collidable)) {
        return 1;
      }
      scene = {vertices,    faces.size() / 3,   faces.data(), edges.size() / 2,      edges.data(),
               self.size(), face_object.data(), self.data(),  collidable.size() / 2, collidable.data()};
      char message[CCDBENCH_MESSAGE_SIZE] = {};
      const int status = library.table().begin ? library.table().begin(context, &scene, message) : 0;
      message[CCDBENCH_MESSAGE_SIZE - 1] = '\0';
      const std::vector<char> reply = status_reply(status, message);
      if (!write_all(kReplyFd, reply.data(), reply.size())) return 1;
    } else if (kind == kStep) {
      std::uint64_t index = 0, vertices = 0;
      double thickness = 0;
      if (!read_all(kRequestFd, reinterpret_cast<char*>(&index), sizeof index) ||
          !read_all(kRequestFd, reinterpret_cast<char*>(&thickness), sizeof thickness) ||
          !read_all(kRequestFd, reinterpret_cast<char*>(&vertices), sizeof vertices)) {
        return 1;
      }
      std::vector<double> x0(3 * vertices), x1(3 * vertices);
      if (!read_all(kRequestFd, reinterpret_cast<char*>(x0.data()), x0.size() * sizeof(double)) ||
          !read_all(kRequestFd, reinterpret_cast<char*>(x1.data()), x1.size() * sizeof(double))) {
        return 1;
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
      const ccdbench_step step{index, x0.data(), x1.data(), thickness};
      char message[CCDBENCH_MESSAGE_SIZE] = {};
      const int status = library.table().step(context, &step, &contacts, message);
      message[CCDBENCH_MESSAGE_SIZE - 1] = '\0';
      std::vector<char> reply = status_reply(status, message);
      put(reply, collected.vertex_face_count);
      reply.insert(reply.end(), collected.vertex_face.begin(), collected.vertex_face.end());
      put(reply, collected.edge_edge_count);
      reply.insert(reply.end(), collected.edge_edge.begin(), collected.edge_edge.end());
      if (!write_all(kReplyFd, reply.data(), reply.size())) return 1;
    } else if (kind == kEnd) {
      if (library.table().end) library.table().end(context);
      const std::vector<char> reply = status_reply(0, "");
      if (!write_all(kReplyFd, reply.data(), reply.size())) return 1;
    } else {
      return 1;
    }
  }
  library.table().destroy(context);
  return 0;
}

PluginInstance::PluginInstance(const PluginDescription& description_, const narrowphase::SpecReader& keys)
    : description(description_), values(plugin_values(keys, description)), host(read_host_settings(keys, description)) {
  if (host.isolate) {
    isolated = std::make_unique<IsolatedPlugin>(description, values, host.timeout_seconds);
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

IsolatedPlugin::IsolatedPlugin(const PluginDescription& description, std::vector<std::string> values, double timeout_seconds)
    : path_(description.path), digest_(description.digest), values_(std::move(values)), timeout_seconds_(timeout_seconds) {
  // A broken pipe is an answer here (the child died), never a reason for this process to die.
  ::signal(SIGPIPE, SIG_IGN);
}

IsolatedPlugin::~IsolatedPlugin() {
  if (child_ > 0) stop(false);
}

bool IsolatedPlugin::start(std::string& why) {
#if CCDBENCH_GUARD_CHILD_IDENTITY
  std::vector<std::string> arguments{path_, digest_};
#else
  std::vector<std::string> arguments{path_, "-"};
#endif
  arguments.insert(arguments.end(), values_.begin(), values_.end());
  const Child child = spawn_child(arguments);
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
  const std::string digest(greeting.data() + kStatusSize, kDigestSize);
  if (status == kChangedStatus) {
    stop(true);
    changed_ = "its code changed during the run: a child started again loaded code of digest " + digest + ", the run's is " + digest_ +
               " (the plugin or a library it loads was replaced or rebuilt): no answer of other code stands for the run's";
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

int IsolatedPlugin::begin(const ccdbench_scene& scene, std::string& message) {
  std::lock_guard lock(mutex_);
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
