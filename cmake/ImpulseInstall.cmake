# SPDX-License-Identifier: Apache-2.0
# `cmake --install`: the impulse tool, the libraries (static), their facades and the headers the
# facades list under include/impulse/ (docs/design.md §2 "Facades"; app/ installs none), the built-in scenes, a CMake package (find_package(impulse) gives
# impulse::numeric ... impulse::scenes) and a pkg-config file (impulse.pc).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(IMPULSE_LIBRARIES ${IMPULSE_LIBRARY_FOLDERS})
set(IMPULSE_INSTALL_INCLUDEDIR ${CMAKE_INSTALL_INCLUDEDIR}/impulse)

# In the build tree a library's headers are found from the source root ("scenes/scenes.h") and
# as a consumer names them (<impulse/scenes/scenes.h>, the root CMakeLists.txt); installed, only
# as <impulse/...> from include/. The warning flags stay with this project's own build; the
# floating-point contract (bit-identical frames) travels with the targets.
set(headers)
foreach(lib ${IMPULSE_LIBRARIES})
    get_target_property(dirs impulse_${lib} INTERFACE_INCLUDE_DIRECTORIES)
    list(TRANSFORM dirs REPLACE "^${PROJECT_SOURCE_DIR}$"
         "$<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>;$<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>")
    set_target_properties(impulse_${lib} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${dirs}"
                          EXPORT_NAME ${lib})
    # The facade and what it lists: every header at the folder's top level
    # (tests/docs/check_layering.py holds the two equal); detail/ stays home.
    file(GLOB lib_headers ${PROJECT_SOURCE_DIR}/${lib}/*.h)
    list(APPEND headers ${lib_headers})
endforeach()
# Installed headers include each other by the installed names: cmake/InstallHeaders.cmake
# rewrites `#include "scenes/scene.h"` to `#include <impulse/scenes/scene.h>` as it copies.
string(REPLACE ";" "|" library_regex "${IMPULSE_LIBRARIES}")
install(CODE "set(IMPULSE_HEADERS \"${headers}\")
set(IMPULSE_LIBRARY_REGEX \"${library_regex}\")
set(IMPULSE_HEADER_STAGE \"${PROJECT_BINARY_DIR}/installed_headers\")
set(IMPULSE_HEADER_DESTINATION \"\${CMAKE_INSTALL_PREFIX}/${IMPULSE_INSTALL_INCLUDEDIR}\")")
install(SCRIPT ${CMAKE_CURRENT_LIST_DIR}/InstallHeaders.cmake)
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
