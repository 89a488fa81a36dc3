# SPDX-License-Identifier: Apache-2.0
# Run by blender/test_blender_addon.sh inside headless Blender:
#   blender -b --factory-startup --python-exit-code 1 --python test_addon.py -- ZIP MODULE_DIR EXR_FITS CONFTEST_DIR CLI
# Installs the add-on from its zip, fills an Image with drift's frame 12 at 192x108 and compares
# its pixels with the CLI's EXR (as FITS, float32) bit for bit; a scene that does not load is
# the operator's error report (one line) and no Image; a small cloudvolume comes in as a Volume
# object sequence with its "density" grid; vertices coloured by `impulse mesh texture`; sliders
# of exposed keys render the CLI's `--set` frame and refuse a value outside their range; a baked
# EXR sequence holds the CLI's pixels and Blender frame f reads file f; a deformed mesh keeps its
# vertices in order (the tool's positions); a porous object has faces.
import os
import sys

import bpy
import numpy as np

zip_path, module_dir, fits, conftest_dir, cli = sys.argv[sys.argv.index("--") + 1:]
sys.path[:0] = [conftest_dir, os.path.dirname(os.path.abspath(__file__))]
from conftest import read_fits  # noqa: E402
from install_addon import install  # noqa: E402

settings = install(zip_path, module_dir, cli)
settings.source, settings.width, settings.height = "drift", 192, 108
assert bpy.ops.impulse.fill_image(frame=12) == {"FINISHED"}
image = settings.image
assert tuple(image.size) == (192, 108) and image.is_float, (tuple(image.size), image.is_float)
pixels = np.empty(len(image.pixels), dtype=np.float32)
image.pixels.foreach_get(pixels)
rgba = pixels.reshape(108, 192, 4)[::-1]  # Blender's rows run bottom-up
reference = read_fits(fits)
for c in range(3):
    assert np.array_equal(rgba[:, :, c].view(np.uint32), reference.view(np.uint32)), f"channel {c} differs"
assert np.all(rgba[:, :, 3] == 1.0)
print("impulse add-on: drift frame 12 in the Image equals the CLI's EXR bit for bit")

images = len(bpy.data.images)
settings.source, settings.image = "drfit", None
try:
    bpy.ops.impulse.fill_image(frame=12)
    raise AssertionError("a scene that does not exist was accepted")
except RuntimeError as e:  # the operator's ERROR report, as Blender raises it in the background
    message = str(e).strip()
    assert 'drfit: no such scene file or built-in scene (did you mean "drift"?)' in message, message
    assert len(message.splitlines()) == 1, message
assert len(bpy.data.images) == images and settings.image is None
print("impulse add-on: a bad scene is one error report, no Image")

settings.source = "cloudvolume"
settings.overrides = "volume.size=[40,24,20]; volume.octaves=2; volume.kernel.radius=8"
assert bpy.ops.impulse.import_volume(first=2, last=4) == {"FINISHED"}
volume = bpy.context.active_object
assert volume.type == "VOLUME", volume.type
assert volume.data.is_sequence and volume.data.frame_duration == 3, (volume.data.is_sequence, volume.data.frame_duration)
bpy.context.scene.frame_set(volume.data.frame_start + 1)  # the sequence's second frame, file 3
volume.data.grids.load()
names = [g.name for g in volume.data.grids]
assert "density" in names, (names, volume.data.grids.error_message, volume.data.filepath)
print(f"impulse add-on: cloudvolume frames 2-4 as a Volume sequence with grids {names}")
settings.overrides = "volume.size=[40,24]"
objects = len(bpy.data.objects)
try:
    bpy.ops.impulse.import_volume(first=0, last=0)
    raise AssertionError("a bad override was accepted")
except RuntimeError as e:
    message = str(e).strip()
    assert "volume.size" in message and len(message.splitlines()) == 1, message
assert len(bpy.data.objects) == objects
print("impulse add-on: a bad volume key is one error report, no object")

