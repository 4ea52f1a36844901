# At install time (CMakeLists.txt's install(CODE)): a model file's plugins' precompiled header,
# compiled from the installed cli/shell/ header. Clang records the header a precompiled header was
# made from and refuses it once that file is gone, so the build tree's copy, made from the source
# tree's header, would stop working when the checkout is removed. A failure costs the installed
# wlx's plugins only their speed (model_plugin.cpp compiles without it): a warning.
# In: WLX_PRELUDE_COMPILER, WLX_PRELUDE_FLAGS (a list), WLX_PRELUDE_HEADER (in cli/shell/),
# WLX_PRELUDE_NAME (plugin_prelude-<name>.pch); WLX_PRELUDE_WITH_CODE: the header was precompiled
# with -fpch-codegen, and its code is compiled with WLX_PRELUDE_CODE_FLAGS into the archive
# plugin_prelude-<name>.a (WLX_PRELUDE_AR; without it, a plugin that loaded the header would link
# but not load, so where it fails the header is removed too, and model_plugin.cpp uses no such
# header without its archive).
# Absolute: the header's path is recorded as given, and a relative one (`cmake --install --prefix
# build/install`) would be looked up from wherever a plugin is built.
get_filename_component(share "$ENV{DESTDIR}${CMAKE_INSTALL_PREFIX}/${WLX_PRELUDE_DATADIR}/wlx" ABSOLUTE)
file(MAKE_DIRECTORY "${share}/precompiled")
set(pch "${share}/precompiled/plugin_prelude-${WLX_PRELUDE_NAME}.pch")
set(object "${share}/precompiled/plugin_prelude-${WLX_PRELUDE_NAME}.o")
set(archive "${share}/precompiled/plugin_prelude-${WLX_PRELUDE_NAME}.a")
execute_process(
  COMMAND "${WLX_PRELUDE_COMPILER}" ${WLX_PRELUDE_FLAGS} -x c++-header "${share}/cli/shell/${WLX_PRELUDE_HEADER}" -o "${pch}"
  RESULT_VARIABLE result ERROR_VARIABLE errors)
if(result EQUAL 0 AND WLX_PRELUDE_WITH_CODE)
  file(REMOVE "${archive}")
  execute_process(COMMAND "${WLX_PRELUDE_COMPILER}" ${WLX_PRELUDE_CODE_FLAGS} -c "${pch}" -o "${object}"
                  RESULT_VARIABLE result ERROR_VARIABLE errors)
  if(result EQUAL 0)
    execute_process(COMMAND "${WLX_PRELUDE_AR}" qc "${archive}" "${object}" RESULT_VARIABLE result ERROR_VARIABLE errors)
  endif()
  file(REMOVE "${object}")
  if(NOT result EQUAL 0)
    file(REMOVE "${pch}" "${archive}")
  endif()
endif()
if(NOT result EQUAL 0)
  message(WARNING "plugin_prelude-${WLX_PRELUDE_NAME}.pch not precompiled (${errors}): model files' plugins compile without it")
else()
  message(STATUS "Precompiled: ${pch}")
endif()
