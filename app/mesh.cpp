// SPDX-License-Identifier: Apache-2.0
// `impulse mesh ...` and `impulse trajectories`: parse, check everything, call impulse::mesh,
// write (atomically, through mesh::write_mesh and output::write_rgb_image).

#include "app/mesh.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>

#include "app/commands.h"
#include "app/parse.h"
#include "mesh/mesh.h"
#include "numeric/errors.h"
#include "output/output.h"
#include "scenes/scenes.h"

namespace impulse::app {
namespace {

/// The mesh's bounding box.
struct Box {
    Eigen::Vector3d lo, hi;
    double diagonal() const { return (hi - lo).norm(); }
    Eigen::Vector3d centre() const { return 0.5 * (lo + hi); }
};

Box bounds(const mesh::Mesh& m) {
    Box b{Eigen::Vector3d::Constant(INFINITY), Eigen::Vector3d::Constant(-INFINITY)};
    for (const mesh::Vec3& p : m.positions) b.lo = b.lo.cwiseMin(p.cast<double>()), b.hi = b.hi.cwiseMax(p.cast<double>());
    return b;
}

/// The noise of --scale (kernel radius; `fallback` when not given), --density and --seed.
synth::SolidParams noise_params(const MeshOptions& o, double fallback, int dims = 3) {
    synth::SolidParams p;
    p.kernel.radius = o.scale.empty() ? fallback : parse_whole<double>("--scale", o.scale, "a length > 0");
    if (!(p.kernel.radius > 0)) throw ValueError("--scale " + o.scale + ": expected a length > 0");
    p.density = parse_whole<double>("--density", o.density, "impulses per kernel volume in (0, 1000]");
    const auto seed = parse_whole<long long>("--seed", o.seed, "an integer in [0, 2^63 - 1]");
    if (seed < 0) throw ValueError("--seed " + o.seed + ": expected an integer in [0, 2^63 - 1]");
    p.seed = uint64_t(seed);
    p.dims = dims;
    synth::SolidNoise{p};  // its own checks, before any work
    return p;
}

double positive(const std::string& option, const std::string& text) {
    const double v = parse_whole<double>(option, text, "a number > 0");
    if (!(v > 0)) throw ValueError(option + " " + text + ": expected a number > 0");
    return v;
}

Eigen::Vector3d parse_axis(const std::string& text) {
    if (text == "x" || text == "y" || text == "z") return Eigen::Vector3d::Unit(text[0] - 'x');
    const auto v = parse_triple("--axis", text);
    const Eigen::Vector3d a(v[0], v[1], v[2]);
    if (!(a.norm() > 0)) throw ValueError("--axis " + text + ": expected x, y, z or a nonzero vector a,b,c");
    return a;
}

/// The colour ramp and profile numbers of the built-in 2-D scene of the same name (scenes/wood.toml,
/// scenes/marble.toml), so carved and flat wood look alike.
scenes::Scene builtin_look(const std::string& transform) {
    if (transform != "wood" && transform != "marble")
        throw ValueError("--transform " + transform + ": expected one of wood, marble");
    return scenes::load_scene(scenes::resolve_scene(transform));
}

mesh::SolidTexture texture_params(const MeshOptions& o, const Box& box) {
    const scenes::Scene look = builtin_look(o.transform);
    const double d = box.diagonal() > 0 ? box.diagonal() : 1.0;
    mesh::SolidTexture t;
    t.noise = noise_params(o, d / 6.0);  // features a sixth of the object: visible, not busy
    t.ramp = look.shading.ramp;
    t.transform = look.transform;
    t.direction = parse_axis(o.axis);
    t.origin = box.centre();
    if (!o.center.empty()) {
        const auto c = parse_triple("--center", o.center);
        t.origin = Eigen::Vector3d(c[0], c[1], c[2]);
    }
    t.transform.ring_width = o.ring_width.empty() ? d / 24.0 : positive("--ring-width", o.ring_width);
    t.transform.frequency = o.frequency.empty() ? 10.0 / d : positive("--frequency", o.frequency);
    if (!o.turbulence.empty()) t.transform.turbulence = parse_whole<double>("--turbulence", o.turbulence, "a number >= 0");
    if (!o.growth.empty()) t.transform.growth = parse_whole<double>("--growth", o.growth, "a number in [0, 1)");
    if (!o.sharpness.empty()) t.transform.sharpness = parse_whole<double>("--sharpness", o.sharpness, "a number >= 1");
    mesh::validate(t);
    return t;
}

/// "z=0" (or x=, y=): the section's plane, over the box's extent in the other two axes.
mesh::Section parse_section(const MeshOptions& o, const Box& box) {
    const std::string& s = o.section;
    if (s.size() < 3 || s[1] != '=' || (s[0] != 'x' && s[0] != 'y' && s[0] != 'z'))
        throw ValueError("--section " + s + ": expected x=V, y=V or z=V");
    mesh::Section sec;
    sec.axis = s[0] - 'x';
    sec.value = parse_whole<double>("--section", s.substr(2), "x=V, y=V or z=V with V a number");
    const int u = (sec.axis + 1) % 3, v = (sec.axis + 2) % 3;
    sec.lo = {box.lo[u], box.lo[v]}, sec.hi = {box.hi[u], box.hi[v]};
    const int n = parse_int("--pixels", o.pixels, 16, 8192);
    const Eigen::Vector2d ext = (sec.hi - sec.lo).cwiseMax(1e-12);
    sec.width = ext.x() >= ext.y() ? n : std::max(16, int(std::lround(n * ext.x() / ext.y())));
    sec.height = ext.x() >= ext.y() ? std::max(16, int(std::lround(n * ext.y() / ext.x()))) : n;
    return sec;
}

void check_image_output(const std::string& path) {
    if (!output::is_image_path(path))
        throw ValueError(path + ": expected an image (.png .exr .tif .jpg) for --section");
}

int run_texture(const MeshOptions& o) {
    o.section.empty() ? mesh::check_mesh_output(o.output) : check_image_output(o.output);
    mesh::Mesh m = mesh::read_mesh(o.input);
    const Box box = bounds(m);
    const mesh::SolidTexture t = texture_params(o, box);
    if (!o.section.empty()) {
        const mesh::Section s = parse_section(o, box);
        output::write_rgb_image(o.output, s.width, s.height, mesh::solid_texture_section(t, s),
                                {{"command", "impulse mesh texture --section " + o.section}});
        return 0;
    }
    mesh::texture_mesh(t, m);
    mesh::write_mesh(o.output, m);
    return 0;
}

int run_porous(const MeshOptions& o) {
    mesh::check_mesh_output(o.output);
    mesh::PorousParams p;
    p.noise = noise_params(o, 0.25);
    p.envelope = mesh::parse_envelope(o.envelope);
    p.falloff = positive("--falloff", o.falloff);
    p.iso = parse_whole<double>("--iso", o.iso, "a number (standard deviations of the noise)");
    p.size = parse_int("--size", o.size, 8, 1024);
    const mesh::PorousField field = mesh::porous_field(p);
    mesh::write_mesh(o.output, mesh::porous_mesh(field, p.iso));
    return 0;
}

int run_deform(const MeshOptions& o) {
    const bool animated = !o.frames.empty();
    const int frames = animated ? parse_int("--frames", o.frames, 1, 100000) : 1;
    if (animated && !find_pattern(o.output).found)
        throw ValueError(o.output + ": --frames needs a numbered output such as blob_####.obj");
    mesh::check_mesh_output(animated ? expand_pattern(o.output, 0) : o.output);
    mesh::DeformParams p;
    p.noise = noise_params(o, 1.0, animated ? 4 : 3);
    p.amount = parse_whole<double>("--amount", o.amount, "a length (mesh units per standard deviation)");
    const double speed = o.speed.empty() ? p.noise.kernel.radius / 24.0 : positive("--speed", o.speed);
    const mesh::Mesh m = mesh::read_mesh(o.input);
    for (int f = 0; f < frames; ++f) {
        p.t = double(f) * speed;  // moving through the 4th dimension of the noise
        mesh::write_mesh(animated ? expand_pattern(o.output, f) : o.output, mesh::deform_mesh(p, m));
    }
    return 0;
}

int run_view(const MeshOptions& o) {
    if (!output::is_image_path(o.output)) throw ValueError(o.output + ": expected an image (.png .exr .tif .jpg)");
    mesh::PreviewView v;
    v.width = v.height = parse_int("--pixels", o.pixels, 16, 8192);
    v.azimuth_deg = parse_whole<double>("--azimuth", o.azimuth, "degrees");
    v.elevation_deg = parse_whole<double>("--elevation", o.elevation, "degrees");
    const mesh::Mesh m = mesh::read_mesh(o.input);
    output::write_rgb_image(o.output, v.width, v.height, mesh::render_preview(m, v),
                            {{"command", "impulse mesh view"}});
    return 0;
}

void add_noise_options(CLI::App* c, MeshOptions& o, const std::string& scale_help) {
    c->add_option("--scale", o.scale, scale_help);
    c->add_option("--density", o.density, "Impulses per kernel volume, in (0, 1000] (default 16)");
    c->add_option("--seed", o.seed, "Seed of the noise, integer in [0, 2^63 - 1] (default 0)");
}

void add_texture(CLI::App* mesh, MeshOptions& o) {
    CLI::App* c = mesh->add_subcommand("texture", "Colour every vertex from solid wood or marble (Lewis 1989 §5.1)");
    c->add_option("input", o.input, "Mesh to colour (OBJ, PLY or any format assimp reads)")->required();
    c->add_option("-o,--output", o.output, "OUT.ply or OUT.obj (vertex colours); with --section an image")->required();
    c->add_option("--transform", o.transform, "wood or marble")->required();
    c->add_option("--section", o.section, "Write the planar section x=V, y=V or z=V through the block as an image");
    c->add_option("--pixels", o.pixels, "The section's longer side in pixels (default 512)");
    add_noise_options(c, o, "Kernel radius of the perturbing noise, mesh units (default: bounding box diagonal / 6)");
    c->add_option("--axis", o.axis, "Wood: the trunk's axis; marble: the direction across the stripes; x, y, z or a,b,c (default z)");
    c->add_option("--center", o.center, "A point of the axis x,y,z (default: the bounding box's centre)");
    c->add_option("--turbulence", o.turbulence, "Rings (wood) or radians (marble) per standard deviation of the noise");
    c->add_option("--ring-width", o.ring_width, "Wood: mean ring width, mesh units (default diagonal / 24)");
    c->add_option("--growth", o.growth, "Wood: ring width irregularity in [0, 1)");
    c->add_option("--sharpness", o.sharpness, "Wood: latewood exponent >= 1");
    c->add_option("--frequency", o.frequency, "Marble: stripes per mesh unit along the axis (default 10 / diagonal)");
}

void add_models(CLI::App* mesh, MeshOptions& o) {
    CLI::App* p = mesh->add_subcommand("porous", "Porous object: iso-surface of noise times an envelope (Lewis 1989 §5.2)");
    p->add_option("-o,--output", o.output, "OUT.obj or OUT.ply")->required();
    p->add_option("--iso", o.iso, "The iso value T in standard deviations of the noise, nonzero")->required();
    p->add_option("--envelope", o.envelope, "sphere or box over [-1, 1]^3 (default sphere)");
    p->add_option("--falloff", o.falloff, "Width of the envelope's taper, in (0, 1] (default 0.3)");
    p->add_option("--size", o.size, "Grid samples across the object, in [8, 1024] (default 128)");
    add_noise_options(p, o, "Kernel radius, object units (the object spans [-1, 1]^3; default 0.25)");
    CLI::App* d = mesh->add_subcommand("deform", "Displace every vertex by vector solid noise (Lewis 1989 §5.3)");
    d->add_option("input", o.input, "Mesh to deform")->required();
    d->add_option("-o,--output", o.output, "OUT.obj or OUT.ply; with --frames a pattern OUT_####.obj")->required();
    d->add_option("--amount", o.amount, "Displacement per standard deviation, mesh units")->required();
    add_noise_options(d, o, "Kernel radius L, mesh units: the size of the bumps");
    d->get_option("--scale")->required();
    d->add_option("--frames", o.frames, "Write N frames moving through 4-D noise (a numbered sequence)");
    d->add_option("--speed", o.speed, "With --frames: noise units per frame along the 4th axis (default L / 24)");
    CLI::App* s = mesh->add_subcommand("sphere", "Write a unit icosphere to start from");
    s->add_option("-o,--output", o.output, "OUT.obj or OUT.ply")->required();
    s->add_option("--levels", o.levels, "Subdivisions of the icosahedron, in [0, 8] (default 5: 10242 vertices)");
    CLI::App* v = mesh->add_subcommand("view", "Render a mesh orthographically to an image (a look without Blender)");
    v->add_option("input", o.input, "Mesh (OBJ, PLY ...)")->required();
    v->add_option("-o,--output", o.output, "Image (.png .exr .tif .jpg)")->required();
    v->add_option("--pixels", o.pixels, "Width and height in pixels (default 512)");
    v->add_option("--azimuth", o.azimuth, "Degrees round z from +x (default 35)");
    v->add_option("--elevation", o.elevation, "Degrees above the xy plane (default 25)");
}

}  // namespace

CLI::App* add_mesh(CLI::App& app, MeshOptions& o) {
    CLI::App* mesh = app.add_subcommand("mesh", "Solid noise on meshes (Lewis 1989 §5): texture, porous, deform; sphere, view");
    mesh->require_subcommand(1);
    add_texture(mesh, o);
    add_models(mesh, o);
    return mesh;
}

CLI::App* add_trajectories(CLI::App& app, MeshOptions& o) {
    CLI::App* c = app.add_subcommand("trajectories", "Paths of particles forced by vector solid noise (Lewis 1989 Figs. 12-13)");
    c->add_option("-o,--output", o.output, "paths.ply (2-vertex faces) or paths.obj (l records)")->required();
    c->add_option("--particles", o.particles, "Particles, in [1, 10^6] (default 200)");
    c->add_option("--steps", o.steps, "Time steps, in [1, 10^5] (default 400)");
    c->add_option("--dt", o.dt, "Time step (default 0.01)");
    c->add_option("--force", o.force, "Acceleration per standard deviation of the noise (default 10)");
    c->add_option("--drag", o.drag, "Drag per unit time, >= 0 (default 10: the paths follow the streamlines)");
    c->add_option("--radius", o.radius, "Start points uniform in a ball of this radius (default 1)");
    add_noise_options(c, o, "Kernel radius of the force field (default 0.5)");
    return c;
}

int run_mesh(const CLI::App& mesh, const MeshOptions& o) {
    if (mesh.got_subcommand("texture")) return run_texture(o);
    if (mesh.got_subcommand("porous")) return run_porous(o);
    if (mesh.got_subcommand("deform")) return run_deform(o);
    if (mesh.got_subcommand("sphere")) {
        mesh::check_mesh_output(o.output);
        mesh::write_mesh(o.output, mesh::icosphere(parse_int("--levels", o.levels, 0, 8)));
        return 0;
    }
    return run_view(o);
}

int run_trajectories(const MeshOptions& o) {
    mesh::check_mesh_output(o.output);
    mesh::TrajectoryParams p;
    p.noise = noise_params(o, 0.5);
    p.particles = parse_int("--particles", o.particles, 1, 1000000);
    p.steps = parse_int("--steps", o.steps, 1, 100000);
    p.dt = parse_whole<double>("--dt", o.dt, "a time step > 0");
    p.force = parse_whole<double>("--force", o.force, "a number");
    p.drag = parse_whole<double>("--drag", o.drag, "a number >= 0");
    p.radius = parse_whole<double>("--radius", o.radius, "a length > 0");
    mesh::write_mesh(o.output, mesh::trajectories(p));
    return 0;
}

}  // namespace impulse::app