# A UV sphere's vertices coloured by `impulse mesh texture`: attribute colour i is the colour the
# tool gives vertex i of the same vertex list (written here as OBJ, in Blender's order).
import subprocess  # noqa: E402
import tempfile  # noqa: E402

bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24)
sphere = bpy.context.active_object
assert bpy.ops.impulse.texture_mesh(transform="wood", seed=3) == {"FINISHED"}
attribute = sphere.data.color_attributes["impulse"]
got = np.empty(len(sphere.data.vertices) * 4, dtype=np.float32)
attribute.data.foreach_get("color", got)
got = got.reshape(-1, 4)[:, :3]
with tempfile.TemporaryDirectory() as folder:
    obj = os.path.join(folder, "s.obj")
    with open(obj, "w") as f:
        f.writelines("v %.9g %.9g %.9g\n" % tuple(v.co) for v in sphere.data.vertices)
        f.writelines("f " + " ".join(str(i + 1) for i in p.vertices) + "\n" for p in sphere.data.polygons)
    subprocess.run([cli, "mesh", "texture", obj, "--transform", "wood", "--seed", "3", "-o",
                    os.path.join(folder, "s.ply")], check=True, capture_output=True)
    addon = sys.modules["impulse_addon"]
    expected = np.array([[addon._linear(c) for c in rgb] for rgb in addon.ply_colours(os.path.join(folder, "s.ply"))])
assert got.shape == expected.shape, (got.shape, expected.shape)
assert np.abs(got - expected).max() < 1e-6, np.abs(got - expected).max()
assert np.ptp(expected[:, 0]) > 0.1  # the rings vary: a permutation would not match
print(f"impulse add-on: {len(got)} sphere vertices carry the tool's wood colours, vertex for vertex")

# --- Sliders (the keys `impulse preview --expose` exposes, read through the module) ----------
addon = sys.modules["impulse_addon"]


def cli_frame(args, frame):
    """Frame `frame` of `impulse render ARGS` as float32 H x W, top row first (EXR -> FITS)."""
    with tempfile.TemporaryDirectory() as folder:
        exr, fits_path = os.path.join(folder, "f.exr"), os.path.join(folder, "f.fits")
        subprocess.run([cli, "render", *args, "--frames", f"{frame}-{frame}", "-o", exr, "-q"], check=True)
        return exr_field(exr, fits_path)


def exr_field(exr, fits_path):
    subprocess.run(["oiiotool", exr, "-d", "float", "-o", fits_path], check=True)
    return read_fits(fits_path)


def image_red(image):
    """An Image's red channel as float32 H x W, top row first."""
    w, h = image.size
    p = np.empty(w * h * 4, dtype=np.float32)
    image.pixels.foreach_get(p)
    return p.reshape(h, w, 4)[::-1, :, 0].copy()


def bits_equal(a, b):
    return a.shape == b.shape and np.array_equal(a.view(np.uint32), b.view(np.uint32))


def one_error(call, *needles):
    """The operator call fails with one report line holding every needle; returns it."""
    try:
        call()
    except RuntimeError as e:
        message = str(e).strip()
        assert len(message.splitlines()) == 1 and all(n in message for n in needles), message
        return message
    raise AssertionError(f"accepted: expected an error with {needles}")


