#include "strategies/plugin/isolation.hpp"

#include "ccd/config.hpp"
#include "strategies/plugin/child_process.hpp"
#include "strategies/plugin/child_protocol.hpp"
#include "strategies/plugin/query_batch.hpp"

#include <signal.h>
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

namespace ccd::plugin {

using namespace child_protocol;

namespace {

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
  ChildProcess child = spawn_child({"--describe", path});
  const double deadline = now_seconds() + kLoadSeconds;
  char head[kStatusSize + sizeof(std::uint64_t)];
  bool timed_out = false;
  std::string failure;
  std::string bytes;
  ChildRead read = read_from_child(child, head, sizeof head, deadline);
  if (read == ChildRead::whole) {
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
      read = read_from_child(child, bytes.data(), size, deadline);
      if (read != ChildRead::whole) {
        failure = "its child process stopped while describing it";
      } else if (status != 0) {
        failure = !bytes.empty() ? bytes : message.empty() ? "it was refused" : message;
      }
    }
  } else {
    failure = "its child process ended while loading it";
  }
  timed_out = read == ChildRead::timed_out;
  // Whatever it started at load goes with it (a process the plugin forked must not outlive its description).
  const std::string ended = end_child(child, timed_out, kEndSeconds);
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
  // Started now, not at the first request: its start is not timed with the first query or step, and a plugin whose
  // create fails is refused here, as in-process (a child that dies while starting is its first request's error).
  std::string why;
  start(why);
}

IsolatedPlugin::~IsolatedPlugin() {
  if (child_.pid > 0) stop(false);
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
  child_ = spawn_child(arguments, region_ ? region_->fd() : -1);
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
  if (status == kCreateFailedStatus) {
    stop(true);
    throw std::invalid_argument("plugin " + path_ + ": its create call failed: " + message);
  }
  if (status != 0) {
    stop(true);
    throw std::invalid_argument("plugin " + path_ + ": its configuration was refused: " + (message.empty() ? "no reason given" : message));
  }
  return true;
}

std::string IsolatedPlugin::stop(bool kill_it) { return end_child(child_, kill_it, kEndSeconds); }

bool IsolatedPlugin::read_more(std::vector<char>& reply, std::size_t size, std::string& why) {
  const std::size_t start = reply.size();
  reply.resize(start + size);
  const ChildRead read = read_from_child(child_, reply.data() + start, size, deadline_);
  if (read == ChildRead::whole) return true;
  if (read == ChildRead::timed_out) {
    stop(true);
    why = "it did not answer within its timeout of " + narrowphase::format_spec_number(timeout_seconds_) + " s (killed)";
  } else {
    why = stop(false);
  }
  return false;
}

bool IsolatedPlugin::send(std::vector<char> request, std::string& why) {
  // Its number right after the kind: the child puts it before its reply, and no reply of another request (a second
  // one a process the plugin started wrote) is ever taken for this one's.
  const std::uint64_t sequence = ++sequence_;
  request.insert(request.begin() + 1, reinterpret_cast<const char*>(&sequence), reinterpret_cast<const char*>(&sequence) + sizeof sequence);
  deadline_ = now_seconds() + timeout_seconds_;
  if (write_all(child_.to_child, request.data(), request.size())) return true;
  why = stop(false);
  return false;
}

bool IsolatedPlugin::reply_is_this_requests(std::string& why) {
  std::vector<char> number;
  if (!read_more(number, sizeof(std::uint64_t), why)) return false;
  const char* at = number.data();
  const auto sequence = take<std::uint64_t>(at);
  if (sequence == sequence_) return true;
  stop(true);
  why = "its reply was not to this request (a reply to request " + std::to_string(sequence) + " when " + std::to_string(sequence_) +
        " was asked: did the plugin start a process that answers too?) (killed)";
  return false;
}

bool IsolatedPlugin::exchange(const std::vector<char>& request, std::vector<char>& reply, std::size_t reply_size, std::string& why) {
  if (!changed_.empty()) {
    why = changed_;
    return false;
  }
  if (child_.pid <= 0) {
    // A child that dies while starting (the plugin's constructor or create crashed) is this request's error.
    if (!start(why)) return false;
    if (!scene_request_.empty() && request.front() != kBegin && !send_scene(why)) return false;
  }
  if (!send(request, why) || !reply_is_this_requests(why)) return false;
  reply.clear();
  return read_more(reply, reply_size, why);
}

bool IsolatedPlugin::send_scene(std::string& message) {
  std::vector<char> reply;
  if (!send(scene_request_, message) || !reply_is_this_requests(message)) return false;
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
    if (child_.pid <= 0 && !start(why)) {
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
  bool finished = false, foreign = false;
  if (send(request, why)) {
    // Each query has its own timeout: the deadline moves on with every answer the child counts done.
    std::uint64_t seen = 0;
    char reply[kBatchDoneSize];
    std::size_t filled = 0;
    while (true) {
      const ChildRead read = read_some_from_child(child_, reply, sizeof reply, filled, std::min(deadline_, now_seconds() + kBatchWatchSeconds));
      if (read == ChildRead::whole) {
        const char* at = reply;
        const auto sequence = take<std::uint64_t>(at);
        finished = sequence == sequence_ && *at == kBatchDone;
        foreign = !finished;
        if (foreign) {
          stop(true);
          why = "its reply was not this batch's (a reply to request " + std::to_string(sequence) + " when " + std::to_string(sequence_) +
                " was asked: did the plugin start a process that answers too?) (killed)";
        }
        break;
      }
      if (read == ChildRead::ended) {
        why = stop(false);
        break;
      }
      if (const std::uint64_t now_done = region_->done(); now_done != seen) {
        seen = now_done;
        deadline_ = now_seconds() + timeout_seconds_;
      } else if (now_seconds() >= deadline_) {
        stop(true);
        why = "it did not answer within its timeout of " + narrowphase::format_spec_number(timeout_seconds_) + " s (killed)";
        break;
      }
    }
  }
  // What the child counted done, never more than was asked; on a clean finish, every query; after a reply that was
  // not this batch's, none (two processes answered: the batch is its first query's error, and a fresh child answers
  // the rest). An answer stamped with another batch's number was not written for this one (a process the plugin
  // started wrote it, or none was): it and those after it are not taken.
  const std::size_t counted = finished ? count : foreign ? 0 : std::min<std::size_t>(region_->done(), count);
  const auto stamp = static_cast<std::uint32_t>(sequence_);
  std::size_t answered = 0;
  for (; answered < counted; ++answered) {
    const BatchAnswer& in = region_->answers()[answered];
    if (in.batch != stamp) {
      if (child_.pid > 0) stop(true);
      why = "its answer was not written for this batch (it holds batch " + std::to_string(in.batch) + "'s number) (killed)";
      break;
    }
    ccdbench_answer& out = answers[first + answered];
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
  if (child_.pid <= 0) return;
  std::vector<char> reply;
  std::string why;
  exchange({kEnd}, reply, kStatusSize, why);
}

}  // namespace ccd::plugin
