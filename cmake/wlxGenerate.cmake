# wlx_generate(TARGET <name> MODEL <file> [NAME <model>] [NAMESPACE <ns>] [BAKE <name=value>...] [PYTHON])
#
# Runs wlx-gen on a model file at build time (again only when the file, the URDF it names or
# wlx-gen changes) into
# <build>/wlx_generated/<name>/wlx/gen/ and defines the target <name> to link:
#   - without NAMESPACE: a static library, the wlx runtime compiled for this model (Model, Data,
#     IK, dependent rates, inverse dynamics, simulation in namespace wlx::<model>, where <model> is
#     NAME, else the file's name without .yaml; wlx-gen checks that the file's `model:` is that
#     name), with the generated headers on its include path;
#   - with NAMESPACE: the generated headers alone (INTERFACE), in that namespace (the runtime needs
#     the default one).
# BAKE name=value bakes parameters in as constants (wlx-gen --bake).
# PYTHON (not with NAMESPACE) also builds the Python package wlx for this model: the target
# <name>_python, the module in <build>/wlx_python/<name>/wlx/ (PYTHONPATH=<build>/wlx_python/<name>,
# then `import wlx; wlx.model("<model>")`: the same API as the installed package's models, with
# this one built in). Needs pybind11 and Python's headers.
# Used by the installed package (lib/cmake/wlx) and, the same way, inside the source tree.
# The model's name (the runtime's namespace wlx::<model>, the Python module's wlx.model("<model>")),
# which CMake needs before wlx-gen runs: NAME if given, else the file's name without its extension.
# CMake never reads the model file (only wlx-gen does: a second reader could read it otherwise);
# wlx-gen checks that the file's `model:` is this name (--expect-model) and lists the files the
# model was read from (the URDF it names) in a depfile, so that editing any of them regenerates.
# WHO names the caller in errors.
function(wlx_model_name file given name_var who)
  if(given)
    set(name "${given}")
  else()
    get_filename_component(name "${file}" NAME_WLE)
  endif()
  if(NOT name MATCHES "^[A-Za-z_][A-Za-z0-9_]*$")
    message(FATAL_ERROR "${who}: ${file}: the model's name '${name}' (NAME, else the file's name) is not a C++ identifier: "
                        "rename the file or give NAME (the file's `model:`)")
  endif()
  set(${name_var} ${name} PARENT_SCOPE)
endfunction()

# The command that runs wlx-gen on FILE into OUT, touching STAMP, again whenever wlx-gen, FILE or a
# file it read (the URDF) changes. ARGN: further options of wlx-gen.
function(wlx_add_generation stamp file out expected_model comment)
  # CMP0116 NEW (whatever the caller's policies): Ninja is given the depfile's paths relative to the
  # build folder, as it names the stamp; else it would see another target and regenerate every build.
  cmake_policy(PUSH)
  cmake_policy(SET CMP0116 NEW)
  add_custom_command(
    OUTPUT "${stamp}"
    # wlx-gen rewrites all.hpp whenever any header changes: named here, Ninja recompiles what
    # includes it after an edit of the model file (else objects built from the old headers stay).
    BYPRODUCTS "${out}/wlx/gen/all.hpp" "${out}/wlx/gen/model.json"
    COMMAND wlx::wlx-gen "${file}" --out "${out}" --expect-model "${expected_model}" --depfile "${stamp}.d"
            --depfile-target "${stamp}" ${ARGN}
    COMMAND "${CMAKE_COMMAND}" -E touch "${stamp}"
    DEPENDS "${file}" "$<TARGET_FILE:wlx::wlx-gen>"
    DEPFILE "${stamp}.d"
    COMMENT "${comment}"
    VERBATIM)
  cmake_policy(POP)
endfunction()

# wlx_generated_function_units(OUT_VAR NAME GENERATED_DIR): the generated functions' units of one
# model (WLX_GENERATED_FUNCTION_FILES), each a one-line file in this build folder that includes the
# runtime's generated_*.cpp, and that depends on GENERATED_DIR's all.hpp. wlx-gen rewrites all.hpp
# whenever any header changes and its command names it (wlx_add_generation), so Ninja recompiles
# these units in the same build; a unit that includes kinematics.hpp alone, which no rule names,
# would otherwise be compiled from the old header until the next build (and linked against the
# new ones: an arm given a fourth joint failed to link once, then built). One file per model: a
# source file's properties are its folder's, shared by every model built there.
function(wlx_generated_function_units out_var name generated_dir)
  set(units)
  foreach(file IN LISTS WLX_GENERATED_FUNCTION_FILES)
    set(unit "${CMAKE_CURRENT_BINARY_DIR}/wlx-generated-units/${name}/${file}")
    # The path as a C++ string literal: a backslash, quote or line break in it is escaped.
    set(path "${WLX_RUNTIME_SOURCE_DIR}/${file}")
    string(REPLACE "\\" "\\\\" path "${path}")
    string(REPLACE "\"" "\\\"" path "${path}")
    string(REPLACE "\n" "\\n" path "${path}")
    file(CONFIGURE OUTPUT "${unit}" CONTENT "// ${file} for the model ${name} (cmake/wlxGenerate.cmake).\n#include \"${path}\"\n" @ONLY)
    list(APPEND units "${unit}")
  endforeach()
  set_source_files_properties(${units} PROPERTIES SKIP_UNITY_BUILD_INCLUSION ON OBJECT_DEPENDS "${generated_dir}/wlx/gen/all.hpp")
  set(${out_var} ${units} PARENT_SCOPE)
