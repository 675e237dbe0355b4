#include "strategies/plugin/host_method.hpp"

#include "strategies/plugin/ccdbench_plugin.h"
#include "strategies/plugin/fp_environment.hpp"
#include "strategies/plugin/plugin_narrow_phase.hpp"

#include <algorithm>
#include <atomic>
#include <clocale>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>

namespace ccd::plugin {
namespace {

struct RegisteredMethod {
  HostMethod method;
  HostMethodSettings settings;
  /// Whether its answers carry TOIs, as its first answered batch said (-1: not yet): a method reports TOIs for every
  /// answer or for none, as a plugin declares once, so that it cannot leave them out where they would be late.
  mutable std::atomic<int> reports_toi{-1};

  std::string tois_as_before(bool with_tois) const {
    int expected = -1;
    if (reports_toi.compare_exchange_strong(expected, with_tois ? 1 : 0) || expected == (with_tois ? 1 : 0)) return {};
    return with_tois ? "it answered with TOIs after answering without" : "it answered without TOIs after answering with them";
  }
};

/// The process state a method of the calling program can change and must not: the floating-point environment, the
/// working directory, the C locale.
struct CallerState {
  FpEnvironment environment;
  std::string directory, locale;

  static CallerState current() {
    CallerState state{FpEnvironment::current(), working_directory(), {}};
    if (const char* locale = std::setlocale(LC_ALL, nullptr)) state.locale = locale;
    return state;
  }
  static std::string working_directory() {
    std::error_code error;
    return std::filesystem::current_path(error).string();
  }
  void restore() const {
    environment.install();
    std::error_code error;
    if (working_directory() != directory) std::filesystem::current_path(directory, error);
    if (const char* now = std::setlocale(LC_ALL, nullptr); now == nullptr || now != locale) std::setlocale(LC_ALL, locale.c_str());
  }
  /// What changed since this state was taken, in words ("" when nothing did), each change put back.
  std::string changes_undone() const {
    const CallerState after = current();
    std::string changed;
    if (after.environment != environment) changed = "it changed the floating-point environment: " + describe_change(environment, after.environment);
    if (after.directory != directory)
      changed += (changed.empty() ? "" : "; ") + std::string("it changed the working directory to ") + after.directory;
    if (after.locale != locale) changed += (changed.empty() ? "" : "; ") + std::string("it changed the C locale to ") + after.locale;
    if (!changed.empty()) restore();
    return changed;
  }
};

std::mutex& host_methods_mutex() {
  static std::mutex mutex;
  return mutex;
}

/// A registered method, and its registry entry. Entries are never freed: a spec parsed while the method was
/// registered keeps pointing at it (making it after unregister_host_method says the method is gone); the method itself
/// (the caller's code, a Python callable) is freed when unregistered and no strategy made from it still runs.
struct Registration {
  std::shared_ptr<const RegisteredMethod> method;
  const narrowphase::NarrowPhaseEntry* entry;
};

std::map<std::string, Registration>& host_methods() {
  static std::map<std::string, Registration> methods;
  return methods;
}

std::string head(const std::string& name) { return std::string(kCallableHead) + ":" + name; }

class HostNarrowPhase final : public narrowphase::NarrowPhase {
 public:
  HostNarrowPhase(std::string name, std::shared_ptr<const RegisteredMethod> method, bool errors_count_as_hits)
      : name_(std::move(name)), method_(std::move(method)), errors_count_as_hits_(errors_count_as_hits) {}

  std::string name() const override { return name_ + ":errors=" + (errors_count_as_hits_ ? "hit" : "miss"); }
  bool conservative() const override { return false; }
  /// The caller's code may not be reentrant (Python's is not): its strategy runs on one thread.
  bool thread_safe() const override { return false; }
  bool prefers_batches() const override { return true; }
  std::size_t preferred_batch() const override {
    return method_->settings.batch == 0 ? std::numeric_limits<std::size_t>::max() : method_->settings.batch;
  }
  std::vector<std::pair<std::string, std::string>> provenance() const override {
    return {{"method", name_ + ": code of the calling program, not digested: its cells are never kept for a later run"}};
  }

