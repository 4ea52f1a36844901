// tools/kernels_by_compiler.sh: each generated kernel of one model as GCC and as clang compiled it
// (kernels.cpp, twice), interleaved in one process: medians of 15 alternating batches and their
// ratio, clang's time over GCC's.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

namespace by_gcc {
double run_kernel(int which, int n);
}
namespace by_clang {
double run_kernel(int which, int n);
}

int main() {
  const char* const names[] = {"kinematics", "kinematic_update", "bodies", "dynamics_update", "convective", "reduced_dynamics",
                               "generalized_forces"};
  constexpr int kBatch = 2000, kRepetitions = 15;
  std::printf("%-20s %10s %10s %10s\n", "kernel", "GCC ns", "clang ns", "clang/GCC");
  double sink = 0;
  for (int which = 0; which < 7; ++which) {
    std::vector<double> gcc, clang;
    for (int r = 0; r < kRepetitions; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      sink += by_gcc::run_kernel(which, kBatch);
      const auto t1 = std::chrono::steady_clock::now();
      sink += by_clang::run_kernel(which, kBatch);
      const auto t2 = std::chrono::steady_clock::now();
      gcc.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() / kBatch);
      clang.push_back(std::chrono::duration<double, std::nano>(t2 - t1).count() / kBatch);
    }
    std::sort(gcc.begin(), gcc.end());
    std::sort(clang.begin(), clang.end());
    const double g = gcc[kRepetitions / 2], c = clang[kRepetitions / 2];
    std::printf("%-20s %10.1f %10.1f %10.2f\n", names[which], g, c, c / g);
  }
  return sink == 12345.678 ? 1 : 0;  // uses the results
}
