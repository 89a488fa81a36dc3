// SPDX-License-Identifier: Apache-2.0
// The table libimpulse_io.so exports (output/io_module.h).

#include "output/detail/io_impl.h"

extern "C" const impulse::output::IoModule* impulse_io_module() {
    namespace io = impulse::output::io;
    static const impulse::output::IoModule table = {
        impulse::output::kIoModuleAbi, io::write_pixels,      io::read_image,
        io::image_size_problem,        io::image_mismatch,    io::read_metadata,
        io::probe_image,               io::is_readable_image_path,
        io::read_pixels,               io::write_exr_stack,   io::write_vdb,
        io::read_vdb,                  io::list_vdb_grids,    io::read_vdb_vectors,
        io::encode_png,                io::make_video_sink,   io::quiet_video_logs,
        io::probe_video,               io::decode_video_luma,
        io::write_named_pixels,        io::read_channel,      io::channel_names,
        io::read_vdb_active_box,
    };
    return &table;
}