scene = bpy.context.scene
settings.source, settings.overrides, settings.image, settings.width, settings.height = "drift", "", None, 192, 108
settings.expose = "layer.0.gain, layer.0.kernel.sigma=60:200, layer.0.kernel.radius"
keys = {k.key: k for k in settings.keys}
assert list(keys) == ["layer.0.gain", "layer.0.kernel.sigma", "layer.0.kernel.radius"], (list(keys), settings.keys_error)
gain, sigma = keys["layer.0.gain"], keys["layer.0.kernel.sigma"]
# The preview's ranges: 0 to twice the file's value (gain = 1.0), or the range given.
# sigma is written as an integer: its slider moves in whole steps.
assert (gain.value, gain.lo, gain.hi, gain.integer) == (1, 0, 2, False)
assert (sigma.value, sigma.lo, sigma.hi, sigma.integer) == (120, 60, 200, True)
settings.follow = True
scene.frame_set(12)  # follows: fills the Image with frame 12
assert bpy.ops.impulse.set_key(key="layer.0.kernel.sigma", value=150) == {"FINISHED"}
assert bpy.ops.impulse.set_key(key="layer.0.gain", value=1.3) == {"FINISHED"}
field = image_red(settings.image)
SLIDERS = ["--set", "layer.0.kernel.sigma=150", "--set", "layer.0.gain=1.3"]
expected = cli_frame(["drift", "--size", "192x108", *SLIDERS], 12)
assert bits_equal(field, expected), "the sliders' frame differs from the CLI's with --set"
assert not bits_equal(field, reference)  # the overrides took effect
print("impulse add-on: sliders sigma = 150, gain = 1.3 render the CLI's --set frame bit for bit")

# Out of range, through the operator and typed into the slider: one report, nothing changes.
one_error(lambda: bpy.ops.impulse.set_key(key="layer.0.gain", value=5), "layer.0.gain = 5", "[0, 2]")
one_error(lambda: bpy.ops.impulse.set_key(key="layer.0.kernel.sigma", value=250), "layer.0.kernel.sigma = 250", "[60, 200]")
one_error(lambda: bpy.ops.impulse.set_key(key="layer.0.kernel.sigma", value=99.5), "sigma = 99.5", "whole number")
gain.value = -3  # as typed in the panel: the update calls the operator, which refuses it
sigma.whole = 500  # an integer key's field
assert abs(gain.value - 1.3) < 1e-6 and (sigma.value, sigma.whole) == (150, 150), (gain.value, sigma.value, sigma.whole)
assert bits_equal(image_red(settings.image), field), "a refused value changed the Image"
one_error(lambda: bpy.ops.impulse.set_key(key="layer.0.density", value=5), 'unknown key "layer.0.density"')
# In range, but a value the scene refuses: the loader's line, and the slider goes back.
one_error(lambda: bpy.ops.impulse.set_key(key="layer.0.kernel.radius", value=0), "kernel.radius = 0", "expected a radius > 0")
radius = keys["layer.0.kernel.radius"]
assert abs(radius.value - 446.031) < 1e-3 and not radius.moved, (radius.value, radius.moved)
assert bits_equal(image_red(settings.image), field), "a refused value changed the Image"
settings.follow = False
print("impulse add-on: a value outside a slider's range is one error report; slider and Image unchanged")

# --- Bake frames 3-5 to EXR; an Image Texture node that showed the Image shows the sequence ---
material = bpy.data.materials.new("impulse baked")
material.use_nodes = True
node = material.node_tree.nodes.new("ShaderNodeTexImage")
node.image = settings.image
bpy.ops.mesh.primitive_plane_add()
bpy.context.active_object.data.materials.append(material)  # a material in use: evaluated per frame
bake_dir = tempfile.mkdtemp()
assert bpy.ops.impulse.bake_sequence(first=3, last=5, directory=bake_dir) == {"FINISHED"}
baked = settings.baked
assert baked.source == "SEQUENCE" and node.image == baked, (baked.source, node.image)
names = [f"drift_{f:04d}.exr" for f in (3, 4, 5)]
assert sorted(os.listdir(bake_dir)) == names, os.listdir(bake_dir)  # no staging folder left
with tempfile.TemporaryDirectory() as folder:  # the CLI's frames, with the sliders' --set
    subprocess.run([cli, "render", "drift", "--size", "192x108", *SLIDERS, "--frames", "3-5", "-o",
                    os.path.join(folder, "drift_####.exr"), "-q"], check=True)
    for name in names:  # pixels as Blender reads them (the headers name their commands)
        ours, theirs = (bpy.data.images.load(os.path.join(d, name), check_existing=False) for d in (bake_dir, folder))
        assert bits_equal(image_red(ours), image_red(theirs)), f"{name} differs from the CLI's"
        assert not bits_equal(image_red(ours), field)  # not frame 12
        bpy.data.images.remove(ours), bpy.data.images.remove(theirs)
