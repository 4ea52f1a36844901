// The headers every translation unit of a model file's plugin includes and no model changes: the
// standard library's, Eigen's, fmt's and nlohmann-json's (the commands' units load them through
// plugin_prelude_commands.hpp, which adds the templates they instantiate). wlx's build compiles them once into a
// precompiled header per optimization level (CMakeLists.txt, when the compiler is Clang), which
// the plugin's compiles load instead of parsing these again (cli/shell/model_plugin.cpp): about
// 1.2 s of each unit's front end, 3.4 s of CPU over an excavator-sized plugin's units. Nothing
// here may depend on a model or on a macro a source defines before its includes (no source of the
// plugin configures Eigen, fmt or nlohmann-json by macro).
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <set>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/QR>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>
