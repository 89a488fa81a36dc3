// SPDX-License-Identifier: Apache-2.0
// `impulse mesh` and `impulse trajectories` as separate processes (issue 21): files read back
// with assimp, deterministic and order-free; bad input is one line, a non-zero exit and no file.

#include <catch2/catch.hpp>
#include <algorithm>
#include <map>
#include <numeric>
#include <random>

#include "mesh/mesh.h"
#include "output/image.h"
#include "tests/support.h"

namespace {

using namespace impulse;
using namespace impulse::test;
using Catch::Matchers::Contains;

Result run(const TempDir& dir, const std::string& args) { return shell(dir, quote(IMPULSE_BINARY) + " " + args); }

/// The mesh with its vertices in another order (faces renumbered).
mesh::Mesh shuffled(const mesh::Mesh& m, unsigned seed) {
    std::vector<uint32_t> perm(m.vertex_count()), where(m.vertex_count());
    std::iota(perm.begin(), perm.end(), 0);
    std::shuffle(perm.begin(), perm.end(), std::mt19937(seed));
    mesh::Mesh s = m;
    for (size_t i = 0; i < perm.size(); ++i) s.positions[i] = m.positions[perm[i]], where[perm[i]] = uint32_t(i);
    for (auto& v : s.indices) v = where[v];
    return s;
}

/// Input position -> output position, vertex by vertex (vertex order kept by the command).
std::map<std::array<float, 3>, mesh::Vec3> moves(const mesh::Mesh& in, const mesh::Mesh& out) {
    REQUIRE(in.vertex_count() == out.vertex_count());
    std::map<std::array<float, 3>, mesh::Vec3> m;
    for (size_t i = 0; i < in.vertex_count(); ++i) m[{in.positions[i].x(), in.positions[i].y(), in.positions[i].z()}] = out.positions[i];
    return m;
}

}  // namespace

TEST_CASE("mesh deform moves each vertex the same in any file order", "[mesh][cli][determinism]") {
    TempDir dir;
    const mesh::Mesh sphere = mesh::icosphere(3);
    mesh::write_mesh(dir / "a.obj", sphere);
    mesh::write_mesh(dir / "b.obj", shuffled(sphere, 7));
    for (const char* n : {"a", "b"})
        REQUIRE(run(dir, "mesh deform " + quote(dir / (std::string(n) + ".obj")) + " --amount 0.1 --scale 0.5 --seed 3 -o " +
                             quote(dir / (std::string(n) + "_out.obj"))).status == 0);
    const auto a = moves(mesh::read_mesh(dir / "a.obj"), mesh::read_mesh(dir / "a_out.obj"));
    const auto b = moves(mesh::read_mesh(dir / "b.obj"), mesh::read_mesh(dir / "b_out.obj"));
    CHECK(a.size() == sphere.vertex_count());
    CHECK(a == b);
}

TEST_CASE("mesh deform frames differ and are deterministic", "[mesh][cli][determinism]") {
    TempDir dir;
    mesh::write_mesh(dir / "s.obj", mesh::icosphere(2));
    const std::string args = "mesh deform " + quote(dir / "s.obj") + " --amount 0.1 --scale 0.5 --frames 3 -o ";
    REQUIRE(run(dir, args + quote(dir / "x_####.obj")).status == 0);
    REQUIRE(run(dir, args + quote(dir / "y_####.obj")).status == 0);
    for (int f = 0; f < 3; ++f) {
        const std::string n = "_000" + std::to_string(f) + ".obj";
        CHECK(read_file(dir / ("x" + n)) == read_file(dir / ("y" + n)));
        CHECK(read_file(dir / ("x" + n)).size() > 1000);
    }
    CHECK(read_file(dir / "x_0000.obj") != read_file(dir / "x_0001.obj"));
    CHECK(read_file(dir / "x_0001.obj") != read_file(dir / "x_0002.obj"));
}