for f in (3, 4, 5):
    scene.frame_set(f)
    # The file Blender reads at frame f: the node's image user as the depsgraph evaluates it
    # for the render (the original's frame is not advanced outside a window).
    user = material.evaluated_get(bpy.context.evaluated_depsgraph_get()).node_tree.nodes[node.name].image_user
    read = baked.filepath_from_user(image_user=user)
    assert os.path.basename(read) == f"drift_{f:04d}.exr", (f, read, user.frame_current)

# The final render reads the files: Cycles renders the plane, lit only by the texture through an
# Emission shader (nearest texel, a box filter narrower than a pixel, an orthographic camera
# with a pixel a texel), and frame f of the render is file f's pixels bit for bit.
tree = material.node_tree
emission, output = tree.nodes.new("ShaderNodeEmission"), tree.nodes["Material Output"]
tree.links.new(node.outputs["Color"], emission.inputs["Color"])
tree.links.new(emission.outputs["Emission"], output.inputs["Surface"])
node.interpolation = "Closest"
plane = bpy.context.active_object
plane.scale = (192 / 108, 1, 1)
camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
camera.data.type, camera.data.ortho_scale, camera.location = "ORTHO", 2 * 192 / 108, (0, 0, 5)
scene.collection.objects.link(camera)
scene.camera = camera
for other in scene.objects:
    other.hide_render = other not in (plane, camera)  # the start-up cube, the sphere, the volume
scene.render.engine, scene.cycles.samples, scene.cycles.use_denoising = "CYCLES", 1, False
scene.cycles.pixel_filter_type, scene.cycles.filter_width = "BOX", 0.01
scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 192, 108, 100
scene.render.image_settings.file_format, scene.render.image_settings.color_depth = "OPEN_EXR", "32"
for f in (3, 4, 5):
    scene.frame_set(f)
    scene.render.filepath = os.path.join(bake_dir, "..", f"render_{os.getpid()}_{f}.exr")
    bpy.ops.render.render(write_still=True)
    rendered = bpy.data.images.load(scene.render.filepath, check_existing=False)
    file = bpy.data.images.load(os.path.join(bake_dir, f"drift_{f:04d}.exr"), check_existing=False)
    assert bits_equal(image_red(rendered), image_red(file)), (f, np.abs(image_red(rendered) - image_red(file)).max())
    bpy.data.images.remove(rendered), bpy.data.images.remove(file)
    os.remove(scene.render.filepath)
print("impulse add-on: bake 3-5 writes the CLI's EXR pixels bit for bit; at Blender frame f the node "
      "reads file f, and Cycles renders file f's pixels")

images = len(bpy.data.images)
settings.overrides = "layer.0.kernel.radius=-4"
bad_dir = tempfile.mkdtemp()
one_error(lambda: bpy.ops.impulse.bake_sequence(first=0, last=2, directory=bad_dir), "layer[0].kernel.radius = -4")
assert os.listdir(bad_dir) == [] and len(bpy.data.images) == images and settings.baked == baked
settings.overrides = ""
print("impulse add-on: a bad key in a bake is one error report, no file, no Image")

# --- Deform: the new object's vertex i is the tool's vertex i; the tool keeps the order -------
bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, radius=1.0)
ball = bpy.context.active_object
assert bpy.ops.impulse.deform_mesh(amount=0.2, scale=0.6, seed=4) == {"FINISHED"}
deformed = bpy.data.objects[f"{ball.name} deformed"]
got = np.array([tuple(v.co) for v in deformed.data.vertices])
before = np.array([tuple(v.co) for v in ball.data.vertices])


