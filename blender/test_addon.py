# SPDX-License-Identifier: Apache-2.0
# Run by blender/test_blender_addon.sh inside headless Blender:
#   blender -b --factory-startup --python-exit-code 1 --python test_addon.py -- ZIP MODULE_DIR EXR_FITS CONFTEST_DIR
# Installs the add-on from its zip, fills an Image with drift's frame 12 at 192x108 and compares
# its pixels with the CLI's EXR (as FITS, float32) bit for bit; a scene that does not load is
# the operator's error report (one line) and no Image.
import sys

import bpy
import numpy as np

zip_path, module_dir, fits, conftest_dir = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, conftest_dir)
from conftest import read_fits  # noqa: E402

bpy.ops.preferences.addon_install(filepath=zip_path)
bpy.ops.preferences.addon_enable(module="impulse_addon")
bpy.context.preferences.addons["impulse_addon"].preferences.module_dir = module_dir

settings = bpy.context.scene.impulse
settings.source, settings.width, settings.height = "drift", 192, 108
assert bpy.ops.impulse.fill_image(frame=12) == {"FINISHED"}
image = settings.image
assert tuple(image.size) == (192, 108) and image.is_float, (tuple(image.size), image.is_float)
pixels = np.empty(len(image.pixels), dtype=np.float32)
image.pixels.foreach_get(pixels)
rgba = pixels.reshape(108, 192, 4)[::-1]  # Blender's rows run bottom-up
cli = read_fits(fits)
for c in range(3):
    assert np.array_equal(rgba[:, :, c].view(np.uint32), cli.view(np.uint32)), f"channel {c} differs"
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