TEST_CASE("mesh texture porous view and trajectories write what assimp reads back", "[mesh][cli]") {
    TempDir dir;
    mesh::write_mesh(dir / "s.obj", mesh::icosphere(3));
    REQUIRE(run(dir, "mesh texture " + quote(dir / "s.obj") + " --transform wood -o " + quote(dir / "w.ply")).status == 0);
    REQUIRE(run(dir, "mesh texture " + quote(dir / "s.obj") + " --transform marble --section z=0 -o " + quote(dir / "m.png")).status == 0);
    REQUIRE(run(dir, "mesh porous --iso 0.5 --size 32 -o " + quote(dir / "p.obj")).status == 0);
    REQUIRE(run(dir, "mesh view " + quote(dir / "w.ply") + " --pixels 64 -o " + quote(dir / "w.png")).status == 0);
    REQUIRE(run(dir, "trajectories --particles 10 --steps 20 -o " + quote(dir / "t.ply")).status == 0);
    const mesh::Mesh w = mesh::read_mesh(dir / "w.ply");
    CHECK(w.colors.size() == w.vertex_count());
    CHECK(mesh::read_mesh(dir / "p.obj").face_count() > 100);
    const mesh::Mesh t = mesh::read_mesh(dir / "t.ply");
    CHECK(t.face_count() == 200u);
    CHECK(std::all_of(t.face_sizes.begin(), t.face_sizes.end(), [](uint32_t n) { return n == 2; }));
    CHECK(output::probe_image(dir / "m.png").width == 512);
    CHECK(output::probe_image(dir / "w.png").width == 64);
}

TEST_CASE("mesh commands refuse bad input with one line and write nothing", "[mesh][cli][errors]") {
    TempDir dir;
    write_file(dir / "bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    write_file(dir / "nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n");
    write_file(dir / "ok.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n");
    const std::string out = " -o " + quote(dir / "out.ply");
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"mesh texture " + quote(dir / "bad.obj") + " --transform wood" + out, "bad.obj:4: v index 9: expected 1..3 or -3..-1 (the v lines above it)"},
        {"mesh deform " + quote(dir / "nan.obj") + " --amount 1 --scale 1" + out, "nan.obj: vertex 2 position (nan, 1, 0): expected finite coordinates"},
        {"mesh porous --iso 40 --size 16" + out, "iso = 40: outside the field's range ["},
        {"mesh porous --iso 0 --size 16" + out, "iso = 0: F is 0 all round the object"},
        {"mesh texture " + quote(dir / "ok.obj") + " --transform wood -o " + quote(dir / "out.stl"), "out.stl: expected an output ending in .obj or .ply"},
        {"trajectories -o " + quote(dir / "paths.xyz"), "paths.xyz: expected an output ending in .obj or .ply"},
        {"mesh texture " + quote(dir / "ok.obj") + " --transform oak" + out, "--transform oak: expected one of wood, marble"},
        {"mesh texture " + quote(dir / "ok.obj") + " --transform wood --section w=1 -o " + quote(dir / "s.png"), "--section w=1: expected x=V"},
        {"mesh deform " + quote(dir / "ok.obj") + " --amount 1 --scale 1 --frames 3" + out, "--frames needs a numbered output"},
        {"mesh deform " + quote(dir / "ok.obj") + " --amount x --scale 1" + out, "--amount x: expected"},
        {"mesh porous --iso 1 --size 4" + out, "--size 4: expected an integer in [8, 1024]"},
        {"mesh texture " + quote(dir / "missing.obj") + " --transform wood" + out, "missing.obj: cannot read mesh"},
    };
    for (const auto& [args, message] : cases) {
        const Result r = run(dir, args);
        INFO(args);
        CHECK(r.status != 0);
        REQUIRE(r.err_lines().size() == 1);
        CHECK_THAT(r.err_lines()[0], Contains(message));
    }
    CHECK(dir.files() == std::vector<std::string>{"bad.obj", "nan.obj", "ok.obj"});
}
