#pragma once
/// @file
/// Running the ccdbench executable from tests, as a user types it: exit status and everything it printed.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sys/wait.h>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace ccd::testing {

struct CommandResult {
  int exit_code;
  std::string output;  // stdout and stderr together
};

/// Runs a shell command line; stderr is captured with stdout.
inline CommandResult run_command(const std::string& command_line) {
  const std::string command = "(" + command_line + ") 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return {-1, "popen failed"};
  std::string output;
  std::array<char, 4096> buffer;
  while (std::fgets(buffer.data(), buffer.size(), pipe) != nullptr) output += buffer.data();
  const int status = ::pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

/// Runs `ccdbench ARGUMENTS` (in `directory` when given) through the shell.
inline CommandResult run_ccdbench(const std::string& arguments, const std::filesystem::path& directory = {}) {
  const std::string cd = directory.empty() ? std::string() : "cd '" + directory.string() + "' && ";
  return run_command(cd + CCDBENCH_EXECUTABLE + " " + arguments);
}

inline nlohmann::json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

/// The lines of a JSON-lines file, parsed.
inline std::vector<nlohmann::json> read_json_lines(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::vector<nlohmann::json> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(nlohmann::json::parse(line));
  return lines;
}

/// 'PATH', quoted for the shell.
inline std::string quoted(const std::filesystem::path& path) {
  std::string text(1, '\'');
  text.append(path.string()).push_back('\'');
  return text;
}

/// `ccdbench ARGUMENTS --json JSON`: exit status, output and the JSON it wrote (null when it wrote none).
inline std::pair<CommandResult, nlohmann::json> run_ccdbench_with_json(const std::string& arguments, const std::filesystem::path& json) {
  std::filesystem::remove(json);
  CommandResult result = run_ccdbench(arguments + " --json " + quoted(json));
  return {result, std::filesystem::exists(json) ? read_json(json) : nlohmann::json()};
}

/// The summary whose spec (as given) is `spec`; a test failure, and null, when there is none.
inline nlohmann::json cell_of(const nlohmann::json& summaries, const std::string& spec) {
  for (const nlohmann::json& s : summaries) {
    if (s.value("spec", "") == spec) return s;
  }
  ADD_FAILURE() << "no cell for " << spec << " in " << summaries.dump().substr(0, 2000);
  return {};
}

}  // namespace ccd::testing
