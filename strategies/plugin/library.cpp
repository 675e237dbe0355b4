#include "strategies/plugin/library.hpp"

#include "ccd/config.hpp"

#include <dlfcn.h>
#include <link.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace ccd::plugin {
namespace {

/// A plugin's key names are letters, digits and '_' (they go into specs and file names).
bool plain_name(const std::string& name) {
  if (name.empty()) return false;
  for (const char c : name) {
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_')) return false;
  }
  return true;
}

std::string text_or(const char* text, const char* fallback) { return text != nullptr ? text : fallback; }

// A plugin's timeout: from a millisecond (a test of one) to a day (a whole step of a huge mesh).
constexpr narrowphase::SpecRange kTimeoutRange{0.001, 86400};
// Queries per batch to an isolated child: one (a pipe round trip each) to the shared region's capacity.
constexpr narrowphase::SpecRange kBatchRange{1, 4096, true};

/// isolate='s value when a spec does not give one (set_default_isolation).
std::atomic<bool> default_isolation{true};

/// The table's fields as plain data. Only what its size says it holds is read: a table of another ABI version, or
/// a shorter one, keeps its size and version alone, and `describe` refuses it.
PluginTable read_table(const ccdbench_plugin& table) {
  PluginTable plain;
  plain.size = table.size;
  plain.abi_version = table.abi_version;
  if (table.abi_version != CCDBENCH_PLUGIN_ABI_VERSION || table.size < sizeof(ccdbench_plugin)) return plain;
  plain.name = text_or(table.name, "");
  plain.version = text_or(table.version, "");
  plain.help = text_or(table.help, "");
  plain.capabilities = table.capabilities;
  for (std::size_t k = 0; k < table.key_count; ++k) {
    const ccdbench_key& key = table.keys[k];
    plain.keys.push_back(
        {text_or(key.name, ""), key.kind, text_or(key.default_value, ""), key.minimum, key.maximum, text_or(key.choices, ""), text_or(key.help, "")});
  }
  plain.has_create = table.create != nullptr;
  plain.has_destroy = table.destroy != nullptr;
  plain.has_vertex_face = table.vertex_face != nullptr;
  plain.has_edge_edge = table.edge_edge != nullptr;
  plain.has_step = table.step != nullptr;
  return plain;
}

}  // namespace

