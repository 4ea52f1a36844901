# At install time (CMakeLists.txt's install(CODE)): a model file's plugins' precompiled header,
# compiled from the installed cli/shell/plugin_prelude.hpp. Clang records the header a precompiled
# header was made from and refuses it once that file is gone, so the build tree's copy, made from
# the source tree's header, would stop working when the checkout is removed. A failure costs the
# installed wlx's plugins only their speed (model_plugin.cpp compiles without it): a warning.
# In: WLX_PRELUDE_COMPILER, WLX_PRELUDE_FLAGS (a list), WLX_PRELUDE_NAME (plugin_prelude-<name>.pch).
# Absolute: the header's path is recorded as given, and a relative one (`cmake --install --prefix
# build/install`) would be looked up from wherever a plugin is built.
get_filename_component(share "$ENV{DESTDIR}${CMAKE_INSTALL_PREFIX}/${WLX_PRELUDE_DATADIR}/wlx" ABSOLUTE)
file(MAKE_DIRECTORY "${share}/precompiled")
execute_process(
  COMMAND "${WLX_PRELUDE_COMPILER}" ${WLX_PRELUDE_FLAGS} -x c++-header "${share}/cli/shell/plugin_prelude.hpp"
          -o "${share}/precompiled/plugin_prelude-${WLX_PRELUDE_NAME}.pch"
  RESULT_VARIABLE result ERROR_VARIABLE errors)
if(NOT result EQUAL 0)
  message(WARNING "plugin_prelude-${WLX_PRELUDE_NAME}.pch not precompiled (${errors}): model files' plugins compile without it")
else()
  message(STATUS "Precompiled: ${share}/precompiled/plugin_prelude-${WLX_PRELUDE_NAME}.pch")
endif()
