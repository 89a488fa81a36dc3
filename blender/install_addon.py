# SPDX-License-Identifier: Apache-2.0
# For the scripts Blender runs here (blender/test_addon.py, blender/screenshot_panel.py): the
# add-on installed from its zip (scripts/blender_addon.sh) into the user configuration Blender
# was started with, enabled, and pointed at the impulse module and tool.
import bpy


def install(zip_path, module_dir, cli):
    """Installs and enables the add-on; returns the Blender scene's impulse settings."""
    bpy.ops.preferences.addon_install(filepath=zip_path)
    bpy.ops.preferences.addon_enable(module="impulse_addon")
    prefs = bpy.context.preferences.addons["impulse_addon"].preferences
    prefs.module_dir, prefs.tool = module_dir, cli
    return bpy.context.scene.impulse
