# Install rules (GLOW_INSTALL, on when Glow is the top-level project): the runtime (glow::runtime) and,
# with GLOW_WITH_GL, the GL 4.5 backend (glow::gl) and its GL entry-point table (glow::glfns), their
# public headers, a CMake package (find_package(glow [COMPONENTS runtime gl])) with a version file,
# and glow.pc for pkg-config (the runtime). Static libraries, or shared ones with BUILD_SHARED_LIBS. The
# linker, the CPU hosts kit and the samples are tools of this repository, not part of the SDK
# (docs/integration.md, "Build and link").
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# BUILD_SHARED_LIBS: the shared twins (libglow_runtime.so.0.1, libglow_gl.so.0.1 with the GL entry-point
# table inside; runtime/CMakeLists.txt, integration/gpu/CMakeLists.txt) under the same exported names.
if(BUILD_SHARED_LIBS)
  set(glow_rt glow_runtime_shared)
  set(glow_gl_t glow_gl_shared)
else()
  set(glow_rt glow_runtime)
  set(glow_gl_t glow_gl)
endif()
set(glow_install_targets ${glow_rt})
set_target_properties(${glow_rt} PROPERTIES EXPORT_NAME runtime)
target_include_directories(${glow_rt} INTERFACE $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
install(FILES ${PROJECT_SOURCE_DIR}/runtime/include/glow/glow.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/glow)
set(GLOW_PACKAGE_COMPONENTS runtime)
if(TARGET ${glow_gl_t} AND TARGET glow_glfns)
  if(BUILD_SHARED_LIBS) # glow::glfns stays a name consumers can link: here an interface onto libglow_gl
    add_library(glow_glfns_iface INTERFACE)
    target_link_libraries(glow_glfns_iface INTERFACE glow_gl_shared)
    set(glow_glfns_t glow_glfns_iface)
  else()
    set(glow_glfns_t glow_glfns)
  endif()
  list(APPEND glow_install_targets ${glow_gl_t} ${glow_glfns_t})
  set_target_properties(${glow_gl_t} PROPERTIES EXPORT_NAME gl)
  set_target_properties(${glow_glfns_t} PROPERTIES EXPORT_NAME glfns)
  foreach(t ${glow_gl_t} ${glow_glfns_t})
    target_include_directories(${t} INTERFACE $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  endforeach()
  install(FILES ${PROJECT_SOURCE_DIR}/integration/gpu/include/glow/glow_gl.h
                ${PROJECT_SOURCE_DIR}/integration/gpu/include/glow/glow_gl_loader.h
                ${PROJECT_SOURCE_DIR}/integration/gpu/include/glow/glow_glfns.h
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/glow)
  list(APPEND GLOW_PACKAGE_COMPONENTS gl)
endif()

install(TARGETS ${glow_install_targets} EXPORT glowTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
set(glow_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/glow)
install(EXPORT glowTargets NAMESPACE glow:: DESTINATION ${glow_cmake_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/glowConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/glowConfig.cmake INSTALL_DESTINATION ${glow_cmake_dir})
# 0.x: minor versions may break the API, so only the same minor is compatible
write_basic_package_version_file(${PROJECT_BINARY_DIR}/glowConfigVersion.cmake VERSION ${PROJECT_VERSION}
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/glowConfig.cmake ${PROJECT_BINARY_DIR}/glowConfigVersion.cmake
        DESTINATION ${glow_cmake_dir})
# relocatable: the prefix is found from the .pc file's own folder, so `cmake --install --prefix P` works
file(RELATIVE_PATH GLOW_PC_TO_PREFIX /glow-prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig /glow-prefix)
configure_file(${PROJECT_SOURCE_DIR}/cmake/glow.pc.in ${PROJECT_BINARY_DIR}/glow.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/glow.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