PluginDescription describe(const std::string& path, const PluginTable& table, std::vector<LoadedObject> objects, std::string environment_at_load) {
  auto refuse = [&](const std::string& reason) { return std::invalid_argument("plugin " + path + ": " + reason); };
  // Size and version first: they are the only fields every ABI version keeps in place.
  if (table.abi_version != CCDBENCH_PLUGIN_ABI_VERSION) {
    throw refuse("built for plugin ABI version " + std::to_string(table.abi_version) + ", but this ccdbench speaks version " +
                 std::to_string(CCDBENCH_PLUGIN_ABI_VERSION) + ": rebuild it against this ccdbench's ccdbench_plugin.h");
  }
  if (table.size < sizeof(ccdbench_plugin)) {
    throw refuse("its table is " + std::to_string(table.size) + " bytes, smaller than ABI version " + std::to_string(CCDBENCH_PLUGIN_ABI_VERSION) +
                 "'s " + std::to_string(sizeof(ccdbench_plugin)));
  }
  if (table.name.empty() || table.name.find_first_of(": \t\n") != std::string::npos)
    throw refuse("its name must be non-empty, without ':' or spaces");
  if (!table.has_create || !table.has_destroy) throw refuse("has no create or no destroy function");
  const bool queries = table.has_vertex_face || table.has_edge_edge;
  if (queries && !(table.has_vertex_face && table.has_edge_edge)) throw refuse("answers vertex-face queries or edge-edge queries, not both");
  if (!queries && !table.has_step) throw refuse("answers neither queries nor steps");
  PluginDescription description;
  description.path = path;
  description.table = table;
  const std::vector<narrowphase::KeySpec> host = host_keys();
  for (std::size_t k = 0; k < table.keys.size(); ++k) {
    const TableKey& key = table.keys[k];
    if (!plain_name(key.name)) throw refuse("key " + std::to_string(k) + ": its name must be letters, digits and '_'");
    // A value goes into the resolved name as key=value between ':' (a spec's words): one with ':' would read back as
    // other keys (a default "a:errors=hit" would show errors=hit in the name where errors=miss was used).
    if (key.default_value.find(':') != std::string::npos || key.choices.find(':') != std::string::npos) {
      throw refuse("key '" + key.name + "': its default and choices may not hold ':' (it separates a spec's keys)");
    }
    for (const narrowphase::KeySpec& own : host) {
      if (own.name == key.name) throw refuse("key '" + own.name + "' is one of ccdbench's own keys for every plugin");
    }
    narrowphase::KeySpec spec;
    switch (key.kind) {
      case CCDBENCH_KEY_NUMBER:
      case CCDBENCH_KEY_INTEGER: {
        const bool integer = key.kind == CCDBENCH_KEY_INTEGER;
        if (!(key.minimum <= key.maximum)) throw refuse("key '" + key.name + "': its minimum exceeds its maximum");
        spec = integer ? narrowphase::KeySpec::integer(key.name, 0, {key.minimum, key.maximum}, key.help)
                       : narrowphase::KeySpec::number(key.name, 0, {key.minimum, key.maximum}, key.help);
        const double value = narrowphase::parse_spec_number("plugin " + table.name, key.name, key.default_value, spec.range);
        spec.default_value = integer ? std::to_string(static_cast<long>(value)) : narrowphase::format_spec_number(value);
        break;
      }
      case CCDBENCH_KEY_CHOICE: {
        std::vector<std::string> choices;
        std::istringstream list(key.choices);
        for (std::string choice; std::getline(list, choice, '|');) choices.push_back(choice);
        spec = narrowphase::KeySpec::choice(key.name, choices, key.default_value, key.help);
        if (std::find(choices.begin(), choices.end(), spec.default_value) == choices.end()) {
          throw refuse("key '" + key.name + "': its default is not one of its choices");
        }
        break;
      }
      case CCDBENCH_KEY_TEXT:
        spec = narrowphase::KeySpec::text(key.name, key.help);
        spec.default_value = key.default_value;
        break;
      default: throw refuse("key '" + key.name + "': unknown kind " + std::to_string(key.kind));
    }
    description.keys.push_back(std::move(spec));
  }
  if (objects.empty()) throw refuse("no code of it was found loaded");
  description.objects = std::move(objects);
#if CCDBENCH_GUARD_IDENTITY
  description.digest = combined_digest(description.objects);
#else
  // Without the guard: the plugin's file alone, read apart from its load.
  description.digest = content_digest(path);
#endif
  description.environment_at_load = std::move(environment_at_load);
  return description;
}

std::string PluginDescription::description() const {
  std::string text = table.name + " " + table.version + ": " + table.help + " (";
  text += reports_toi() ? "reports TOIs" : "yes or no, no TOIs";
  text += thread_safe() ? "; thread-safe" : "; not thread-safe: runs on one thread";
  if (conservative()) text += "; claims to be conservative";
  if (!environment_at_load.empty()) text += "; its load changes the floating-point environment: " + environment_at_load;
  return text + ")";
}

std::string PluginDescription::label() const { return "plugin " + (table.name.empty() ? std::string("?") : table.name) + " (" + path + ")"; }

namespace {

// The description's wire form: fields in a fixed order, each string as a 32-bit length and its bytes.
void put_text(std::vector<char>& out, const std::string& text) {
  const auto size = static_cast<std::uint32_t>(text.size());
  out.insert(out.end(), reinterpret_cast<const char*>(&size), reinterpret_cast<const char*>(&size) + sizeof size);
  out.insert(out.end(), text.begin(), text.end());
}
template <class T>
void put_value(std::vector<char>& out, const T& value) {
  out.insert(out.end(), reinterpret_cast<const char*>(&value), reinterpret_cast<const char*>(&value) + sizeof value);
}

/// Reads what a child sent, never past its end: a reply that stops short or holds more is not a description.
class Reader {
 public:
  Reader(std::string_view bytes, const std::string& path) : bytes_(bytes), path_(path) {}
  template <class T>
  T value() {
    T v;
    need(sizeof v);
    std::memcpy(&v, bytes_.data() + at_, sizeof v);
    at_ += sizeof v;
    return v;
  }
  std::string text() {
    const auto size = value<std::uint32_t>();
    need(size);
    std::string text(bytes_.substr(at_, size));
    at_ += size;
    return text;
  }
  /// A count of items of at least `item_bytes` each, backed by the bytes left.
  std::size_t count(std::size_t item_bytes) {
    const auto n = value<std::uint32_t>();
    if (static_cast<std::size_t>(n) * item_bytes > bytes_.size() - at_) throw bad("a count the reply does not back");
    return n;
  }
  void end() const {
    if (at_ != bytes_.size()) throw bad("bytes after its end");
  }

