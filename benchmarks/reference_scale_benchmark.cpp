// The exact reference's cost at every scale (issue 60): time per query and the share the certified filter decides,
// on the public query files and on the extremes suite, each multiplied exactly by 2^0, 2^±500 and 2^±1000, with and
// without the earliest contact time. The same questions at every scale, so the same answers: only the cost may
// differ, and should not.
//
// Two entries of the reference, as its callers use them:
//   rationals  decide(ExactPair, mpq δ), as query files, query scoring and ccdbench.oracle_file ask: every query,
//              scaled as a rational (always exact, also past the double range);
//   doubles    decide(kind, rows, double δ), as whole-step truth and ccdbench.oracle on arrays ask: the queries that
//              are doubles and stay normal (or zero) doubles at every one of the scales, the same ones at each.
// One iteration decides its whole set once, on one thread, at δ = 0 (the public files' truth is at δ = 0).
// Counters: per_query (seconds a query), filter_share (decided by the certified filter), queries.
//
// Run: build/release/benchmarks/reference_scale_benchmark (CCDBENCH_DATA_DIR names the public data; without it
// the public rows are skipped, saying so).

#include "datasets/data_dir.hpp"
#include "datasets/extremes_suite.hpp"
#include "datasets/query_file.hpp"
#include "reference/elementary_pair.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <string>
#include <vector>

namespace ccd::reference {
namespace {

struct Query {
  PairKind kind;
  ExactPair exact;
  /// Whether every coordinate is a double that stays a normal (or zero) double at every scale: the doubles entry's set.
  bool scales_as_doubles;
  std::array<Vec3, 8> rows;
};

const std::vector<int> kExponents = {0, -500, 500, -1000, 1000};

PairKind kind_of(datasets::QueryKind kind) { return kind == datasets::QueryKind::vertex_face ? PairKind::vertex_face : PairKind::edge_edge; }

bool scales_as_doubles(const std::array<Vec3, 8>& rows) {
  for (int exponent : kExponents) {
    if (!datasets::scaled_exactly(rows, exponent)) return false;
  }
  return true;
}

Query query_of_doubles(PairKind kind, const std::array<Vec3, 8>& rows) {
  return {kind, exact_pair_from_doubles(kind, rows), scales_as_doubles(rows), rows};
}

std::vector<Query> public_queries() {
  std::vector<Query> queries;
  const auto data = datasets::external_data_dir();
  if (!data) return queries;
  for (const auto& path : datasets::discover_query_files({*data / "sample-queries", *data / "scalable-ccd-sample"})) {
    const datasets::QueryFile file = datasets::read_query_file(path);
    for (const datasets::Query& query : file.queries) {
      Query q{kind_of(file.kind), ExactPair{kind_of(file.kind), {}}, query.exactly_double && scales_as_doubles(query.rounded), query.rounded};
      for (int r = 0; r < 8; ++r) q.exact.rows[r] = query.exact[r];
      queries.push_back(std::move(q));
    }
  }
  return queries;
}

std::vector<Query> extremes_queries() {
  std::vector<Query> queries;
  for (const datasets::ExtremeQuery& query : datasets::extremes_suite(1)) queries.push_back(query_of_doubles(kind_of(query.kind), query.rows));
  return queries;
}

mpq_class times_power_of_two(const mpq_class& q, int exponent) {
  mpq_class scaled;
  if (exponent >= 0) {
    mpq_mul_2exp(scaled.get_mpq_t(), q.get_mpq_t(), static_cast<mp_bitcnt_t>(exponent));
  } else {
    mpq_div_2exp(scaled.get_mpq_t(), q.get_mpq_t(), static_cast<mp_bitcnt_t>(-exponent));
  }
  return scaled;
}

enum class Entry { rationals, doubles };

void BM_Oracle(benchmark::State& state, const std::vector<Query>& set, Entry entry, int exponent, bool toi) {
  std::vector<ExactPair> pairs;
  std::vector<std::pair<PairKind, std::array<Vec3, 8>>> rows;
  for (const Query& query : set) {
    if (entry == Entry::rationals) {
      ExactPair scaled{query.kind, {}};
      for (int r = 0; r < 8; ++r) {
        for (int k = 0; k < 3; ++k) scaled.rows[r][k] = times_power_of_two(query.exact.rows[r][k], exponent);
      }
      pairs.push_back(std::move(scaled));
    } else if (query.scales_as_doubles) {
      rows.emplace_back(query.kind, *datasets::scaled_exactly(query.rows, exponent));
    }
  }
  const std::size_t count = entry == Entry::rationals ? pairs.size() : rows.size();
  if (count == 0) return state.SkipWithError("no queries (the public data: CCDBENCH_DATA_DIR)");
  const mpq_class zero = 0;
  const DecisionRequest request{true, toi, 64};
  std::size_t by_filter = 0;
  for (auto _ : state) {
    by_filter = 0;
    for (std::size_t i = 0; i < count; ++i) {
      const Decision decision = entry == Entry::rationals ? decide(pairs[i], zero, request) : decide(rows[i].first, rows[i].second, 0.0, request);
      by_filter += decision.decided_by == DecidedBy::filter ? 1 : 0;
      benchmark::DoNotOptimize(decision);
    }
  }
  state.counters["per_query"] =
      benchmark::Counter(static_cast<double>(count), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["filter_share"] = static_cast<double>(by_filter) / static_cast<double>(count);
  state.counters["queries"] = static_cast<double>(count);
}

}  // namespace
}  // namespace ccd::reference

int main(int argc, char** argv) {
  using namespace ccd::reference;
  benchmark::Initialize(&argc, argv);
  static const std::vector<Query> public_set = public_queries();
  static const std::vector<Query> extremes_set = extremes_queries();
  for (const auto& [set_name, set] : {std::pair<const char*, const std::vector<Query>*>{"public", &public_set}, {"extremes", &extremes_set}}) {
    for (Entry entry : {Entry::rationals, Entry::doubles}) {
      for (bool toi : {false, true}) {
        for (int exponent : kExponents) {
          const std::string name = std::string("Oracle/") + set_name + (entry == Entry::rationals ? "/rationals" : "/doubles") +
                                   (toi ? "/toi" : "/no_toi") + "/2^" + std::to_string(exponent);
          benchmark::RegisterBenchmark(name.c_str(), BM_Oracle, *set, entry, exponent, toi)->Unit(benchmark::kMillisecond);
        }
      }
    }
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
