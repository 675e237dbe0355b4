// Query methods: `answers:FILE[:method=NAME]`, answers read from a file (answer_files.hpp) for code that cannot be
// loaded.

#include "ccd/config.hpp"
#include "harness/queries/answer_files.hpp"
#include "harness/queries/methods.hpp"
#include "strategies/narrowphase/spec.hpp"
#include "strategies/plugin/library.hpp"

#include <cstring>
#include <filesystem>
#include <map>
#include <stdexcept>

namespace ccd::harness {
namespace {

/// The answer files named by `answers:FILE[:method=NAME]` specs, read once per process (every rank reads its own).
std::map<std::string, AnswerTable>& answer_tables() {
  static std::map<std::string, AnswerTable> tables;
  return tables;
}

AnswerTable& answer_table(const std::string& spec) {
  auto it = answer_tables().find(spec);
  if (it != answer_tables().end()) return it->second;
  const auto [head, parameters] = narrowphase::split_spec(spec);
  const std::vector<narrowphase::KeySpec> keys{
      narrowphase::KeySpec::text("method", "which method's answers, when the file holds several (its name, or its name's head)"),
      narrowphase::KeySpec::text("digest", "the file's digest (filled in; checked when given)")};
  const narrowphase::SpecReader reader(head, keys, parameters);
  const std::filesystem::path path = head.substr(std::strlen(narrowphase::kAnswersHead) + 1);
  AnswerTable table = read_answer_table(path, reader.text("method"));
#if !CCDBENCH_GUARD_READ_ONCE
  table.digest = plugin::content_digest(path);  // without the guard: a second read, apart from the one scored
#endif
  if (reader.given("digest") && reader.text("digest") != table.digest) {
    throw std::invalid_argument(spec + ": the file changed (digest " + table.digest + ")");
  }
  return answer_tables().emplace(spec, std::move(table)).first->second;
}

/// Answers read from a file (answer_files.hpp): a method whose code ran elsewhere, judged like the others.
class AnswerFileMethod final : public QueryMethod {
 public:
  explicit AnswerFileMethod(const AnswerTable& table) : table_(table) {}
  std::string name() const override {
    // method= last: it takes the rest of a spec, ':' included (split_spec), so the name reads back as itself.
    std::string name = std::string(narrowphase::kAnswersHead) + ":" + std::filesystem::absolute(table_.path).lexically_normal().string() +
                       ":digest=" + table_.digest;
    if (!table_.method.empty()) name += ":method=" + table_.method;
    return name;
  }
  QueryAnswer answer(const datasets::QueryFile& file, std::size_t index, double) const override {
    const auto it = table_.by_file.find(file.path.string());
    if (it == table_.by_file.end() || index >= it->second.size() || it->second[index] == nullptr) {
      throw std::logic_error("answers " + table_.path.string() + " were not matched to " + file.path.string() + " (bind_answer_files)");
    }
    const AnswerLine& line = *it->second[index];
    if (line.hit < 0)
      return {false, std::numeric_limits<double>::quiet_NaN(), "error (" + table_.path.string() + " line " + std::to_string(line.line) + ")"};
    return {line.hit == 1, line.hit == 1 ? line.toi : std::numeric_limits<double>::quiet_NaN(), {}};
  }

 private:
  const AnswerTable& table_;
};

}  // namespace

std::vector<QueryMethodEntry> answer_file_entries() {
  return {{names_answers,
           [](const std::string& spec) -> std::unique_ptr<QueryMethod> { return std::make_unique<AnswerFileMethod>(answer_table(spec)); },
           [] { return std::vector<std::string>{}; },
           [](const std::vector<std::string>& methods, const std::vector<datasets::QueryFile>& files) {
             for (const std::string& spec : methods) {
               if (names_answers(spec)) bind_answers(answer_table(spec), files);
             }
           }}};
}

}  // namespace ccd::harness
