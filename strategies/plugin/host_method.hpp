#pragma once
/// @file
/// Methods the calling program provides (the C++ API's register_method; Python's callables enter this way) as
/// narrow phases of the registry: `callable:NAME[:errors=miss|hit]` wherever a narrow phase is named (query
/// scoring, `full+callable:NAME` in a run). Such code is under audit as a plugin is (docs/DESIGN.md §10): it is asked
/// in batches from one thread, it gets a copy of the pairs' rows, and an exception, an answer of the wrong size, a
/// TOI that is not a number in [0, 1] or a change of the floating-point environment is an error of the pairs it
/// concerns, counted apart (a batch that throws is asked again one pair at a time, so the error lands on its pair).
/// What it changes of the process (the floating-point environment, the working directory, the C locale) is put back
/// and is the call's error. It runs in the caller's process: a crash or a hang inside it is the caller's, as with
/// `isolate=off`; its answers can change between passes, which the cell's audit pass reports as a plugin's.

#include "strategies/narrowphase/entry.hpp"
#include "strategies/narrowphase/spec.hpp"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace ccd::plugin {

inline constexpr const char* kCallableHead = narrowphase::kHostMethodHead;

// HostBatch and HostAnswers are deliberately not the C++ API's MethodBatch and MethodAnswers
// (api/ccdbench/ccdbench.hpp), though both carry one batch's pairs and answers: those are the installed API's, in its
// words (PairKind, Rows), and change only with its major version; these are this layer's, in the narrow phases' words
// (NarrowPhase's vertex_face flag, rows as flat doubles as a plugin gets them), free to change, and strategies/ must
// not include api/. The API's register_method (api/ccdbench.cpp) translates one into the other.

/// One batch asked of a host method: `count` pairs of one kind, their rows flat (24 doubles a pair, in
/// Tight-Inclusion's order), at thickness δ.
struct HostBatch {
  bool vertex_face = true;
  const double* rows = nullptr;
  std::size_t count = 0;
  double thickness = 0;
};

/// Its answers, one per pair: 1 contact, 0 apart; the TOI (none at all: a method without TOIs; NaN on a contact is
/// an error); a message where it gave no answer (empty or absent: answered).
struct HostAnswers {
  std::vector<std::uint8_t> hits;
  std::vector<double> tois;
  std::vector<std::string> errors;
};

/// Throws a std::exception to say the whole batch got no answer (the message says why), or HostMethodInterrupted.
using HostMethod = std::function<void(const HostBatch&, HostAnswers&)>;

/// Thrown by a method to end the call that runs it (the user's interrupt: Python's KeyboardInterrupt, SystemExit):
/// not a std::exception, so no one counts it as the pairs' error; the C++ API turns it into its MethodInterrupted.
struct HostMethodInterrupted {
  std::string message;
};

struct HostMethodSettings {
  /// Pairs asked at a time; 0: every pair of a step (of one kind) or of a file in one call.
  std::size_t batch = 0;
  std::string help = "a method the calling program provides";
};

/// Makes `callable:NAME` name `method` in this process until unregistered. @throws std::invalid_argument for a name
/// that is empty or holds ':' or '+', or that is taken.
void register_host_method(const std::string& name, HostMethod method, HostMethodSettings settings);
void unregister_host_method(const std::string& name);

/// Whether `name` is `callable:...`.
bool names_host_method(const std::string& name);

/// The registry's entry for `callable:NAME`. @throws std::invalid_argument when no method of that name is registered.
const narrowphase::NarrowPhaseEntry& host_method_entry(const std::string& name);

}  // namespace ccd::plugin
