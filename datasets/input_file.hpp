#pragma once
/// @file
/// Opening input files the same way in every reader: a missing file, a folder where a file is expected and an
/// unreadable file are InputErrors naming the path; JSON documents are parsed with the line of any error, numbers
/// beyond the range of double included.

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace ccd::datasets {

/// Opens `path` for reading. @param what names the expected content in messages ("PLY file", "scene file").
/// @throws InputError (path) when it does not exist, is a folder or not a regular file (a pipe, a device), or cannot
///         be opened.
std::ifstream open_input_file(const std::filesystem::path& path, const std::string& what, std::ios::openmode mode = std::ios::in);

/// "line N": where in a text file an InputError points (1-based).
std::string line_at(std::size_t line);

/// The size of an input file in bytes, for checking counts in headers against the bytes that back them.
/// @throws InputError when it cannot be determined.
std::uintmax_t input_file_size(const std::filesystem::path& path);

/// The whole file as text. @throws InputError as open_input_file.
std::string read_input_text(const std::filesystem::path& path, const std::string& what);

/// Parses JSON text; `file` names errors. Malformed text, and numbers that overflow a double (`1e999`), become
/// InputError(file, "line N", reason).
nlohmann::json parse_json_text(const std::string& text, const std::filesystem::path& file);

/// read_input_text + parse_json_text.
nlohmann::json read_json_file(const std::filesystem::path& path, const std::string& what);

}  // namespace ccd::datasets