endfunction()

function(wlx_generate)
  cmake_parse_arguments(PARSE_ARGV 0 arg "PYTHON" "TARGET;MODEL;NAMESPACE;NAME" "BAKE")
  if(arg_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "wlx_generate: unknown arguments: ${arg_UNPARSED_ARGUMENTS}")
  endif()
  if(NOT arg_TARGET OR NOT arg_MODEL)
    message(FATAL_ERROR "wlx_generate: TARGET and MODEL are required: wlx_generate(TARGET name MODEL file.yaml)")
  endif()
  if(NOT TARGET wlx::wlx-gen)
    message(FATAL_ERROR "wlx_generate: this wlx was built without its generator (WLX_BUILD_GENERATOR=OFF)")
  endif()
  get_filename_component(model_file "${arg_MODEL}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
  if(NOT EXISTS "${model_file}")
    message(FATAL_ERROR "wlx_generate: MODEL ${model_file}: no such file")
  endif()
  wlx_model_name("${model_file}" "${arg_NAME}" model_name "wlx_generate")

  set(out "${CMAKE_CURRENT_BINARY_DIR}/wlx_generated/${arg_TARGET}")
  set(stamp "${CMAKE_CURRENT_BINARY_DIR}/wlx_generated/${arg_TARGET}.stamp")
  set(options --quiet)
  foreach(b IN LISTS arg_BAKE)
    list(APPEND options --bake "${b}")
  endforeach()
  if(arg_NAMESPACE)
    list(APPEND options --namespace "${arg_NAMESPACE}")
  endif()
  wlx_add_generation("${stamp}" "${model_file}" "${out}" ${model_name} "wlx-gen: ${arg_MODEL} -> ${out}/wlx/gen/" ${options})
  add_custom_target(${arg_TARGET}_wlx_gen DEPENDS "${stamp}")

  if(arg_NAMESPACE)
    add_library(${arg_TARGET} INTERFACE)
    target_include_directories(${arg_TARGET} INTERFACE "${out}")
    target_link_libraries(${arg_TARGET} INTERFACE Eigen3::Eigen)
  else()
    set(runtime_sources ${WLX_RUNTIME_FILES})
    list(TRANSFORM runtime_sources PREPEND "${WLX_RUNTIME_SOURCE_DIR}/")
    wlx_generated_function_units(generated_function_sources ${arg_TARGET} "${out}")
    add_library(${arg_TARGET} STATIC ${runtime_sources} ${generated_function_sources})
    # The runtime's sources in one translation unit (they share their Eigen templates: half the
    # compile time); the generated functions' files apart, each defines WLX_GEN_DEFINE_DOUBLE.
    set_target_properties(${arg_TARGET} PROPERTIES UNITY_BUILD ON)
    target_include_directories(${arg_TARGET} PUBLIC "${out}")
    # The generated functions' double versions are compiled once, here (generated_*.cpp).
    target_compile_definitions(${arg_TARGET} PUBLIC WLX_MODEL=${model_name} WLX_GEN_COMPILED_${model_name})
    target_compile_features(${arg_TARGET} PUBLIC cxx_std_20)
    target_link_libraries(${arg_TARGET} PUBLIC wlx::runtime)
  endif()
  add_dependencies(${arg_TARGET} ${arg_TARGET}_wlx_gen)
  if(arg_PYTHON)
    if(arg_NAMESPACE)
      message(FATAL_ERROR "wlx_generate: PYTHON needs the runtime, which NAMESPACE leaves out")
    endif()
    wlx_generate_python(${arg_TARGET} ${model_name})
  endif()
endfunction()

# Writes FILE, the Python package's _built_for.py: the interpreter its compiled module (_wlx) is
# built for, which python/wlx/__init__.py names when another interpreter imports the package and
# cannot load it (the python3 first on PATH may be another one, without this one's NumPy, or of
# another version). No file when CMake knows no interpreter (the package then says nothing more).
function(wlx_write_python_built_for file)
  set(python "${Python3_EXECUTABLE}")
  set(version "${Python3_VERSION_MAJOR}.${Python3_VERSION_MINOR}")
  if(NOT python AND PYTHON_EXECUTABLE)  # pybind11 found it the older way (FindPythonInterp)
    set(python "${PYTHON_EXECUTABLE}")
    set(version "${PYTHON_VERSION_MAJOR}.${PYTHON_VERSION_MINOR}")
  endif()
  if(NOT python)
    file(REMOVE "${file}")
    return()
  endif()
  # Python string literals: backslashes and quotes escaped.
  string(REPLACE "\\" "\\\\" python "${python}")
  string(REPLACE "\"" "\\\"" python "${python}")
  file(CONFIGURE OUTPUT "${file}" CONTENT [=[# Written by CMake: the interpreter wlx's compiled module (_wlx) was built for. Do not edit.
executable = "@python@"
version = "@version@"
]=] @ONLY)
endfunction()

# The Python package for one model: its commands (the command line's parsing and solving, which
# Python's API calls, cli/shell/model_api.hpp) compiled for it, and python/module.cpp with a
# registry that lists it, linked with the shell (wlx::cli_common).
function(wlx_generate_python target model_name)
  if(NOT TARGET wlx::cli_common OR NOT WLX_MODEL_FILE_COMMAND_SOURCES)
    message(FATAL_ERROR "wlx_generate: PYTHON: this wlx was built without its command line (WLX_BUILD_CLI=OFF)")
  endif()
  if(NOT COMMAND pybind11_add_module)
    find_package(Python3 COMPONENTS Interpreter Development.Module REQUIRED)
    find_package(pybind11 CONFIG REQUIRED)
  endif()
  set(dir "${CMAKE_CURRENT_BINARY_DIR}/wlx_python/${target}")
  # The registry of this one model (its commands embed no runs: commands/no_embedded_runs.cpp).
  file(CONFIGURE OUTPUT "${dir}/registry.cpp" CONTENT "// Written by wlx_generate(PYTHON). Do not edit.
#include \"commands.hpp\"
namespace wlx { inline namespace ${model_name} { namespace commands { const cli::ModelCommands& entry(); } } }
namespace wlx::cli {
const std::vector<ModelCommands>& models() {
  static const std::vector<ModelCommands> all{wlx::${model_name}::commands::entry()};
  return all;
}
}  // namespace wlx::cli
")
  set(sources ${WLX_MODEL_FILE_COMMAND_SOURCES})
  list(TRANSFORM sources PREPEND "${WLX_CLI_SOURCE_DIR}/")
  add_library(${target}_commands STATIC ${sources})
  set_target_properties(${target}_commands ${target} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  set_target_properties(${target}_commands PROPERTIES UNITY_BUILD ON)  # they share Eigen's templates
  # The commands' optimization (cmake/wlxModelBuild.cmake): they parse and write around the
  # runtime's calls, which keep this project's own flags.
  wlx_optimize(${target}_commands ${WLX_COMMANDS_OPTIMIZATION})
  target_include_directories(${target}_commands PUBLIC "${WLX_CLI_SOURCE_DIR}/commands")
  target_link_libraries(${target}_commands PUBLIC ${target} wlx::cli_common)
  pybind11_add_module(${target}_python MODULE NO_EXTRAS "${WLX_PYTHON_SOURCE_DIR}/module.cpp" "${dir}/registry.cpp")
  # Link only: the model's WLX_MODEL must not reach module.cpp, which names no model. The shell
  # whole: a model file's plugin (wlx.load) calls its functions from this module.
  target_link_libraries(${target}_python PRIVATE $<LINK_ONLY:${target}_commands> wlx::cli_common Eigen3::Eigen)
  target_link_options(${target}_python PRIVATE "LINKER:--whole-archive" "$<TARGET_FILE:wlx::cli_common>" "$<TARGET_FILE:wlx::numerics>"
                      "LINKER:--no-whole-archive")
  target_compile_features(${target}_python PRIVATE cxx_std_20)
  # wlx.load() runs wlx-gen: the package's own.
  target_compile_definitions(${target}_python PRIVATE WLX_VERSION="${wlx_VERSION}" WLX_BIN_FROM_PYTHON_MODULE="wlx-gen-is-not-here"
                                                     WLX_BUILD_BIN_DIR="$<TARGET_FILE_DIR:wlx::wlx-gen>")
  set_target_properties(${target}_python PROPERTIES OUTPUT_NAME _wlx LIBRARY_OUTPUT_DIRECTORY "${dir}/wlx")
  # The package's Python files (the sweep engine too): CMakeLists.txt's WLX_PYTHON_FILES.
  foreach(file __init__.py __main__.py _sweep.py _sweep_spec.py _sweep_metrics.py _sweep_store.py _sweep_cluster.py
               _sweep_plots.py _sweep_errors.py)
    configure_file("${WLX_PYTHON_SOURCE_DIR}/wlx/${file}" "${dir}/wlx/${file}" COPYONLY)
  endforeach()
  wlx_write_python_built_for("${dir}/wlx/_built_for.py")
endfunction()
