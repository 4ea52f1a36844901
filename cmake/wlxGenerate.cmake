# wlx_generate(TARGET <name> MODEL <file> [NAMESPACE <ns>] [BAKE <name=value>...])
#
# Runs wlx-gen on a model file at build time (again only when the file or wlx-gen changes) into
# <build>/wlx_generated/<name>/wlx/gen/ and defines the target <name> to link:
#   - without NAMESPACE: a static library, the wlx runtime compiled for this model (Model, Data,
#     IK, dependent rates, inverse dynamics, simulation in namespace wlx::<model>, where <model> is
#     the file's `model:` name), with the generated headers on its include path;
#   - with NAMESPACE: the generated headers alone (INTERFACE), in that namespace (the runtime needs
#     the default one).
# BAKE name=value bakes parameters in as constants (wlx-gen --bake).
# Used by the installed package (lib/cmake/wlx) and, the same way, inside the source tree.
function(wlx_generate)
  cmake_parse_arguments(PARSE_ARGV 0 arg "" "TARGET;MODEL;NAMESPACE" "BAKE")
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
  # The runtime's namespace is the model's name: read it from the file (wlx-gen checks the rest).
  file(STRINGS "${model_file}" name_line REGEX "^model:[ \t]*[A-Za-z_][A-Za-z0-9_]*[ \t]*(#.*)?$" LIMIT_COUNT 1)
  if(NOT name_line)
    message(FATAL_ERROR "wlx_generate: ${model_file}: no line 'model: <name>' (a C++ identifier) found")
  endif()
  string(REGEX REPLACE "^model:[ \t]*([A-Za-z_][A-Za-z0-9_]*).*$" "\\1" model_name "${name_line}")

  # A model file that reads a URDF (`urdf: robot.urdf`, relative to the file): generated again
  # when the URDF changes too.
  set(model_inputs "${model_file}")
  file(STRINGS "${model_file}" urdf_line REGEX "^urdf:[ \t]*[^ \t#]+" LIMIT_COUNT 1)
  if(urdf_line)
    string(REGEX REPLACE "^urdf:[ \t]*([^ \t#]+).*$" "\\1" urdf_file "${urdf_line}")
    get_filename_component(model_dir "${model_file}" DIRECTORY)
    get_filename_component(urdf_file "${urdf_file}" ABSOLUTE BASE_DIR "${model_dir}")
    list(APPEND model_inputs "${urdf_file}")
  endif()

  set(out "${CMAKE_CURRENT_BINARY_DIR}/wlx_generated/${arg_TARGET}")
  set(stamp "${CMAKE_CURRENT_BINARY_DIR}/wlx_generated/${arg_TARGET}.stamp")
  set(options --quiet)
  foreach(b IN LISTS arg_BAKE)
    list(APPEND options --bake "${b}")
  endforeach()
  if(arg_NAMESPACE)
    list(APPEND options --namespace "${arg_NAMESPACE}")
  endif()
  add_custom_command(
    OUTPUT "${stamp}"
    COMMAND wlx::wlx-gen "${model_file}" --out "${out}" ${options}
    COMMAND "${CMAKE_COMMAND}" -E touch "${stamp}"
    DEPENDS ${model_inputs} "$<TARGET_FILE:wlx::wlx-gen>"
    COMMENT "wlx-gen: ${arg_MODEL} -> ${out}/wlx/gen/"
    VERBATIM)
  add_custom_target(${arg_TARGET}_wlx_gen DEPENDS "${stamp}")

  if(arg_NAMESPACE)
    add_library(${arg_TARGET} INTERFACE)
    target_include_directories(${arg_TARGET} INTERFACE "${out}")
    target_link_libraries(${arg_TARGET} INTERFACE Eigen3::Eigen)
  else()
    file(GLOB runtime_sources "${WLX_RUNTIME_SOURCE_DIR}/*.cpp")
    add_library(${arg_TARGET} STATIC ${runtime_sources})
    # The runtime's sources in one translation unit (they share their Eigen templates: half the
    # compile time); the generated functions' files apart, each defines WLX_GEN_DEFINE_DOUBLE.
    set_target_properties(${arg_TARGET} PROPERTIES UNITY_BUILD ON)
    set(generated_function_sources "${runtime_sources}")
    list(FILTER generated_function_sources INCLUDE REGEX "/generated_[a-z_]*\\.cpp$")
    set_source_files_properties(${generated_function_sources} PROPERTIES SKIP_UNITY_BUILD_INCLUSION ON)
    target_include_directories(${arg_TARGET} PUBLIC "${out}")
    # The generated functions' double versions are compiled once, here (generated_*.cpp).
    target_compile_definitions(${arg_TARGET} PUBLIC WLX_MODEL=${model_name} WLX_GEN_COMPILED_${model_name})
    target_compile_features(${arg_TARGET} PUBLIC cxx_std_20)
    target_link_libraries(${arg_TARGET} PUBLIC wlx::runtime)
  endif()
  add_dependencies(${arg_TARGET} ${arg_TARGET}_wlx_gen)
endfunction()
