// Generation speed (Google Benchmark): building the model, each derivation group, the CSE pass
// alone, and the whole emission as wlx-gen runs it.
#include "../generator/derivations.hpp"
#include "../generator/emit.hpp"
#include "../generator/expr_graph.hpp"
#include "../generator/model_file.hpp"

#include <benchmark/benchmark.h>

namespace {

using namespace wlx::codegen;

const Model& model() {
  static const Model m = load_model_file(WLX_MODEL_FILE);
  return m;
}

// Reading and checking the model file, building the frames' symbolic kinematics.
void BM_build_model(benchmark::State& st) {
  for (auto _ : st) benchmark::DoNotOptimize(load_model_file(WLX_MODEL_FILE));
}

template <FunctionSpec (*Derive)(const Model&)>
void BM_derive(benchmark::State& st) {
  for (auto _ : st) benchmark::DoNotOptimize(Derive(model()));
}

// Conversion to the deterministic DAG and CSE only, for one group.
template <FunctionSpec (*Derive)(const Model&)>
void BM_cse(benchmark::State& st) {
  const FunctionSpec fn = Derive(model());
  for (auto _ : st) {
    ExprGraph g;
    std::vector<int> roots;
    for (const auto& o : fn.outputs)
      for (const auto& [lv, e] : o.elements) roots.push_back(g.add(e));
    benchmark::DoNotOptimize(eliminate_common_subexpressions(g, roots));
  }
}

// What wlx-gen does, without writing files.
void BM_generate_everything(benchmark::State& st) {
  EmitOptions opt;
  opt.generator_version = "bench";
  for (auto _ : st) {
    const Model m = load_model_file(WLX_MODEL_FILE);
    auto files = emit_model_headers(m, opt);
    std::vector<FunctionStats> stats;
    const auto fns = derive_all(m);
    for (const auto& fn : fns) {
      FunctionStats s;
      files.push_back(emit_function(m, fn, opt, s));
      stats.push_back(s);
    }
    files.push_back(emit_umbrella(m, fns, stats, opt));
    benchmark::DoNotOptimize(files.data());
  }
}

}  // namespace

BENCHMARK(BM_build_model)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_derive<derive_kinematics>)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_derive<derive_closure>)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_derive<derive_nonholonomic>)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_derive<derive_convective>)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_derive<derive_bodies>)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_cse<derive_kinematics>)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_cse<derive_closure>)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_cse<derive_nonholonomic>)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_cse<derive_convective>)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_cse<derive_bodies>)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_generate_everything)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
