#include "strategies/plugin/library.hpp"

#include <dlfcn.h>
#include <xxhash.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace ccd::plugin {
namespace {

/// A plugin's key names are letters, digits and '_' (they go into specs and file names).
bool plain_name(const char* name) {
  if (name == nullptr || *name == '\0') return false;
  for (const char* c = name; *c; ++c) {
    if (!((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9') || *c == '_')) return false;
  }
  return true;
}

std::string text_or(const char* text, const char* fallback) { return text != nullptr ? text : fallback; }

void hash_file(XXH3_state_t* state, const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  char buffer[1 << 16];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) XXH3_128bits_update(state, buffer, static_cast<std::size_t>(in.gcount()));
}

}  // namespace

std::string content_digest(const std::filesystem::path& path) {
  XXH3_state_t* state = XXH3_createState();
  XXH3_128bits_reset(state);
  if (std::filesystem::is_directory(path)) {
    std::vector<std::filesystem::path> files;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(path)) {
      if (entry.is_regular_file()) files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    for (const std::filesystem::path& file : files) {
      const std::string name = std::filesystem::relative(file, path).generic_string();
      XXH3_128bits_update(state, name.c_str(), name.size() + 1);
      hash_file(state, file);
      const char separator = '\0';
      XXH3_128bits_update(state, &separator, 1);
    }
  } else {
    hash_file(state, path);
  }
  const XXH128_hash_t hash = XXH3_128bits_digest(state);
  XXH3_freeState(state);
  char text[33];
  std::snprintf(text, sizeof text, "%016llx%016llx", static_cast<unsigned long long>(hash.high64), static_cast<unsigned long long>(hash.low64));
  return text;
}

namespace {

// A plugin's timeout under isolation: from a millisecond (a test of one) to a day (a whole step of a huge mesh).
constexpr narrowphase::SpecRange kTimeoutRange{0.001, 86400};

}  // namespace

Library::Library(const std::filesystem::path& given) {
  std::error_code error;
  const std::filesystem::path absolute = std::filesystem::weakly_canonical(std::filesystem::absolute(given), error);
  path_ = (error ? std::filesystem::absolute(given) : absolute).string();
  auto refuse = [&](const std::string& reason) { return std::invalid_argument("plugin " + path_ + ": " + reason); };
  if (!std::filesystem::is_regular_file(path_)) throw refuse("no such file");
  handle_ = ::dlopen(path_.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle_ == nullptr) throw refuse(std::string("cannot be loaded: ") + text_or(::dlerror(), "dlopen failed"));
  const auto entry = reinterpret_cast<ccdbench_plugin_entry>(::dlsym(handle_, CCDBENCH_PLUGIN_ENTRY_NAME));
  if (entry == nullptr) throw refuse("exports no " CCDBENCH_PLUGIN_ENTRY_NAME " (see ccdbench_plugin.h)");
  table_ = entry(CCDBENCH_PLUGIN_ABI_VERSION);
  if (table_ == nullptr) throw refuse("its entry point returned no table for ABI version " + std::to_string(CCDBENCH_PLUGIN_ABI_VERSION));
  // Size and version first: they are the only fields every ABI version keeps in place.
  if (table_->abi_version != CCDBENCH_PLUGIN_ABI_VERSION) {
    throw refuse("built for plugin ABI version " + std::to_string(table_->abi_version) + ", but this ccdbench speaks version " +
                 std::to_string(CCDBENCH_PLUGIN_ABI_VERSION) + ": rebuild it against this ccdbench's ccdbench_plugin.h");
  }
  if (table_->size < sizeof(ccdbench_plugin)) {
    throw refuse("its table is " + std::to_string(table_->size) + " bytes, smaller than ABI version " + std::to_string(CCDBENCH_PLUGIN_ABI_VERSION) +
                 "'s " + std::to_string(sizeof(ccdbench_plugin)));
  }
  const std::string name = text_or(table_->name, "");
  if (name.empty() || name.find_first_of(": \t\n") != std::string::npos) throw refuse("its name must be non-empty, without ':' or spaces");
  if (table_->create == nullptr || table_->destroy == nullptr) throw refuse("has no create or no destroy function");
  const bool queries = table_->vertex_face != nullptr || table_->edge_edge != nullptr;
  if (queries && !answers_queries()) throw refuse("answers vertex-face queries or edge-edge queries, not both");
  if (!queries && table_->step == nullptr) throw refuse("answers neither queries nor steps");
  const std::vector<narrowphase::KeySpec> host = host_keys();
  for (std::size_t k = 0; k < table_->key_count; ++k) {
    const ccdbench_key& key = table_->keys[k];
    if (!plain_name(key.name)) throw refuse("key " + std::to_string(k) + ": its name must be letters, digits and '_'");
    for (const narrowphase::KeySpec& own : host) {
      if (own.name == key.name) throw refuse("key '" + own.name + "' is one of ccdbench's own keys for every plugin");
    }
    const std::string help = text_or(key.help, "");
    narrowphase::KeySpec spec;
    switch (key.kind) {
      case CCDBENCH_KEY_NUMBER:
      case CCDBENCH_KEY_INTEGER: {
        const bool integer = key.kind == CCDBENCH_KEY_INTEGER;
        if (!(key.minimum <= key.maximum)) throw refuse("key '" + std::string(key.name) + "': its minimum exceeds its maximum");
        spec = integer ? narrowphase::KeySpec::integer(key.name, 0, {key.minimum, key.maximum}, help)
                       : narrowphase::KeySpec::number(key.name, 0, {key.minimum, key.maximum}, help);
        const double value =
            narrowphase::parse_spec_number("plugin " + std::string(table_->name), key.name, text_or(key.default_value, ""), spec.range);
        spec.default_value = integer ? std::to_string(static_cast<long>(value)) : narrowphase::format_spec_number(value);
        break;
      }
      case CCDBENCH_KEY_CHOICE: {
        std::vector<std::string> choices;
        std::istringstream list(text_or(key.choices, ""));
        for (std::string choice; std::getline(list, choice, '|');) choices.push_back(choice);
        spec = narrowphase::KeySpec::choice(key.name, choices, text_or(key.default_value, ""), help);
        if (std::find(choices.begin(), choices.end(), spec.default_value) == choices.end()) {
          throw refuse("key '" + std::string(key.name) + "': its default is not one of its choices");
        }
        break;
      }
      case CCDBENCH_KEY_TEXT:
        spec = narrowphase::KeySpec::text(key.name, help);
        spec.default_value = text_or(key.default_value, "");
        break;
      default: throw refuse("key '" + std::string(key.name) + "': unknown kind " + std::to_string(key.kind));
    }
    keys_.push_back(std::move(spec));
  }
  digest_ = content_digest(path_);
}

Library::~Library() {
  // Not unloaded: a plugin may have registered atexit handlers or thread-local destructors that run later.
}

std::string Library::description() const {
  std::string text = std::string(table_->name) + " " + text_or(table_->version, "") + ": " + text_or(table_->help, "") + " (";
  text += reports_toi() ? "reports TOIs" : "yes or no, no TOIs";
  text += thread_safe() ? "; thread-safe" : "; not thread-safe: runs on one thread";
  if (conservative()) text += "; claims to be conservative";
  return text + ")";
}

std::shared_ptr<const Library> load_library(const std::string& path) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const Library>> loaded;
  std::lock_guard lock(mutex);
  const std::string key = std::filesystem::absolute(path).lexically_normal().string();
  auto it = loaded.find(key);
  if (it == loaded.end()) it = loaded.emplace(key, std::make_shared<const Library>(path)).first;
  return it->second;
}

std::vector<narrowphase::KeySpec> host_keys() {
  using narrowphase::KeySpec;
  const HostSettings defaults;
  return {KeySpec::text("digest", "the plugin file's digest (filled in; a cell kept for another build of the plugin is never reused)"),
          KeySpec::choice("errors", {"miss", "hit"}, "miss",
                          "how an error or undecided answer counts for verdicts and the gate (it is also counted apart)"),
          KeySpec::on_off("isolate", defaults.isolate, "run the plugin in a child process: a crash or a hang is an error, not the end of the run"),
          KeySpec::number("timeout", defaults.timeout_seconds, kTimeoutRange, "with isolate=on: seconds a query or a step may take")};
}

std::vector<narrowphase::KeySpec> entry_keys(const Library& library) {
  std::vector<narrowphase::KeySpec> keys = library.keys();
  for (narrowphase::KeySpec& key : host_keys()) keys.push_back(std::move(key));
  return keys;
}

HostSettings read_host_settings(const narrowphase::SpecReader& keys, const Library& library) {
  HostSettings settings;
  settings.digest = keys.text("digest");
  if (!settings.digest.empty() && settings.digest != library.digest()) {
    throw std::invalid_argument("plugin " + library.path() + ": its file changed (digest " + library.digest() + ", the spec asks for " +
                                settings.digest + "): a result of the other build cannot be reused or compared as this one's");
  }
  settings.digest = library.digest();
  settings.errors_count_as_hits = keys.choice("errors") == "hit";
  settings.isolate = keys.choice("isolate") == "on";
  settings.timeout_seconds = keys.number("timeout");
  return settings;
}

std::vector<std::string> plugin_values(const narrowphase::SpecReader& keys, const Library& library) {
  std::vector<std::string> values;
  for (const narrowphase::KeySpec& key : library.keys()) {
    switch (key.kind) {
      case narrowphase::KeySpec::Kind::number: values.push_back(narrowphase::format_spec_number(keys.number(key.name))); break;
      case narrowphase::KeySpec::Kind::integer: values.push_back(std::to_string(keys.integer(key.name))); break;
      case narrowphase::KeySpec::Kind::choice: values.push_back(keys.choice(key.name)); break;
      case narrowphase::KeySpec::Kind::text: values.push_back(keys.text(key.name)); break;
    }
  }
  return values;
}

std::string resolved_name(const Library& library, const std::vector<std::string>& values, const HostSettings& host) {
  std::string name = std::string(narrowphase::kPluginHead) + ":" + library.path();
  for (std::size_t k = 0; k < values.size(); ++k) name += ":" + library.keys()[k].name + "=" + values[k];
  name += ":digest=" + host.digest + ":errors=" + (host.errors_count_as_hits ? "hit" : "miss");
  // Isolation changes no answer, only what a crash does: off, the default, is not printed.
  if (host.isolate) name += ":isolate=on:timeout=" + narrowphase::format_spec_number(host.timeout_seconds);
  return name;
}

Context::Context(std::shared_ptr<const Library> library, const std::vector<std::string>& values) : library_(std::move(library)) {
  std::vector<const char*> pointers;
  for (const std::string& value : values) pointers.push_back(value.c_str());
  char error[CCDBENCH_MESSAGE_SIZE] = {};
  handle_ = library_->table().create(pointers.data(), error);
  if (handle_ == nullptr) {
    error[CCDBENCH_MESSAGE_SIZE - 1] = '\0';
    throw std::invalid_argument("plugin " + std::string(library_->table().name) +
                                ": its configuration was refused: " + (error[0] ? error : "no reason given"));
  }
}

Context::~Context() {
  if (handle_ != nullptr) library_->table().destroy(handle_);
}

}  // namespace ccd::plugin
