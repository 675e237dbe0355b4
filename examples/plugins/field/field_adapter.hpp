// What the field's adapters share (reports/field/README.md): the two rules every adapter follows where its library
// leaves a choice, so that no adapter answers for its library.
//  - A method without a minimum separation is not asked at δ > 0: the query is an error saying so (counted apart,
//    never a miss or a hit), so that a table at δ > 0 never holds a δ = 0 answer judged at δ.
//  - A library that throws a C string (several do) has it rethrown as std::runtime_error, whose message
//    CCDBENCH_PLUGIN_FROM_CCD_CLASS writes into the query's error: the fault is the library's, shown with its words.
#ifndef CCDBENCH_FIELD_ADAPTER_HPP
#define CCDBENCH_FIELD_ADAPTER_HPP

#include <Eigen/Core>

#include <cstdio>
#include <stdexcept>
#include <string>

/// The library's commit, given by scripts/field/build.sh (the plugin's version, in every record's provenance).
#ifndef FIELD_LIBRARY_COMMIT
#define FIELD_LIBRARY_COMMIT "unknown"
#endif

namespace field {

/// Refuses δ > 0 for a method that has no minimum separation (an error of the query, with this message).
inline void require_zero_thickness(double min_distance) {
  if (min_distance != 0) {
    char message[128];
    std::snprintf(message, sizeof message, "takes no minimum separation: not asked at δ = %.17g", min_distance);
    throw std::invalid_argument(message);
  }
}

/// Calls `call`, turning a C string the library throws into an exception that carries its words.
template <class Call>
auto keeping_library_messages(Call&& call) -> decltype(call()) {
  try {
    return call();
  } catch (const char* message) {
    throw std::runtime_error(std::string("the library threw: ") + message);
  }
}

}  // namespace field

#endif  // CCDBENCH_FIELD_ADAPTER_HPP
