// The part of the command line that works with a model (parsing inputs for it, running its IK,
// simulations and report) is compiled once per model, like the runtime: into the namespace
// wlx::<model>::commands. The model-independent part (argument parsing, processes, output and
// input checks) lives in wlx::cli and is visible here too.
#pragma once

#include <wlx/model_namespace.hpp>

#define WLX_COMMANDS_BEGIN    \
  WLX_MODEL_NAMESPACE_BEGIN   \
  namespace commands {        \
  using namespace ::wlx::cli;
#define WLX_COMMANDS_END \
  }                      \
  WLX_MODEL_NAMESPACE_END

namespace wlx::cli {}
