// Generation speed (Google Benchmark), for every built-in model: building the model, each
// derivation group, the CSE pass alone, and the whole emission as wlx-gen runs it. Each benchmark
// is registered once per model, named NAME/<model> (BM_generate_everything/walker); the models
// are CMake's WLX_MODELS (bench_generator_models.hpp, written by CMakeLists.txt).
#include "../generator/derivations.hpp"
#include "../generator/emit.hpp"
#include "../generator/expr_graph.hpp"
#include "../generator/model_file.hpp"
#include "bench_generator_models.hpp"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <deque>
#include <exception>
#include <string>

namespace {

using namespace wlx::codegen;

// Reading and checking the model file, building the frames' symbolic kinematics.
void BM_build_model(benchmark::State& st, const std::string& file) {
  for (auto _ : st) benchmark::DoNotOptimize(load_model_file(file));
}

void BM_derive(benchmark::State& st, const Model* m, Derivation d) {
  for (auto _ : st) benchmark::DoNotOptimize(d.derive(*m));
}

// Conversion to the deterministic DAG and CSE only, for one group.
void BM_cse(benchmark::State& st, const Model* m, Derivation d) {
  const FunctionSpec fn = d.derive(*m);
  for (auto _ : st) {
    ExprGraph g;
    std::vector<int> roots;
    for (const auto& o : fn.outputs)
      for (const auto& [lv, e] : o.elements) roots.push_back(g.add(e));
    benchmark::DoNotOptimize(eliminate_common_subexpressions(g, roots));
  }
}

// What wlx-gen does, without writing files.
void BM_generate_everything(benchmark::State& st, const std::string& file) {
  EmitOptions opt;
  opt.generator_version = "bench";
  for (auto _ : st) {
    const Model m = load_model_file(file);
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

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  // A deque: the benchmarks keep pointers to the models, which must not move.
  std::deque<Model> models;
  for (const auto& [name, file] : wlx::bench::kModelFiles) {
    try {
      models.push_back(load_model_file(file));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "wlx_bench_generator: model %s (%s): %s\n", name, file, e.what());
      return 1;
    }
    const Model* m = &models.back();
    const std::string suffix = std::string("/") + name;
    const auto ms = [](benchmark::internal::Benchmark* b) { b->Unit(benchmark::kMillisecond); };
    ms(benchmark::RegisterBenchmark(("BM_build_model" + suffix).c_str(), BM_build_model, std::string(file)));
    // The groups wlx-gen derives for this model (clearance only when it has a clearance box).
    for (const Derivation& d : derivations(*m))
      ms(benchmark::RegisterBenchmark(("BM_derive/" + std::string(d.name) + suffix).c_str(), BM_derive, m, d));
    for (const Derivation& d : derivations(*m))
      ms(benchmark::RegisterBenchmark(("BM_cse/" + std::string(d.name) + suffix).c_str(), BM_cse, m, d));
    ms(benchmark::RegisterBenchmark(("BM_generate_everything" + suffix).c_str(), BM_generate_everything,
                                    std::string(file)));
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