 private:
  void need(std::size_t size) const {
    if (size > bytes_.size() - at_) throw bad("it stops short");
  }
  std::invalid_argument bad(const std::string& why) const {
    return std::invalid_argument("plugin " + path_ + ": its child process sent a description ccdbench cannot read (" + why + ")");
  }
  std::string_view bytes_;
  const std::string& path_;
  std::size_t at_ = 0;
};

}  // namespace

std::vector<char> encode(const PluginDescription& d) {
  std::vector<char> out;
  const PluginTable& t = d.table;
  put_value(out, t.size);
  put_value(out, t.abi_version);
  put_text(out, t.name);
  put_text(out, t.version);
  put_text(out, t.help);
  put_value(out, t.capabilities);
  put_value(out, static_cast<std::uint32_t>(t.keys.size()));
  for (const TableKey& key : t.keys) {
    put_text(out, key.name);
    put_value(out, static_cast<std::int32_t>(key.kind));
    put_text(out, key.default_value);
    put_value(out, key.minimum);
    put_value(out, key.maximum);
    put_text(out, key.choices);
    put_text(out, key.help);
  }
  const std::uint8_t functions =
      (t.has_create ? 1 : 0) | (t.has_destroy ? 2 : 0) | (t.has_vertex_face ? 4 : 0) | (t.has_edge_edge ? 8 : 0) | (t.has_step ? 16 : 0);
  put_value(out, functions);
  put_value(out, static_cast<std::uint32_t>(d.objects.size()));
  for (const LoadedObject& object : d.objects) {
    put_text(out, object.path);
    put_text(out, object.digest);
  }
  put_text(out, d.environment_at_load);
  return out;
}

PluginDescription decode_description(const std::string& path, std::string_view bytes) {
  Reader in(bytes, path);
  PluginTable t;
  t.size = in.value<std::uint64_t>();
  t.abi_version = in.value<std::uint32_t>();
  t.name = in.text();
  t.version = in.text();
  t.help = in.text();
  t.capabilities = in.value<std::uint32_t>();
  const std::size_t keys = in.count(2 * sizeof(double));
  for (std::size_t k = 0; k < keys; ++k) {
    TableKey key;
    key.name = in.text();
    key.kind = in.value<std::int32_t>();
    key.default_value = in.text();
    key.minimum = in.value<double>();
    key.maximum = in.value<double>();
    key.choices = in.text();
    key.help = in.text();
    t.keys.push_back(std::move(key));
  }
  const auto functions = in.value<std::uint8_t>();
  t.has_create = functions & 1;
  t.has_destroy = functions & 2;
  t.has_vertex_face = functions & 4;
  t.has_edge_edge = functions & 8;
  t.has_step = functions & 16;
  std::vector<LoadedObject> objects(in.count(2 * sizeof(std::uint32_t)));
  for (LoadedObject& object : objects) {
    object.path = in.text();
    object.digest = in.text();
  }
  std::string environment = in.text();
  in.end();
  // Checked as a table loaded here would be; its digest is made here from the objects' digests the child sent.
  return describe(path, t, objects, environment);
}

