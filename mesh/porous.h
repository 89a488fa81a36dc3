// SPDX-License-Identifier: Apache-2.0
#pragma once
// Porous iso-surface objects (Lewis 1989 §5.2; docs/mesh.md): "objects as the equal-density
// surface of a solid noise", the shape controlled by "multiplying the noise by an analytic
// density function that tapers to zero outside of the desired object shape":
//     F(p) = e(p) eta(p) / sigma,   the object {F > T},
// e a sphere or box envelope over [-1, 1]^3 (1 inside, a smoothstep to 0 over `falloff` at the
// rim, 0 outside), eta the solid noise, sigma its standard deviation (so T is in sd). The surface
// F = T is extracted with OpenVDB's mesher (tools::volumeToMesh) from F sampled on a grid with
// a margin where F = 0: for T != 0 it is closed. Part of impulse::mesh.

#include <vector>

#include "mesh/mesh_io.h"
#include "synth/solid.h"

namespace impulse::mesh {

enum class Envelope { Sphere, Box };
/// "sphere", "box"; anything else throws ValueError listing them.
Envelope parse_envelope(const std::string& name);

struct PorousParams {
    synth::SolidParams noise;  ///< eta: kernel radius in object units (the object spans [-1, 1]^3)
    Envelope envelope = Envelope::Sphere;
    double falloff = 0.3;  ///< width of the envelope's taper at the rim, object units, in (0, 1]
    double iso = 0.5;      ///< T, in standard deviations of the noise, != 0
    int size = 128;        ///< grid samples across [-1, 1], in [8, 1024]
};

/// F on the grid: n^3 samples, sample (i, j, k) at origin + (i, j, k) spacing, x fastest.
struct PorousField {
    std::vector<float> values;
    int n = 0;
    double origin = 0.0, spacing = 0.0;
    float min = 0.0f, max = 0.0f;  ///< the range of F over the grid
};

/// e(p) in [0, 1].
double envelope(Envelope shape, double falloff, double x, double y, double z);
/// Samples F; validates (ValueError naming size, falloff or the noise's field).
PorousField porous_field(const PorousParams& params);
/// The surface F = iso of a sampled field through OpenVDB's mesher (quads and triangles,
/// outward-facing). Throws ValueError "iso = T: outside the field's range [min, max]" when no
/// sample lies on either side, and for T = 0 (F is 0 all round the object).
Mesh porous_mesh(const PorousField& field, double iso);

}  // namespace impulse::mesh