  narrowphase::NarrowPhaseResult vertex_face(const narrowphase::PairRows& rows, double thickness) const override {
    return one(rows, true, thickness);
  }
  narrowphase::NarrowPhaseResult edge_edge(const narrowphase::PairRows& rows, double thickness) const override { return one(rows, false, thickness); }

  /// Runs of pairs of one kind and δ, in batches of the method's size.
  void answer_batch(std::span<const BatchPair> pairs, std::span<narrowphase::NarrowPhaseResult> results) const override {
    std::size_t first = 0;
    while (first < pairs.size()) {
      std::size_t end = first + 1;
      while (end < pairs.size() && end - first < preferred_batch() && pairs[end].vertex_face == pairs[first].vertex_face &&
             std::memcmp(&pairs[end].thickness, &pairs[first].thickness, sizeof(double)) == 0) {
        ++end;
      }
      ask(pairs.subspan(first, end - first), results.subspan(first, end - first));
      first = end;
    }
  }

 private:
  narrowphase::NarrowPhaseResult one(const narrowphase::PairRows& rows, bool vertex_face, double thickness) const {
    const BatchPair pair{&rows, vertex_face, thickness};
    narrowphase::NarrowPhaseResult result;
    ask({&pair, 1}, {&result, 1});
    return result;
  }

  /// One call: the rows copied (the method cannot reach ccdbench's own), its answers checked as a plugin's are.
  void ask(std::span<const BatchPair> pairs, std::span<narrowphase::NarrowPhaseResult> results) const {
    std::vector<double> rows(24 * pairs.size());
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      for (std::size_t p = 0; p < 8; ++p) {
        for (int c = 0; c < 3; ++c) rows[24 * i + 3 * p + static_cast<std::size_t>(c)] = (*pairs[i].rows)[p][c];
      }
    }
    const HostBatch batch{pairs.front().vertex_face, rows.data(), pairs.size(), pairs.front().thickness};
    HostAnswers answers;
    const CallerState before = CallerState::current();
    std::string failure;
    try {
      method_->method(batch, answers);
    } catch (const std::exception& error) {
      failure = error.what();
    } catch (const HostMethodInterrupted&) {
      before.restore();
      throw;  // the user's interrupt: it ends the call that runs the method, never an answer
    } catch (...) {
      failure = "an exception that is not a std::exception";
    }
    // What it changed of the process is put back and is its error: arithmetic, where relative paths lead, how
    // numbers are read and printed.
    if (const std::string changed = before.changes_undone(); !changed.empty()) {
      failure = changed;
    } else if (failure.empty()) {
      failure = wrong_size(answers, pairs.size());
    }
    // Only a batch with an answer in it says whether the method gives TOIs (one whose every pair is its error does not).
    const bool answered =
        answers.errors.empty() || std::any_of(answers.errors.begin(), answers.errors.end(), [](const std::string& e) { return e.empty(); });
    if (failure.empty() && answered) failure = method_->tois_as_before(!answers.tois.empty());
    if (!failure.empty() && pairs.size() > 1) {
      // Asked again one pair at a time: the error lands on the pair that causes it.
      for (std::size_t i = 0; i < pairs.size(); ++i) ask(pairs.subspan(i, 1), results.subspan(i, 1));
      return;
    }
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      ccdbench_answer answer;
      std::memset(&answer, 0, sizeof answer);
      answer.toi = std::numeric_limits<double>::quiet_NaN();
      std::string message = failure;
      if (message.empty() && !answers.errors.empty()) message = answers.errors[i];
      if (!message.empty()) {
        answer.outcome = CCDBENCH_ERROR;
      } else {
        answer.outcome = answers.hits[i] == 0 ? CCDBENCH_APART : answers.hits[i] == 1 ? CCDBENCH_CONTACT : 4;
        if (!answers.tois.empty()) answer.toi = answers.tois[i];
      }
      message.copy(answer.message, CCDBENCH_MESSAGE_SIZE - 1);  // answer is zeroed: the text ends within it
      results[i] = checked_answer(answer, !answers.tois.empty(), errors_count_as_hits_);
    }
  }

