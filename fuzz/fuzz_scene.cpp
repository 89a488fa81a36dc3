// SPDX-License-Identifier: Apache-2.0
// libFuzzer target for the scene loader: any bytes must load or fail with impulse::Error —
// never crash, hang, leak or trip a sanitizer.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "scenes/scenes.h"
#include "numeric/errors.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    try {
        impulse::scenes::Scene s = impulse::scenes::load_scene_string(text, "fuzz.toml");
        (void)impulse::scenes::scene_theory(s);
    } catch (const impulse::Error&) {
    }
    return 0;
}
