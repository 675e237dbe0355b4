#pragma once
/// @file
/// The one error type for bad input: it names the file, where in it, and what is wrong.

#include <filesystem>
#include <stdexcept>
#include <string>

namespace ccd {

/// Bad input (malformed file, NaN, wrong count, topology change...). `what()` reads
/// "FILE:WHERE: REASON", e.g. "cloth/frame_0003.ply:line 17: coordinate y is NaN".
/// The command line prints it and exits non-zero; readers never return half-read data.
class InputError : public std::runtime_error {
 public:
  /// @param file  the offending file (may be empty while a reader without a file raises it)
  /// @param where "line N", "vertex N", "face N", "frame N", "query N"... or empty
  InputError(std::filesystem::path file, std::string where, std::string reason);

  const std::filesystem::path& file() const { return file_; }
  const std::string& where() const { return where_; }
  const std::string& reason() const { return reason_; }

  /// The same error, attributed to `file` (for errors raised below the reader that knows the file).
  InputError in_file(const std::filesystem::path& file) const { return {file, where_, reason_}; }

 private:
  std::filesystem::path file_;
  std::string where_;
  std::string reason_;
};

}  // namespace ccd