Library::Library(const std::filesystem::path& given) {
  std::error_code error;
  const std::filesystem::path absolute = std::filesystem::weakly_canonical(std::filesystem::absolute(given), error);
  const std::string path = (error ? std::filesystem::absolute(given) : absolute).string();
  auto refuse = [&](const std::string& reason) { return std::invalid_argument("plugin " + path + ": " + reason); };
  if (!std::filesystem::is_regular_file(path)) throw refuse("no such file");
  const std::vector<LinkMapEntry> before = link_map();
  PluginLoad load("plugin " + path);
  handle_ = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle_ == nullptr) {
    load.finish();
    throw refuse(std::string("cannot be loaded: ") + text_or(::dlerror(), "dlopen failed"));
  }
  const auto entry = reinterpret_cast<ccdbench_plugin_entry>(::dlsym(handle_, CCDBENCH_PLUGIN_ENTRY_NAME));
  table_ = entry != nullptr ? entry(CCDBENCH_PLUGIN_ABI_VERSION) : nullptr;
  const PluginLoad::Finished loaded = load.finish();
  environment_ = loaded.environment;
  if (!loaded.refused.empty()) throw refuse("while it was loaded, " + loaded.refused);
  if (entry == nullptr) throw refuse("exports no " CCDBENCH_PLUGIN_ENTRY_NAME " (see ccdbench_plugin.h)");
  if (table_ == nullptr) throw refuse("its entry point returned no table for ABI version " + std::to_string(CCDBENCH_PLUGIN_ABI_VERSION));
  std::vector<LoadedObject> objects;
  try {
    objects = objects_loaded_since(before);
    // Nothing new: the process had this library already (under another name of the same file); it is then itself,
    // as the loader has it, and what it brought in came with it before.
    struct link_map* map = nullptr;
    if (objects.empty() && ::dlinfo(handle_, RTLD_DI_LINKMAP, &map) == 0 && map != nullptr) objects.push_back(loaded_object(map->l_name));
  } catch (const std::runtime_error& changed) {
    throw refuse(changed.what());
  }
#if !CCDBENCH_GUARD_IDENTITY
  objects.resize(std::min<std::size_t>(objects.size(), 1));
#endif
  description_ = describe(path, read_table(*table_), std::move(objects), describe_change(FpEnvironment::current(), environment_));
}

Library::~Library() {
  // Not unloaded: a plugin may have registered atexit handlers or thread-local destructors that run later.
}

namespace {

/// Libraries loaded into this process, by absolute path, and descriptions made, kept for the process.
std::mutex& registry_mutex() {
  static std::mutex mutex;
  return mutex;
}

/// The library at `path` (absolute), loaded into this process once: a second dlopen of it would bring nothing new.
/// The caller holds registry_mutex.
std::shared_ptr<const Library> library_at(const std::string& path) {
  static std::map<std::string, std::shared_ptr<const Library>> loaded;
  auto it = loaded.find(path);
  if (it == loaded.end()) it = loaded.emplace(path, std::make_shared<const Library>(path)).first;
  return it->second;
}

}  // namespace

std::shared_ptr<const Library> library_loaded_at(const std::string& path) {
  std::lock_guard lock(registry_mutex());
  return library_at(path);
}

std::shared_ptr<const Library> load_library(const PluginDescription& description) {
  std::lock_guard lock(registry_mutex());
  std::shared_ptr<const Library> loaded = library_at(description.path);
#if CCDBENCH_GUARD_IDENTITY
  // Once, when it is first loaded here: the code in this process does not change after that.
  static std::map<std::string, std::string> differences;
  auto it = differences.find(description.path);
  if (it == differences.end())
    it = differences.emplace(description.path, differs_from_loaded(description.objects, loaded->description().objects)).first;
  if (!it->second.empty()) {
    throw std::invalid_argument("plugin " + description.path + ": the code loaded into this process is not the code a child process described (" +
                                it->second + "): its file or a library it links changed in between");
  }
#endif
  return loaded;
}

std::vector<narrowphase::KeySpec> host_keys() {
  using narrowphase::KeySpec;
  const HostSettings defaults;
  return {KeySpec::text("digest", "the digest of the plugin's code as loaded (filled in; a cell kept for another build is never reused)"),
          KeySpec::choice("errors", {"miss", "hit"}, "miss",
                          "how an error or undecided answer counts for verdicts and the gate (it is also counted apart)"),
          KeySpec::on_off("isolate", default_isolation.load(),
                          "run the plugin in a child process (the default): a crash, an exit or a hang is that call's error, not the end of the run"),
          KeySpec::number("timeout", defaults.timeout_seconds, kTimeoutRange,
                          "seconds a query or a step may take (isolated: that call's error; in-process: the run ends)"),
          KeySpec::integer("batch", defaults.batch, kBatchRange, "isolated: queries sent to the child at a time (1: a pipe round trip each)")};
}

