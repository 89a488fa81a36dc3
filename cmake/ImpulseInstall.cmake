# SPDX-License-Identifier: Apache-2.0
# `cmake --install`: the impulse tool, the libraries (static), their headers under
# include/impulse/, the built-in scenes, a CMake package (find_package(impulse) gives
# impulse::numeric ... impulse::scenes) and a pkg-config file (impulse.pc).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(IMPULSE_LIBRARIES numeric kernels sim synth analysis render output volume mesh scenes app)
set(IMPULSE_INSTALL_INCLUDEDIR ${CMAKE_INSTALL_INCLUDEDIR}/impulse)

# In the build tree a library's headers are found from the source root ("scenes/scenes.h");
# installed, from include/impulse/. The warning flags stay with this project's own build; the
# floating-point contract (bit-identical frames) travels with the targets.
foreach(lib ${IMPULSE_LIBRARIES})
    get_target_property(dirs impulse_${lib} INTERFACE_INCLUDE_DIRECTORIES)
    list(TRANSFORM dirs REPLACE "^${PROJECT_SOURCE_DIR}$"
         "$<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>;$<INSTALL_INTERFACE:${IMPULSE_INSTALL_INCLUDEDIR}>")
    set_target_properties(impulse_${lib} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${dirs}"
                          EXPORT_NAME ${lib})
    file(GLOB headers ${PROJECT_SOURCE_DIR}/${lib}/*.h)
    install(FILES ${headers} DESTINATION ${IMPULSE_INSTALL_INCLUDEDIR}/${lib})
endforeach()
get_target_property(options impulse_options INTERFACE_COMPILE_OPTIONS)
list(TRANSFORM options REPLACE "^(-W.*)$" "$<BUILD_INTERFACE:\\1>")
set_target_properties(impulse_options PROPERTIES INTERFACE_COMPILE_OPTIONS "${options}"
                      EXPORT_NAME options)

list(TRANSFORM IMPULSE_LIBRARIES PREPEND impulse_ OUTPUT_VARIABLE targets)
install(TARGETS impulse impulse_options ${targets} EXPORT impulseTargets
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
# The image and video module the tool (and any program using impulse::output's files) loads on
# first use: lib/impulse/ is where io_loader.cpp looks from bin/ and at the install prefix.
install(TARGETS impulse_io LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}/impulse)
# `impulse mesh` and `impulse trajectories` run this companion beside the tool (app/mesh_main.cpp).
install(TARGETS impulse-mesh RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(EXPORT impulseTargets NAMESPACE impulse:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/impulse)
file(GLOB scene_files ${PROJECT_SOURCE_DIR}/scenes/*.toml)
install(FILES ${scene_files} DESTINATION ${CMAKE_INSTALL_DATADIR}/impulse/scenes)

configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/impulseConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/impulseConfig.cmake
                              INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/impulse)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/impulseConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/impulseConfig.cmake ${PROJECT_BINARY_DIR}/impulseConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/impulse)

# pkg-config: static libraries, so their dependencies are Requires (not .private): a consumer
# links them all. Dependency order: each library before those it uses.
string(REGEX REPLACE "[^/]+" ".." IMPULSE_PC_UP "${CMAKE_INSTALL_LIBDIR}/pkgconfig")
configure_file(${CMAKE_CURRENT_LIST_DIR}/impulse.pc.in ${PROJECT_BINARY_DIR}/impulse.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/impulse.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
