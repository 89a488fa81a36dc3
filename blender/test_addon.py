# SPDX-License-Identifier: Apache-2.0
# Run by blender/test_blender_addon.sh inside headless Blender:
#   blender -b --factory-startup --python-exit-code 1 --python test_addon.py -- ZIP MODULE_DIR EXR_FITS CONFTEST_DIR CLI
# Installs the add-on from its zip, fills an Image with drift's frame 12 at 192x108 and compares
# its pixels with the CLI's EXR (as FITS, float32) bit for bit; a scene that does not load is
# the operator's error report (one line) and no Image; a small cloudvolume comes in as a Volume
# object sequence with its "density" grid.
import sys

import bpy
import numpy as np

zip_path, module_dir, fits, conftest_dir, cli = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, conftest_dir)
from conftest import read_fits  # noqa: E402

bpy.ops.preferences.addon_install(filepath=zip_path)
bpy.ops.preferences.addon_enable(module="impulse_addon")
prefs = bpy.context.preferences.addons["impulse_addon"].preferences
prefs.module_dir, prefs.tool = module_dir, cli

settings = bpy.context.scene.impulse
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
import os  # noqa: E402
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
