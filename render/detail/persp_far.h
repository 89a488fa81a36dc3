// SPDX-License-Identifier: Apache-2.0
#pragma once
// The far field of a perspective view (internal to impulse::render; render/perspective.h says
// what it computes). Far from the camera a grazing footprint is hundreds of texture units long
// and a few wide, so each kernel is a thin sliver of the pixel filter along the depth: its
// contribution separates into a profile across (the level's line integral, as in the line
// form) and the pixel filter along (the chord's spread along the axis entering through an
// expansion). Impulses are deposited (linear weights) onto sub-rows of the image that follow the
// circles around the camera's foot (the major axis of every footprint points at the foot), and,
// for kernels that are not radially symmetric, onto direction bins; each sub-row is convolved
// across with its profiles, and each pixel filters the sub-rows along: a few additions per
// impulse, a bounded amount of work per pixel. docs/perspective.md §5 derives it: the circles,
// the Moebius map Y(rho), the expansion around the bin's mean Gaussian and the deposit.

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "render/detail/persp.h"

namespace impulse::render::detail {

/// A far impulse, ready to deposit: in direction bins bin and bin + 1 (mod the bins; radial
/// kernels: one bin) with weights wb[0], wb[1], on sub-rows row and row + 1 at nodes node[e] and
/// node[e] + 1 with weights w[e][0], w[e][1] (node -1: nothing on that sub-row).
struct FarItem {
    int32_t row = 0, bin = 0;
    int32_t node[2] = {-1, -1};
    float w[2][2] = {{0, 0}, {0, 0}};
    float wb[2] = {1, 0};
};

/// Memory of FarField::render kept from frame to frame (PerspectiveWorkspace).
struct FarScratch {
    std::vector<uint32_t> order;  ///< far impulses sorted by band
    std::vector<float> grids;     ///< the sub-rows' node grids
};

/// Profiles of the far field: the derivatives 0 .. 4 of the along Gaussian.
constexpr int kFarProfiles = 5;

class FarField {
public:
    /// Sets the far zone of a frame up: inactive when the form does not apply (filtering off,
    /// isotropic rule, no fade, kernels with negative lobes, or no footprint long enough).
    FarField(const kernels::KernelPyramid& pyramid, const PerspectiveView& view,
             const PixelCoords& coords, const AntiAlias& aa) {
        setup(pyramid, view, coords, aa);
    }
    /// Inactive until set up.
    FarField() = default;
    /// Sets the far zone of another frame up, reusing this one's memory (a frame's sub-rows and
    /// per-pixel arrays are megabytes, new pages every frame otherwise).
    void setup(const kernels::KernelPyramid& pyramid, const PerspectiveView& view,
               const PixelCoords& coords, const AntiAlias& aa);
    bool active() const { return m_active; }
    /// Whether the impulse at (rx, ry) from the camera's foot belongs to the far field.
    bool contains(double rx, double ry) const {
        return m_active && rx * rx + ry * ry >= m_rho_far2 && depth(rx, ry) >= m_depth_min;
    }
    /// Bands of sub-rows, the unit of the deposit (render).
    int bands() const {
        return m_active ? (static_cast<int>(m_rows.size()) + kBand - 1) / kBand : 0;
    }
    /// The sub-row coordinate q of a far impulse at (rx, ry) from the foot (sub-row floor(q),
    /// weight q - floor(q) on the next), -1 when it adds nothing (behind the camera, or beyond
    /// the sub-rows). item() may still drop it.
    double row_coordinate(double rx, double ry) const {
        const double q = (y_of(std::sqrt(rx * rx + ry * ry)) - m_y0) * m_inv_dy;
        return depth(rx, ry) > 0.0 && q >= 0.0 && q < static_cast<double>(m_rows.size() - 1)
                   ? q
                   : -1.0;
    }
    /// The band whose deposit takes the impulse at sub-row coordinate q >= 0.
    static int band_of(double q) { return static_cast<int>(q) / kBand; }
    /// The item of a far impulse at (rx, ry) from the foot, at sub-row coordinate q
    /// (row_coordinate() >= 0) and image column sx (column()), turned by theta (radians, the
    /// kernel's own orientation included; unused for radial kernels); false when it adds nothing
    /// (faded out, too far off the image).
    bool item(double rx, double ry, double q, double sx, float weight, double theta,
              FarItem& it) const;
    /// The impulses of a frame as the far field reads them. Impulse i of `imp` lies at
    /// (x[i] - cam_x, y[i] - cam_y) from the foot, turned by orient + theta[i]; q[i]:
    /// row_coordinate() of it, or -1 when it is not far; counts[c * bands() + b]: how many
    /// impulses of chunk c (impulses [c * chunk, (c + 1) * chunk)) are in band b (band_of).
    struct Impulses {
        const sim::Impulses* imp = nullptr;
        double cam_x = 0, cam_y = 0, orient = 0;
        const double* q = nullptr;
        const uint32_t* counts = nullptr;
        size_t chunk = 1;
    };
    /// Adds the far field of the impulses to `out`, summed in their canonical order whatever the
    /// threads; returns how many impulses it drew (item() true).
    size_t render(const Impulses& in, Frame& out, const PerspLoops& loops, bool parallel,
                  FarScratch& scratch) const;

private:
    struct Setup;  // the steps of setup (persp_far.cpp)
    struct Pass;   // the steps of render (persp_far.cpp)
    /// A sub-row: its circle, the across coordinate, node grid and, per segment of columns,
    /// the filter.
    struct Row {
        double y = 0;  ///< y' of the circle
        /// Across coordinate xi: texture units along the circle, at image columns 0 .. W
        /// (linear between, extended with the end slopes beyond).
        std::vector<double> xi;
        double margin = 0;        ///< pixels beyond the image edges that still reach it
        double xi0 = 0, dxi = 1;  ///< node n at xi0 + n dxi
        double inv_dxi = 1;       ///< 1 / dxi (item: a multiply per impulse)
        int nodes = 0, taps = 0;  ///< node count, half-width of the profiles in nodes
        std::array<bool, kFarProfiles> used{};  ///< which profiles matter (0 always)
        std::vector<int> segment_node;  ///< first node of each segment (segments + 1 entries)
        std::vector<float> weight;      ///< per segment: fade / (sqrt(2 pi) s_major)
        std::vector<float> sbar;        ///< per segment: variance of the along Gaussian, px^2
        /// per segment, direction bin and profile: 2 taps + 1 values (offsets -taps .. taps)
        std::vector<float> tables;
    };
    bool m_active = false;
    int m_width = 0, m_height = 0, m_segments = 1;
    double m_segment_px = 1;
    double m_ya = 0, m_yb = 0, m_yc = 0, m_yd = 0;  ///< Y(rho) = (a rho + b) / (c rho + d)
    double m_rho_far2 = 0, m_depth_min = 0;
    double m_P[9] = {};  ///< the view's homography (PerspectiveView::homography)
    double m_inv_segment_px = 1;
    int m_bins = 1;                     ///< direction bins (1: radial kernel)
    double m_period = 1;                ///< the bins' period, radians
    double m_v_sign = 1, m_u_sign = 1;  ///< orientation of the tables (see setup)
    double m_y0 = 0, m_dy = 1;          ///< sub-row r at y' = y0 + r dy
    double m_inv_dy = 1;                ///< 1 / dy (item: a multiply, not a divide, per impulse)
    std::vector<Row> m_rows;
    /// Pixels that receive the far field: rows [m_j0, m_j1), per pixel y', 1 / kappa, 1 / s,
    /// 1 / sqrt(s).
    int m_j0 = 0, m_j1 = 0;
    std::vector<float> m_yp, m_ik, m_is, m_rs;
    std::vector<double> m_rho_edge;  ///< set-up only: rho at the pixel edges of those rows
    /// Per row of [m_j0, m_j1) and piece of kAlongPiece columns: the sub-rows [m_reach0,
    /// m_reach1) within the along filter's reach of its pixels (Setup::along_reach).
    std::vector<int> m_reach0, m_reach1;

    double y_of(double rho) const { return (m_ya * rho + m_yb) / (m_yc * rho + m_yd); }
    /// Sub-rows per deposit task (a band); the halo between bands fixes the order of the sums,
    /// so it is part of the output's bits.
    static constexpr int kBand = 16;
    /// The depth of a point at (rx, ry) from the foot.
    double depth(double rx, double ry) const { return m_P[6] * rx + m_P[7] * ry + m_P[8]; }
    /// The image column of an impulse at (rx, ry) from the foot.
    double column(double rx, double ry) const {
        return (m_P[0] * rx + m_P[1] * ry + m_P[2]) / depth(rx, ry);
    }
    // Inlined into item (called for every far impulse; the calls cost more than the bodies).
    [[gnu::always_inline]] inline float row_weight(const Row& row, double sx) const;
    /// xi of image column x on a sub-row.
    [[gnu::always_inline]] inline double xi_at(const Row& row, double x) const;
};

}  // namespace impulse::render::detail
