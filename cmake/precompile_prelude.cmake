# A model file's plugins' precompiled header and, for the commands' one, the archive of its code:
# the one recipe of both, run by the build (`cmake -P`, CMakeLists.txt's custom command, from the
# source tree's header) and at install time (install(CODE), from the installed cli/shell/ header:
# Clang records the header a precompiled header was made from and refuses it once that file is
# gone, so the build tree's copy would stop working when the checkout is removed).
# In: WLX_PRELUDE_COMPILER; WLX_PRELUDE_FLAGS (a list, its items joined by '|' or ';');
# WLX_PRELUDE_HEADER (the header's absolute path: it is recorded as given, and a relative one would
# be looked up from wherever a plugin is built); WLX_PRELUDE_OUTPUT (the .pch to write);
# WLX_PRELUDE_WITH_CODE: the flags hold -fpch-codegen, and the header's code is compiled with
# WLX_PRELUDE_CODE_FLAGS (a list, as above) into <output without .pch>.a by WLX_PRELUDE_AR (without
# it a plugin that loaded the header would link but not load, so where it fails the header is
# removed too; model_plugin.cpp uses no such header without its archive); WLX_PRELUDE_REQUIRED: a
# failure is an error (the build's), else a warning (an installed wlx's plugins then compile
# without it, only slower).
string(REPLACE "|" ";" flags "${WLX_PRELUDE_FLAGS}")
string(REPLACE "|" ";" code_flags "${WLX_PRELUDE_CODE_FLAGS}")
set(pch "${WLX_PRELUDE_OUTPUT}")
string(REGEX REPLACE "\\.pch$" "" stem "${pch}")
set(object "${stem}.o")
set(archive "${stem}.a")
get_filename_component(dir "${pch}" DIRECTORY)
file(MAKE_DIRECTORY "${dir}")
execute_process(COMMAND "${WLX_PRELUDE_COMPILER}" ${flags} -x c++-header "${WLX_PRELUDE_HEADER}" -o "${pch}"
                RESULT_VARIABLE result ERROR_VARIABLE errors)
if(result EQUAL 0 AND WLX_PRELUDE_WITH_CODE)
  file(REMOVE "${archive}")
  execute_process(COMMAND "${WLX_PRELUDE_COMPILER}" ${code_flags} -c "${pch}" -o "${object}" RESULT_VARIABLE result ERROR_VARIABLE errors)
  if(result EQUAL 0)
    execute_process(COMMAND "${WLX_PRELUDE_AR}" qc "${archive}" "${object}" RESULT_VARIABLE result ERROR_VARIABLE errors)
  endif()
  file(REMOVE "${object}")
endif()
if(NOT result EQUAL 0)
  file(REMOVE "${pch}" "${archive}")
  if(WLX_PRELUDE_REQUIRED)
    message(FATAL_ERROR "precompiling ${WLX_PRELUDE_HEADER} into ${pch} failed: ${errors}")
  endif()
  message(WARNING "${pch} not precompiled (${errors}): model files' plugins compile without it")
else()
  message(STATUS "Precompiled: ${pch}")
endif()