def cli_deform(points, faces, folder, name, frames=0):
    """The tool's deformed positions (N x 3; with frames, a list of them) of the vertex list."""
    path = os.path.join(folder, name + ".obj")
    with open(path, "w") as f:
        f.writelines("v %.9g %.9g %.9g\n" % tuple(p) for p in points)
        f.writelines("f " + " ".join(str(i + 1) for i in face) + "\n" for face in faces)
    out = os.path.join(folder, name + ("_####.ply" if frames else ".ply"))
    subprocess.run([cli, "mesh", "deform", path, "--amount", "0.2", "--scale", "0.6", "--seed", "4",
                    "-o", out] + (["--frames", str(frames)] if frames else []), check=True, capture_output=True)
    read = lambda ply: np.array(addon.ply_vertex_columns(ply, ("x", "y", "z")))  # noqa: E731
    return [read(out.replace("####", "%04d" % f)) for f in range(frames)] if frames else read(out)


faces = [list(p.vertices) for p in ball.data.polygons]
n = len(before)
reverse = np.arange(n)[::-1]  # vertex i of the reversed list is vertex n-1-i
with tempfile.TemporaryDirectory() as folder:
    tool = cli_deform(before, faces, folder, "ball")
    tool_reversed = cli_deform(before[reverse], [[n - 1 - i for i in f] for f in faces], folder, "reversed")
assert got.shape == tool.shape == before.shape, (got.shape, tool.shape, before.shape)
assert np.abs(got - tool).max() < 1e-6, np.abs(got - tool).max()
# The tool keeps its input's order: deforming the vertices listed backwards gives the same
# positions listed backwards (the displacement depends on the position only, docs/mesh.md).
assert np.abs(tool_reversed[reverse] - tool).max() < 1e-6, np.abs(tool_reversed[reverse] - tool).max()
moved = np.linalg.norm(got - before, axis=1)
assert moved.min() > 0 and moved.max() > 0.05, (moved.min(), moved.max())  # it did move
print(f"impulse add-on: a {n}-vertex sphere deformed keeps count and order (max |Blender - tool| "
      f"{np.abs(got - tool).max():.1e}, displacement up to {moved.max():.3f})")

# Frames through 4-D noise as shape keys: at Blender frame f the evaluated mesh is the tool's
# frame f, vertex for vertex.
bpy.context.view_layer.objects.active = ball
assert bpy.ops.impulse.deform_mesh(amount=0.2, scale=0.6, seed=4, frames=3) == {"FINISHED"}
moving = bpy.context.active_object
assert [k.name for k in moving.data.shape_keys.key_blocks] == ["frame 0", "frame 1", "frame 2"]
with tempfile.TemporaryDirectory() as folder:
    tool_frames = cli_deform(before, faces, folder, "moving", frames=3)
for f in (2, 0, 1):
    scene.frame_set(f)
    evaluated = moving.evaluated_get(bpy.context.evaluated_depsgraph_get())
    shape = np.array([tuple(v.co) for v in evaluated.to_mesh().vertices])
    evaluated.to_mesh_clear()
    assert np.abs(shape - tool_frames[f]).max() < 1e-6, (f, np.abs(shape - tool_frames[f]).max())
assert np.abs(tool_frames[2] - tool_frames[0]).max() > 0.01  # the frames differ
print("impulse add-on: deform --frames 3 as shape keys: Blender frame f is the tool's frame f")

# --- A porous object comes in with faces; a bad iso is one report and no object ---------------
assert bpy.ops.impulse.porous_object(iso=0.5, size=32, seed=2) == {"FINISHED"}
porous = bpy.context.active_object
assert porous.type == "MESH" and len(porous.data.polygons) > 0, len(porous.data.polygons)
objects = len(bpy.data.objects)
one_error(lambda: bpy.ops.impulse.porous_object(iso=40, size=16), "iso")
assert len(bpy.data.objects) == objects
print(f"impulse add-on: porous object with {len(porous.data.polygons)} faces; a bad iso is one report, no object")
