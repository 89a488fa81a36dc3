# SPDX-License-Identifier: Apache-2.0
# Run by `cmake --install` (cmake/ImpulseInstall.cmake sets IMPULSE_HEADERS, the facades and the
# headers they list; IMPULSE_LIBRARY_REGEX, the library folders as a|b|c; IMPULSE_HEADER_STAGE, a
# folder of the build tree; IMPULSE_HEADER_DESTINATION, include/impulse under the prefix).
# Each header is copied with the project's own includes renamed as a consumer writes them,
# "scenes/scene.h" -> <impulse/scenes/scene.h>, so an installed tree answers only to the
# <impulse/...> names (as <openvdb/openvdb.h> and <OpenImageIO/imageio.h> do) and a short name
# such as "scenes/scenes.h" cannot collide with a consumer's own.
foreach(header IN LISTS IMPULSE_HEADERS)
    get_filename_component(folder ${header} DIRECTORY)
    get_filename_component(lib ${folder} NAME)
    get_filename_component(name ${header} NAME)
    file(READ ${header} text)
    string(REGEX REPLACE "#include \"((${IMPULSE_LIBRARY_REGEX})/[^\"]+)\"" "#include <impulse/\\1>"
           text "${text}")
    file(WRITE ${IMPULSE_HEADER_STAGE}/${lib}/${name} "${text}")
    file(INSTALL ${IMPULSE_HEADER_STAGE}/${lib}/${name} DESTINATION ${IMPULSE_HEADER_DESTINATION}/${lib})
endforeach()
