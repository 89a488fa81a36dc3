// SPDX-License-Identifier: Apache-2.0
// Solid textures as OpenVDB grids (part of libimpulse_io.so, output/io_module.h).

#include <openvdb/openvdb.h>
#include <unistd.h>

#include <filesystem>

#include "numeric/errors.h"
#include "output/io_impl.h"

namespace impulse::output::io {

void write_vdb(const std::string& path, const std::vector<float>& v, const std::array<int, 3>& n,
               const std::string& description) {
    namespace fs = std::filesystem;
    openvdb::initialize();
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("density");
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    grid->insertMeta("description", openvdb::StringMetadata(description));
    auto acc = grid->getAccessor();
    for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
            for (int i = 0; i < n[0]; ++i)
                acc.setValue({i, j, k}, v[(size_t(k) * n[1] + j) * n[0] + i]);
    const fs::path p(path);
    const std::string tmp = (p.parent_path() / ("." + p.stem().string() + ".partial-" +
                                                std::to_string(::getpid()) + p.extension().string()))
                                .string();
    std::error_code ec;
    try {
        openvdb::io::File file(tmp);
        file.write({grid});
        file.close();
    } catch (const std::exception& e) {
        fs::remove(tmp, ec);
        throw IoError(path + ": cannot write: " + e.what());
    }
    fs::rename(tmp, path, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw IoError(path + ": cannot rename temporary file into place: " + ec.message());
    }
}

}  // namespace impulse::output::io
