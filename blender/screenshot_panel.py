# SPDX-License-Identifier: Apache-2.0
# Run by blender/screenshot_panel.sh in Blender with a window (under xvfb-run):
#   blender --factory-startup --enable-event-simulate --python screenshot_panel.py -- ZIP MODULE_DIR CLI OUT.png
# Fills an Image with drift's frame 12, shows it in an Image Editor with the sidebar on the
# impulse tab, saves that area as OUT.png and quits.
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from install_addon import install  # noqa: E402

zip_path, module_dir, cli, out = sys.argv[sys.argv.index("--") + 1:]
state = {"step": 0, "tries": 0}


def setup():
    settings = install(zip_path, module_dir, cli)
    settings.source, settings.width, settings.height = "drift", 384, 216
    settings.expose = "layer.0.gain, layer.0.kernel.sigma=60:200"
    settings.follow = True
    bpy.context.scene.frame_set(12)
    bpy.ops.impulse.set_key(key="layer.0.kernel.sigma", value=150)
    bpy.ops.impulse.set_key(key="layer.0.gain", value=1.3)
    window = bpy.context.window_manager.windows[0]
    # One big area: the 3-D viewport becomes the Image Editor (the other areas stay as they are).
    area = max(window.screen.areas, key=lambda a: a.width * a.height)
    area.type = "IMAGE_EDITOR"
    space = area.spaces.active
    space.image = settings.image
    space.show_region_ui = True
    space.show_region_toolbar = False
    return window, area


def panel_drawn():
    return state.get("drawn", False)


_draw = None


def tick():
    """Steps on a timer, so the window has drawn in between."""
    global _draw
    if state["step"] == 0:
        state["window"], state["area"] = setup()
        panel = bpy.types.IMPULSE_PT_panel
        _draw = panel.draw

        def draw(self, context):
            state["drawn"] = True
            _draw(self, context)

        panel.draw = draw
        state["step"] = 1
        return 1.0
    window, area = state["window"], state["area"]
    if state["step"] == 1:
        image_region = next(r for r in area.regions if r.type == "WINDOW")
        with bpy.context.temp_override(window=window, area=area, region=image_region):
            bpy.ops.image.view_all(fit_view=True)
        state["step"] = 2
        return 0.5
    if state["step"] == 2:
        if not panel_drawn() and state["tries"] < 12:
            # The wheel over the sidebar's tabs steps through them until the impulse panel draws.
            sidebar = next(r for r in area.regions if r.type == "UI")
            y = sidebar.y + sidebar.height // 2
            x = sidebar.x + sidebar.width - 8  # over the tabs' column: the wheel steps them
            window.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)
            window.event_simulate(type="WHEELDOWNMOUSE", value="PRESS", x=x, y=y)
            state["tries"] += 1
            return 0.5
        state["step"] = 3
        return 1.0
    if not panel_drawn():
        print("screenshot: the impulse tab did not come up; nothing written")
    else:
        with bpy.context.temp_override(window=window, area=area):
            bpy.ops.screen.screenshot_area(filepath=out)
        print(f"screenshot: {out} ({state['tries']} tab steps)")
    bpy.ops.wm.quit_blender()
    return None


def guarded():
    """tick, quitting Blender on an error (a window would otherwise stay open)."""
    try:
        return tick()
    except Exception:
        import traceback

        traceback.print_exc()
        bpy.ops.wm.quit_blender()
        return None


bpy.context.preferences.view.show_splash = False  # read before the splash would open
bpy.app.timers.register(guarded, first_interval=2.0)
