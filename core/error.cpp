#include "core/error.hpp"

namespace ccd {
namespace {

std::string format_input_error(const std::filesystem::path& file, const std::string& where, const std::string& reason) {
  std::string text = file.empty() ? std::string() : file.string() + ":";
  if (!where.empty()) text += where + ":";
  if (!text.empty()) text += " ";
  return text + reason;
}

}  // namespace

InputError::InputError(std::filesystem::path file, std::string where, std::string reason)
    : std::runtime_error(format_input_error(file, where, reason)), file_(std::move(file)), where_(std::move(where)), reason_(std::move(reason)) {}

}  // namespace ccd
