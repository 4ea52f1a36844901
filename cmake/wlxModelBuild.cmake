# What a model's code is, and how it is compiled: the one definition that every builder of a
# model's code reads.
#   - the build tree, for the built-in models (CMakeLists.txt);
#   - wlx_generate(), for a model in a project of one's own (cmake/wlxGenerate.cmake; installed
#     beside it and included by the package's wlxConfig.cmake);
#   - a model file's plugin (cli/shell/model_plugin.cpp), which is given these as definitions;
#   - the viewer's WebAssembly module (viewer/CMakeLists.txt, and the plugin's module of a model file).
# Nothing else restates a list or a flag of these: change them here.

# The generic runtime's sources (relative to runtime/wlx/), compiled once per model as one
# translation unit: they share their fixed-size Eigen templates, which one unit compiles once.
set(WLX_RUNTIME_FILES
  model.cpp
  settings.cpp
  kinematics.cpp
  ik.cpp
  model_code.cpp
  ik_verification.cpp
  nonholonomic.cpp
  simulation.cpp
  dynamics.cpp
  torque_distribution.cpp
  forward_dynamics.cpp
  contacts.cpp
  stability.cpp
  contact_distribution.cpp)
# Of those, the ones a plugin compiles as units of their own, beside the rest, so that two cores
# share the runtime instead of one waiting for it: its longest compiles (the integrators'
# instantiations, the QRs on J_beta's structure, the rolling rows' factorizations). With
# the precompiled headers (cli/shell/plugin_prelude.hpp) a unit of its own costs little more than
# its share of one unit; an excavator-sized runtime: the rest 6.8 s, these 4.0, 3.8 and 2.7 s
# (clang 14, -O3), against 12.6 s as one unit. (The build tree's unity build splits the runtime
# by CMake's batches.)
set(WLX_RUNTIME_APART_FILES simulation.cpp torque_distribution.cpp nonholonomic.cpp)
# The generated functions' double versions (relative to runtime/wlx/), compiled once per model;
# each defines WLX_GEN_DEFINE_DOUBLE, so none joins the runtime's unit.
set(WLX_GENERATED_FUNCTION_FILES
  generated_kinematics.cpp
  generated_rates.cpp
  generated_bodies.cpp
  generated_reduced_dynamics.cpp)
# The per-model commands (cli/commands/per_model.hpp; relative to cli/).
set(WLX_COMMAND_SOURCES
  commands/input.cpp commands/description.cpp commands/limits.cpp commands/scenario_io.cpp commands/ik_commands.cpp
  commands/simulate_commands.cpp commands/simulate_stream.cpp commands/fk_command.cpp commands/report_command.cpp
  report/runner.cpp commands/viewer_command.cpp commands/model_api.cpp)
# A model compiled from a user's file (a plugin, wlx_generate(PYTHON)) embeds no runs: the same
# commands and the empty definitions of what a built-in model embeds.
set(WLX_MODEL_FILE_COMMAND_SOURCES ${WLX_COMMAND_SOURCES} commands/no_embedded_runs.cpp)
# The viewer's module: the runtime's sources it calls (relative to runtime/wlx/), the command
# line's input bounds (relative to cli/), and the functions its page calls.
set(WLX_VIEWER_RUNTIME_FILES model.cpp parameter_checks.cpp settings.cpp kinematics.cpp ik.cpp)
set(WLX_VIEWER_CLI_FILES commands/limits.cpp)
set(WLX_VIEWER_EXPORTED_FUNCTIONS
    _malloc,_free,_wlx_model_info_json,_wlx_last_error,_wlx_solve_ik,_wlx_forward_kinematics,_wlx_closure_residual,_wlx_body_centres)

# Optimization, per part. The runtime and the generated functions run in users' loops: -O3 (at -O2
# clang 14 made the closed-form IK 19% slower in wlx_bench, the other rows within 3%; the runtime's
# unity compiles as fast at -O3 as at -O2, 9.8 s against 10.2 s). The commands parse, check and write around those calls: -O0 (the excavator's commands alone on
# a core: 27 s at -O2, 19 s at -O1, 10 s at -O0; a report of its runs 28 s against 26.5 s with
# them at -O1). The build tree applies these to its optimized configurations (not Debug, not the
# sanitized tree, whose -O1 is its own); wlx_generate() applies the commands' to a Python
# package's commands and leaves the runtime a controller embeds to that project's own flags; a
# plugin uses both unless WLX_PLUGIN_CXXFLAGS replaces them.
set(WLX_RUNTIME_OPTIMIZATION -O3)
set(WLX_COMMANDS_OPTIMIZATION -O0)
set(WLX_VIEWER_OPTIMIZATION -O2)

# wlx_optimize(TARGET FLAG...): a part's optimization above, after the configuration's own flags (so
# that it wins over Release's -O3), in the optimized configurations only: Debug keeps -O0, and the
# sanitized tree (WLX_SANITIZE, WLX_FUZZ) its -O1, the flags its reports and run times were tuned for.
function(wlx_optimize target)
  if(WLX_SANITIZE OR WLX_FUZZ)
    return()
  endif()
  foreach(flag IN LISTS ARGN)  # one generator expression per flag: a list would split it
    target_compile_options(${target} PRIVATE $<$<NOT:$<CONFIG:Debug>>:${flag}>)
  endforeach()
endfunction()