std::vector<narrowphase::KeySpec> entry_keys(const PluginDescription& description) {
  std::vector<narrowphase::KeySpec> keys = description.keys;
  for (narrowphase::KeySpec& key : host_keys()) keys.push_back(std::move(key));
  return keys;
}

HostSettings read_host_settings(const narrowphase::SpecReader& keys, const PluginDescription& description) {
  HostSettings settings;
  settings.digest = keys.text("digest");
  if (!settings.digest.empty() && settings.digest != description.digest) {
    throw std::invalid_argument("plugin " + description.path + ": its code changed (digest " + description.digest + ", the spec asks for " +
                                settings.digest + "): a result of the other build cannot be reused or compared as this one's");
  }
  settings.digest = description.digest;
  settings.errors_count_as_hits = keys.choice("errors") == "hit";
  settings.isolate = keys.choice("isolate") == "on";
  settings.timeout_seconds = keys.number("timeout");
  settings.batch = keys.integer("batch");
  return settings;
}

void set_default_isolation(bool isolate) { default_isolation = isolate; }

std::vector<std::string> plugin_values(const narrowphase::SpecReader& keys, const PluginDescription& description) {
  std::vector<std::string> values;
  for (const narrowphase::KeySpec& key : description.keys) {
    switch (key.kind) {
      case narrowphase::KeySpec::Kind::number: values.push_back(narrowphase::format_spec_number(keys.number(key.name))); break;
      case narrowphase::KeySpec::Kind::integer: values.push_back(std::to_string(keys.integer(key.name))); break;
      case narrowphase::KeySpec::Kind::choice: values.push_back(keys.choice(key.name)); break;
      case narrowphase::KeySpec::Kind::text: values.push_back(keys.text(key.name)); break;
    }
  }
  return values;
}

std::string resolved_name(const PluginDescription& description, const std::vector<std::string>& values, const HostSettings& host) {
  std::string name = std::string(narrowphase::kPluginHead) + ":" + description.path;
  for (std::size_t k = 0; k < values.size(); ++k) name += ":" + description.keys[k].name + "=" + values[k];
  name += ":digest=" + host.digest + ":errors=" + (host.errors_count_as_hits ? "hit" : "miss");
  // Where it runs and its timeout decide what a crash or a hang does (an error, or the run's end): both are named.
  // Isolated, its batch size changes only the time, but times are results too (and a table compares batch sizes).
  name += std::string(":isolate=") + (host.isolate ? "on" : "off") + ":timeout=" + narrowphase::format_spec_number(host.timeout_seconds);
  if (host.isolate) name += ":batch=" + std::to_string(host.batch);
  return name;
}

Context::Context(std::shared_ptr<const Library> library, const std::vector<std::string>& values, double timeout_seconds)
    : library_(std::move(library)), site_{library_->description().label(), library_->environment(), timeout_seconds} {
  std::vector<const char*> pointers;
  for (const std::string& value : values) pointers.push_back(value.c_str());
  char error[CCDBENCH_MESSAGE_SIZE] = {};
  std::string fault = guarded_call(site_, "create", [&] { handle_ = library_->table().create(pointers.data(), error); });
  if (handle_ != nullptr && !fault.empty()) {
    guarded_call(site_, "destroy", [&] { library_->table().destroy(handle_); });
    handle_ = nullptr;
  }
  if (handle_ == nullptr) {
    error[CCDBENCH_MESSAGE_SIZE - 1] = '\0';
    throw std::invalid_argument(
        "plugin " + library_->description().table.name + ": " +
        (fault.empty() ? "its configuration was refused: " + std::string(error[0] ? error : "no reason given") : "its create call failed: " + fault));
  }
}

Context::~Context() {
  if (handle_ == nullptr) return;
  // Nothing is answered any more: what destroy does beside its job can only be said.
  const std::string fault = guarded_call(site_, "destroy", [&] { library_->table().destroy(handle_); });
  if (!fault.empty()) std::fprintf(stderr, "ccdbench: warning: %s: destroy: %s\n", site_.plugin.c_str(), fault.c_str());
}

}  // namespace ccd::plugin
