# SPDX-License-Identifier: Apache-2.0
# Cross-compiling for arm64 with Debian's g++-aarch64-linux-gnu against an arm64 Debian root
# that holds the core's -dev packages (scripts/arm64_check.sh makes one with mmdebstrap):
#   cmake -S . -B build-arm64/aarch64 -DIMPULSE_CORE_ONLY=ON \
#         -DCMAKE_TOOLCHAIN_FILE=cmake/aarch64-linux-gnu.cmake -DIMPULSE_ARM64_ROOT=<root>
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
# try_compile projects read this file again: hand them the root.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES IMPULSE_ARM64_ROOT)
if(NOT IMPULSE_ARM64_ROOT OR NOT EXISTS "${IMPULSE_ARM64_ROOT}/usr/include")
    message(FATAL_ERROR "IMPULSE_ARM64_ROOT = \"${IMPULSE_ARM64_ROOT}\": expected an arm64 Debian "
                        "root with the core's -dev packages (scripts/arm64_check.sh makes one)")
endif()
set(CMAKE_SYSROOT "${IMPULSE_ARM64_ROOT}")
set(CMAKE_FIND_ROOT_PATH "${IMPULSE_ARM64_ROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# pkg-config (FFTW) reads the root's .pc files and prefixes their paths with the root.
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${IMPULSE_ARM64_ROOT}")
set(ENV{PKG_CONFIG_LIBDIR}
    "${IMPULSE_ARM64_ROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${IMPULSE_ARM64_ROOT}/usr/share/pkgconfig")
