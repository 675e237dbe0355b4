#include "strategies/plugin/isolation.hpp"

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
#include <memory>
#include <stdexcept>

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

int serve_plugin(int argc, char** argv) {
  if (argc < 3) return 2;
  // Whatever the plugin prints goes to the standard error (never into ccdbench's own output, which a script may be
  // reading); its answers go to fd 4 alone.
  ::dup2(STDERR_FILENO, STDOUT_FILENO);
  std::unique_ptr<Library> loaded;
  try {
    loaded = std::make_unique<Library>(argv[2]);
  } catch (const std::exception& error) {
    const std::vector<char> greeting = status_reply(1, error.what());
    write_all(kReplyFd, greeting.data(), greeting.size());
    return 1;
  }
  const Library& library = *loaded;
  std::vector<std::string> values(argv + 3, argv + argc);
  std::vector<const char*> pointers;
  for (const std::string& value : values) pointers.push_back(value.c_str());
  char error[CCDBENCH_MESSAGE_SIZE] = {};
  void* context = library.table().create(pointers.data(), error);
  error[CCDBENCH_MESSAGE_SIZE - 1] = '\0';
  const std::vector<char> greeting = status_reply(context != nullptr ? 0 : 1, context != nullptr ? "" : error);
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

PluginInstance::PluginInstance(std::shared_ptr<const Library> library_, const narrowphase::SpecReader& keys)
    : library(std::move(library_)), values(plugin_values(keys, *library)), host(read_host_settings(keys, *library)) {
  if (host.isolate) {
    isolated = std::make_unique<IsolatedPlugin>(*library, values, host.timeout_seconds);
  } else {
    context = std::make_unique<Context>(library, values);
  }
}

std::string PluginInstance::name() const { return resolved_name(*library, values, host); }

IsolatedPlugin::IsolatedPlugin(const Library& library, std::vector<std::string> values, double timeout_seconds)
    : path_(library.path()), values_(std::move(values)), timeout_seconds_(timeout_seconds) {
  // A broken pipe is an answer here (the child died), never a reason for this process to die.
  ::signal(SIGPIPE, SIG_IGN);
}

IsolatedPlugin::~IsolatedPlugin() {
  if (child_ > 0) stop(false);
}

void IsolatedPlugin::start() {
  int requests[2], replies[2];
  if (::pipe2(requests, O_CLOEXEC) != 0 || ::pipe2(replies, O_CLOEXEC) != 0) throw std::runtime_error("plugin isolation: pipe failed");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, requests[0], kRequestFd);
  posix_spawn_file_actions_adddup2(&actions, replies[1], kReplyFd);
  std::vector<std::string> arguments{"/proc/self/exe", kPluginHostCommand, path_};
  arguments.insert(arguments.end(), values_.begin(), values_.end());
  std::vector<char*> argv;
  for (std::string& argument : arguments) argv.push_back(argument.data());
  argv.push_back(nullptr);
  // The program's own file, not a name looked up on PATH: the child is this build.
  char self[4096] = {};
  const ssize_t length = ::readlink("/proc/self/exe", self, sizeof self - 1);
  if (length <= 0) throw std::runtime_error("plugin isolation: cannot find this program's file (/proc/self/exe)");
  const int spawned = ::posix_spawn(&child_, self, &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(requests[0]);
  ::close(replies[1]);
  to_child_ = requests[1];
  from_child_ = replies[0];
  if (spawned != 0) {
    child_ = -1;
    throw std::runtime_error("plugin isolation: cannot start a child process: " + std::string(std::strerror(spawned)));
  }
  std::vector<char> greeting;
  std::string why;
  deadline_ = now_seconds() + timeout_seconds_ + 10;  // loading and configuring may take longer than one query
  if (!read_more(greeting, kStatusSize, why)) {
    throw std::invalid_argument("plugin " + path_ + ": its child process did not start: " + why);
  }
  const char* at = greeting.data();
  if (take<std::int32_t>(at) != 0) {
    const std::string message(at, strnlen(at, CCDBENCH_MESSAGE_SIZE));
    stop(true);
    throw std::invalid_argument("plugin " + path_ + ": its configuration was refused: " + (message.empty() ? "no reason given" : message));
  }
}

std::string IsolatedPlugin::stop(bool kill_it) {
  if (to_child_ >= 0) ::close(to_child_);
  if (from_child_ >= 0) ::close(from_child_);
  to_child_ = from_child_ = -1;
  if (child_ <= 0) return "it was not running";
  if (kill_it) ::kill(child_, SIGKILL);
  int status = 0;
  while (::waitpid(child_, &status, 0) < 0 && errno == EINTR) {
  }
  child_ = -1;
  if (WIFSIGNALED(status)) {
    return "it crashed with signal " + std::to_string(WTERMSIG(status)) + " (" + ::strsignal(WTERMSIG(status)) + ")";
  }
  if (WIFEXITED(status)) return "its process exited with status " + std::to_string(WEXITSTATUS(status));
  return "its process ended";
}

bool IsolatedPlugin::read_more(std::vector<char>& reply, std::size_t size, std::string& why) {
  const std::size_t start = reply.size();
  reply.resize(start + size);
  std::size_t got = 0;
  while (got < size) {
    const double left = deadline_ - now_seconds();
    pollfd ready{from_child_, POLLIN, 0};
    const int polled = left > 0 ? ::poll(&ready, 1, static_cast<int>(std::ceil(left * 1000))) : 0;
    if (polled < 0 && errno == EINTR) continue;
    if (polled == 0) {
      stop(true);
      why = "it did not answer within its timeout of " + std::to_string(timeout_seconds_) + " s (killed)";
      return false;
    }
    const ssize_t n = ::read(from_child_, reply.data() + start + got, size - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      why = stop(false);
      return false;
    }
    got += static_cast<std::size_t>(n);
  }
  return true;
}

bool IsolatedPlugin::exchange(const std::vector<char>& request, std::vector<char>& reply, std::size_t reply_size, std::string& why) {
  if (child_ <= 0) {
    start();
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
