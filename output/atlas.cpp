// SPDX-License-Identifier: Apache-2.0
// Atlas layouts and the flow-map encoding (docs/export.md).

#include "output/atlas.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <regex>

#include "numeric/errors.h"

namespace impulse::output {
namespace {

constexpr int kMaxAtlasSide = 32768;  // the largest image side the writers take (render --size)

AtlasLayout squarest(int64_t count) {
    AtlasLayout l;
    l.columns = int(std::ceil(std::sqrt(double(count))));
    l.rows = int((count + l.columns - 1) / l.columns);
    return l;
}

}  // namespace

AtlasLayout atlas_layout(const std::string& text, int64_t count, int cell_width, int cell_height) {
    AtlasLayout l = squarest(count);
    if (!text.empty()) {
        static const std::regex re(R"((\d{1,5})x(\d{1,5}))");
        std::smatch m;
        if (!std::regex_match(text, m, re) || std::stoi(m[1].str()) < 1 || std::stoi(m[2].str()) < 1)
            throw ValueError("--layout " + text.substr(0, 40) + ": expected RxC, rows x columns, each >= 1");
        const AtlasLayout fits = l;
        l.rows = std::stoi(m[1].str()), l.columns = std::stoi(m[2].str());
        if (l.cells() < count)
            throw ValueError("--layout " + text + ": " + std::to_string(l.cells()) + " cells cannot hold " +
                             std::to_string(count) + " frames (at least " + std::to_string(count) +
                             " cells, e.g. " + std::to_string(fits.rows) + "x" + std::to_string(fits.columns) + ")");
    }
    l.cell_width = cell_width, l.cell_height = cell_height;
    if (int64_t(l.columns) * cell_width > kMaxAtlasSide || int64_t(l.rows) * cell_height > kMaxAtlasSide)
        throw ValueError("--layout " + std::to_string(l.rows) + "x" + std::to_string(l.columns) + ": an atlas of " +
                         std::to_string(int64_t(l.columns) * cell_width) + "x" +
                         std::to_string(int64_t(l.rows) * cell_height) + " pixels: expected at most " +
                         std::to_string(kMaxAtlasSide) + " a side (a smaller --size)");
    return l;
}

void place_cell(const AtlasLayout& layout, int index, int channels, const float* cell,
                std::vector<float>& atlas) {
    const size_t row_floats = size_t(layout.cell_width) * channels;
    const size_t x0 = size_t(index % layout.columns) * row_floats;
    const size_t y0 = size_t(index / layout.columns) * layout.cell_height;
    const size_t atlas_row = size_t(layout.width()) * channels;
    for (int y = 0; y < layout.cell_height; ++y)
        std::memcpy(&atlas[(y0 + y) * atlas_row + x0], cell + y * row_floats, row_floats * sizeof(float));
}

void encode_flow(const std::vector<double>& vx, const std::vector<double>& vy, double vmax,
                 std::vector<float>& rgb) {
    rgb.assign(vx.size() * 3, 0.0f);
    for (size_t i = 0; i < vx.size(); ++i) {
        rgb[3 * i] = float(std::clamp(0.5 + 0.5 * vx[i] / vmax, 0.0, 1.0));
        rgb[3 * i + 1] = float(std::clamp(0.5 + 0.5 * vy[i] / vmax, 0.0, 1.0));
    }
}

}  // namespace impulse::output
