# femto_add_plugin(<type> KIND <kind> SOURCES <files...> [LIBRARIES <targets...>])
#
# Builds plugin <type> as the shared library <type>.so (the name the XML `type` uses). Used
# for the built-in plugins and, through the installed femto CMake package, for users' own.
function(femto_add_plugin name)
  cmake_parse_arguments(ARG "" "KIND" "SOURCES;LIBRARIES" ${ARGN})
  if(NOT ARG_KIND OR NOT ARG_SOURCES)
    message(FATAL_ERROR "femto_add_plugin(${name}): KIND and SOURCES are required")
  endif()
  set(target femto_plugin_${name})
  add_library(${target} MODULE ${ARG_SOURCES})
  if(TARGET femto)
    target_link_libraries(${target} PRIVATE femto ${ARG_LIBRARIES})
  else()
    target_link_libraries(${target} PRIVATE femto::femto ${ARG_LIBRARIES})
  endif()
  set_target_properties(${target} PROPERTIES
    PREFIX "" OUTPUT_NAME ${name}
    CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON
    FEMTO_PLUGIN_KIND ${ARG_KIND})
  if(DEFINED FEMTO_PLUGIN_OUTPUT_DIR)
    set_target_properties(${target} PROPERTIES LIBRARY_OUTPUT_DIRECTORY ${FEMTO_PLUGIN_OUTPUT_DIR})
  endif()
  if(DEFINED FEMTO_PLUGIN_INSTALL_DIR AND TARGET femto)
    # Plugins find libfemto_io (films, textures) next to libfemto, whichever program loads
    # them (the femto CLI links it; a test program may not): in the build tree, in the library
    # folder beside theirs (femto_runpath, CMakeLists.txt); installed, two levels up
    # (<libdir>/femto/plugins), which the install writes in place of the first (no longer, so
    # it fits without padding).
    file(RELATIVE_PATH _lib_dir ${FEMTO_PLUGIN_OUTPUT_DIR} ${CMAKE_LIBRARY_OUTPUT_DIRECTORY})
    femto_runpath(${target} "$ORIGIN/${_lib_dir}")
    install(TARGETS ${target} LIBRARY DESTINATION ${FEMTO_PLUGIN_INSTALL_DIR})
    install(CODE "set(_plugin \"${FEMTO_PLUGIN_INSTALL_DIR}/${name}.so\")
      if(NOT IS_ABSOLUTE \"\${_plugin}\")
        set(_plugin \"\${CMAKE_INSTALL_PREFIX}/\${_plugin}\")
      endif()
      file(RPATH_CHANGE FILE \"\$ENV{DESTDIR}\${_plugin}\"
           OLD_RPATH \"\$ORIGIN/${_lib_dir}\" NEW_RPATH \"\$ORIGIN/../..\")")
    set_property(GLOBAL APPEND PROPERTY FEMTO_PLUGIN_TARGETS ${target})
  endif()
endfunction()