  static std::string wrong_size(const HostAnswers& answers, std::size_t count) {
    auto size = [&](const char* what, std::size_t n, bool may_be_empty) -> std::string {
      if (n == count || (may_be_empty && n == 0)) return {};
      return std::string("it answered ") + std::to_string(n) + " " + what + " for " + std::to_string(count) + " pairs";
    };
    std::string wrong = size("hits", answers.hits.size(), false);
    if (wrong.empty()) wrong = size("TOIs", answers.tois.size(), true);
    if (wrong.empty()) wrong = size("errors", answers.errors.size(), true);
    return wrong;
  }

  std::string name_;
  std::shared_ptr<const RegisteredMethod> method_;
  bool errors_count_as_hits_;
};

}  // namespace

void register_host_method(const std::string& name, HostMethod method, HostMethodSettings settings) {
  if (name.empty() || name.find_first_of(":+") != std::string::npos) {
    throw std::invalid_argument("a method's name may not be empty nor hold ':' or '+': '" + name + "'");
  }
  auto registered = std::make_shared<RegisteredMethod>();
  registered->method = std::move(method);
  registered->settings = std::move(settings);
  auto entry_made = std::make_unique<narrowphase::NarrowPhaseEntry>();
  narrowphase::NarrowPhaseEntry& entry = *entry_made;
  entry.name = head(name);
  entry.help = registered->settings.help;
  entry.keys = {narrowphase::KeySpec::choice("errors", {"miss", "hit"}, "miss",
                                             "how a pair it gave no answer to counts in the verdicts: as a miss (no), or as a hit at t = 0")};
  std::weak_ptr<const RegisteredMethod> weak = registered;
  entry.make = [weak, full = head(name)](const narrowphase::SpecReader& keys) -> std::unique_ptr<narrowphase::NarrowPhase> {
    auto alive = weak.lock();
    if (!alive) throw std::invalid_argument(full + ": the method is no longer registered");
    return std::make_unique<HostNarrowPhase>(full, std::move(alive), keys.choice("errors") == "hit");
  };
  entry.resolve = [full = head(name)](const narrowphase::SpecReader& keys) { return full + ":errors=" + keys.choice("errors"); };
  static std::vector<std::unique_ptr<const narrowphase::NarrowPhaseEntry>> entries;  // never freed (Registration)
  std::lock_guard lock(host_methods_mutex());
  if (host_methods().count(name) != 0) throw std::invalid_argument("a method named '" + name + "' is registered already");
  entries.push_back(std::move(entry_made));
  host_methods().emplace(name, Registration{std::move(registered), entries.back().get()});
}

void unregister_host_method(const std::string& name) {
  std::shared_ptr<const RegisteredMethod> last;  // freed outside the lock (a Python callable's release may run Python)
  std::lock_guard lock(host_methods_mutex());
  const auto it = host_methods().find(name);
  if (it == host_methods().end()) return;
  last = std::move(it->second.method);
  host_methods().erase(it);
}

bool names_host_method(const std::string& name) { return name.rfind(std::string(kCallableHead) + ":", 0) == 0; }

const narrowphase::NarrowPhaseEntry& host_method_entry(const std::string& name) {
  const std::string short_name = name.substr(std::strlen(kCallableHead) + 1);
  std::lock_guard lock(host_methods_mutex());
  const auto it = host_methods().find(short_name);
  if (it == host_methods().end()) throw std::invalid_argument("no method named '" + short_name + "' is registered (" + name + ")");
  return *it->second.entry;
}

}  // namespace ccd::plugin
