// SPDX-License-Identifier: Apache-2.0
// Finding and loading libimpulse_io.so (output/io_module.h).

#include <dlfcn.h>

#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

#include "numeric/errors.h"
#include "output/io_module.h"

// Defined when the program links the module's objects (impulse::output_io); null otherwise.
extern "C" const impulse::output::IoModule* impulse_io_module() __attribute__((weak));

namespace impulse::output {
namespace {

namespace fs = std::filesystem;

constexpr const char* kModuleName = "libimpulse_io.so";

/// Where to look, in order: beside the executable (the build tree, and a tool copied with its
/// module), ../lib/impulse/ from it (an installed tree, wherever it was moved), and the
/// configured install location (a program of another project linked to the installed
/// libraries).
std::vector<fs::path> candidates() {
    std::vector<fs::path> out;
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) {
        out.push_back(exe.parent_path() / kModuleName);
        out.push_back(exe.parent_path().parent_path() / IMPULSE_IO_LIBDIR / "impulse" / kModuleName);
    }
    out.push_back(fs::path(IMPULSE_IO_INSTALLED) / kModuleName);
    return out;
}

const IoModule* load() {
    if (impulse_io_module) return impulse_io_module();
    std::string tried;
    for (const fs::path& p : candidates()) {
        std::error_code ec;
        if (!fs::exists(p, ec)) {
            tried += (tried.empty() ? "" : ", ") + p.string();
            continue;
        }
        // RTLD_LOCAL: the module's copies of the static libraries stay its own. RTLD_LAZY: of the
        // ~150 k symbol references of OIIO, libav and their dependencies, only those called get
        // bound (RTLD_NOW spent ~100 ms CPU binding them all).
        void* handle = ::dlopen(p.c_str(), RTLD_LAZY | RTLD_LOCAL);
        if (!handle) throw IoError(std::string("cannot load ") + p.string() + ": " + ::dlerror());
        using Entry = const IoModule* (*)();
        auto entry = reinterpret_cast<Entry>(::dlsym(handle, "impulse_io_module"));
        if (!entry) throw IoError(p.string() + ": not an impulse image and video module");
        const IoModule* m = entry();
        if (!m || m->abi != kIoModuleAbi)
            throw IoError(p.string() + ": from another build of impulse (module ABI " +
                          std::to_string(m ? m->abi : 0) + ", expected " +
                          std::to_string(kIoModuleAbi) + "): reinstall");
        return m;  // never unloaded: OIIO and libav keep threads and static state
    }
    throw IoError(std::string("cannot find the image and video module ") + kModuleName +
                  " (looked for " + tried + "): reinstall impulse");
}

}  // namespace

const IoModule& io_module() {
    static std::once_flag once;
    static const IoModule* module = nullptr;
    std::call_once(once, [] { module = load(); });  // an exception leaves it to try again
    return *module;
}

IoPreload::IoPreload()
    : m_thread([] {
          try {
              io_module();
          } catch (...) {  // io_module() tries again where the module is needed, and says why
          }
      }) {}

IoPreload::~IoPreload() { m_thread.join(); }

}  // namespace impulse::output
