#include "datasets/input_file.hpp"

#include "core/error.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <iterator>
#include <system_error>

namespace ccd::datasets {
namespace {

std::size_t line_of_byte(const std::string& text, std::size_t byte) {
  byte = std::min(byte, text.size());
  return 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(byte), '\n'));
}

}  // namespace

std::ifstream open_input_file(const std::filesystem::path& path, const std::string& what, std::ios::openmode mode) {
  std::error_code error;
  const auto status = std::filesystem::status(path, error);
  if (error || !std::filesystem::exists(status)) throw InputError(path, {}, "no such file (expected a " + what + ")");
  if (std::filesystem::is_directory(status)) throw InputError(path, {}, "is a folder, expected a " + what);
  // A pipe or a device would block or never end (/dev/stdin, /dev/zero); inputs are files whose size is known.
  if (!std::filesystem::is_regular_file(status)) {
    throw InputError(path, {}, "is not a regular file (a pipe or a device?), expected a " + what);
  }
  std::ifstream in(path, mode);
  if (!in) throw InputError(path, {}, "cannot open " + what + " for reading");
  return in;
}

std::string line_at(std::size_t line) { return "line " + std::to_string(line); }

std::uintmax_t input_file_size(const std::filesystem::path& path) {
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  if (error) throw InputError(path, {}, "cannot tell the file's size: " + error.message());
  return size;
}

std::string read_input_text(const std::filesystem::path& path, const std::string& what) {
  std::ifstream in = open_input_file(path, what, std::ios::in | std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(path, {}, "read error");
  return text;
}

nlohmann::json parse_json_text(const std::string& text, const std::filesystem::path& file) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& error) {
    // error.byte is the 1-based position of the last character read.
    throw InputError(file, "line " + std::to_string(line_of_byte(text, error.byte == 0 ? 0 : error.byte - 1)), "malformed JSON");
  } catch (const nlohmann::json::out_of_range& error) {
    // The only range error of parsing: a number too large for a double. nlohmann names the token, not where it
    // is; its first occurrence gives the line.
    const std::string message = error.what();
    const std::size_t open = message.find('\''), close = message.rfind('\'');
    std::string where;
    if (open != std::string::npos && close > open) {
      const std::string token = message.substr(open + 1, close - open - 1);
      const std::size_t at = text.find(token);
      if (at != std::string::npos) where = "line " + std::to_string(line_of_byte(text, at));
      throw InputError(file, where, "number " + token + " is beyond the range of double");
    }
    throw InputError(file, where, "a number is beyond the range of double");
  } catch (const nlohmann::json::exception& error) {
    throw InputError(file, {}, std::string("malformed JSON (") + error.what() + ")");
  }
}

nlohmann::json read_json_file(const std::filesystem::path& path, const std::string& what) {
  return parse_json_text(read_input_text(path, what), path);
}

}  // namespace ccd::datasets
