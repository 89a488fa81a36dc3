# SPDX-License-Identifier: Apache-2.0
"""impulse in Blender (docs/blender.md): fill a float Image with frame N of an impulse scene (a
built-in name or a TOML file), rendered by the impulse Python module, optionally following the
timeline (frames rendered on demand and cached); the pixels are the values `impulse render SCENE
--frames N-N -o f.exr` writes, in R, G and B (alpha 1), bit for bit. A volume scene comes in as
a Volume object playing its OpenVDB sequence (grid "density"), written by the impulse tool."""

bl_info = {
    "name": "impulse procedural textures",
    "author": "the impulse authors",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Image Editor > Sidebar > impulse",
    "description": "Animated sparse-convolution noise (Lewis 1986) rendered into an Image",
    "category": "Render",
}

import os
import shutil
import subprocess
import sys
import tempfile
from collections import OrderedDict

import bpy
from bpy.props import BoolProperty, IntProperty, PointerProperty, StringProperty

_CACHED_FRAMES = 16  # frames kept per scene while following the timeline
_cache = {"key": None, "scene": None, "frames": OrderedDict()}


def _impulse():
    """The impulse module: from the add-on's module directory when one is set (build/python, or
    a venv's site-packages after `pip install .`), else from Blender's Python path."""
    prefs = bpy.context.preferences.addons[__name__].preferences
    if prefs.module_dir and prefs.module_dir not in sys.path:
        sys.path.insert(0, bpy.path.abspath(prefs.module_dir))
    import impulse
    return impulse


def _overrides(settings):
    """The settings' overrides, "key=value" separated by semicolons, as a list for --set."""
    return [o.strip() for o in settings.overrides.split(";") if o.strip()]


def _scene(settings):
    """The impulse scene of the settings, loaded once per (source, overrides, size)."""
    size = (settings.width, settings.height) if settings.width > 0 and settings.height > 0 else None
    key = (settings.source, settings.overrides, size)
    if _cache["key"] != key:
        _cache["scene"] = _impulse().load_scene(settings.source, overrides=_overrides(settings), size=size)
        _cache["key"], _cache["frames"] = key, OrderedDict()
    return _cache["scene"]


def _field(scene, frame):
    """Frame `frame` of the scene (float32, H x W, top row first), from the cache if there."""
    frames = _cache["frames"]
    if frame not in frames:
        frames[frame] = scene.render(frame).copy()
        while len(frames) > _CACHED_FRAMES:
            frames.popitem(last=False)
    return frames[frame]


def _image(settings, scene):
    """The settings' Image (a float one of the scene's size is made when none is set)."""
    image = settings.image
    if image is None or tuple(image.size) != (scene.width, scene.height):
        image = bpy.data.images.new(f"impulse {settings.source}", scene.width, scene.height,
                                    alpha=False, float_buffer=True)
        image.colorspace_settings.name = "Non-Color"  # the field's raw values, no view transform
        settings.image = image
    return image


def fill(settings, frame):
    """Renders `frame` into the settings' Image; raises impulse.Error with the CLI's message."""
    import numpy as np

    scene = _scene(settings)
    if not 0 <= frame < scene.frames:
        raise ValueError(f"frame {frame}: outside [0, {scene.frames}) (the scene's output.frames)")
    field = _field(scene, frame)
    rgba = np.ones((scene.height, scene.width, 4), dtype=np.float32)
    rgba[:, :, :3] = field[::-1, :, None]  # Blender stores the bottom row first
    image = _image(settings, scene)
    image.pixels.foreach_set(rgba.ravel())
    image.update()
    return image


def import_volume(settings, first, last):
    """Writes frames first..last of a volume scene as OpenVDB files with the impulse tool (in a
    new temporary directory) and imports them as one Volume object sequence; returns it. Raises
    RuntimeError with the tool's error line."""
    prefs = bpy.context.preferences.addons[__name__].preferences
    folder = tempfile.mkdtemp(prefix="impulse_volume_")
    stem = os.path.splitext(os.path.basename(settings.source))[0]
    pattern = os.path.join(folder, stem + "_####.vdb")
    command = [prefs.tool or "impulse", "render", settings.source, "-o", pattern, "--frames",
               f"{first}-{last}", "-q"]
    for o in _overrides(settings):
        command += ["--set", o]
    run = subprocess.run(command, capture_output=True, text=True)
    if run.returncode != 0:
        shutil.rmtree(folder, ignore_errors=True)  # nothing written
        lines = run.stderr.strip().splitlines()
        raise RuntimeError(lines[-1] if lines else f"impulse exited with status {run.returncode}")
    files = sorted(f for f in os.listdir(folder) if f.endswith(".vdb"))
    bpy.ops.object.volume_import(filepath=os.path.join(folder, files[0]), directory=folder,
                                 files=[{"name": f} for f in files])
    volume = bpy.context.active_object
    volume.data.frame_start = first  # impulse frame f at Blender frame f, as Fill Image does
    return volume


def _write_ply(mesh, path):
    """The mesh's vertices (in Blender's order) and polygons as ASCII PLY."""
    lines = ["ply", "format ascii 1.0", f"element vertex {len(mesh.vertices)}", "property float x",
             "property float y", "property float z", f"element face {len(mesh.polygons)}",
             "property list uchar int vertex_indices", "end_header"]
    lines += ["%.9g %.9g %.9g" % tuple(v.co) for v in mesh.vertices]
    lines += [" ".join([str(len(p.vertices))] + [str(i) for i in p.vertices]) for p in mesh.polygons]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def ply_colours(path):
    """The 8-bit red, green, blue of an ASCII PLY's vertices, in their order, as [0, 1] floats."""
    with open(path) as f:
        text = f.read().split("\n")
    props, count, at, in_vertex = [], 0, 0, False
    while text[at] != "end_header":
        words = text[at].split()
        if words[:2] == ["element", "vertex"]:
            count, in_vertex = int(words[2]), True
        elif words[:1] == ["element"]:
            in_vertex = False
        elif words[:1] == ["property"] and in_vertex:
            props.append(words[-1])
        at += 1
    rgb = [props.index(c) for c in ("red", "green", "blue")]
    rows = (text[at + 1 + i].split() for i in range(count))
    return [[int(row[k]) / 255.0 for k in rgb] for row in rows]


def _linear(c):
    """sRGB-encoded display value to linear (Blender's colour attributes hold linear colour)."""
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def texture_mesh(obj, transform, seed):
    """Colours every vertex of the mesh object with `impulse mesh texture` (solid wood or marble,
    docs/mesh.md) into the colour attribute "impulse": the tool writes vertex i of its input as
    vertex i, so the colours line up with Blender's vertices. Raises RuntimeError with the
    tool's error line."""
    prefs = bpy.context.preferences.addons[__name__].preferences
    with tempfile.TemporaryDirectory(prefix="impulse_mesh_") as folder:
        source, textured = os.path.join(folder, "in.ply"), os.path.join(folder, "out.ply")
        _write_ply(obj.data, source)
        run = subprocess.run([prefs.tool or "impulse", "mesh", "texture", source, "--transform",
                              transform, "--seed", str(seed), "-o", textured],
                             capture_output=True, text=True)
        if run.returncode != 0:
            lines = run.stderr.strip().splitlines()
            raise RuntimeError(lines[-1] if lines else f"impulse exited with status {run.returncode}")
        colours = ply_colours(textured)
    mesh = obj.data
    if len(colours) != len(mesh.vertices):
        raise RuntimeError(f"impulse mesh texture wrote {len(colours)} vertices for {len(mesh.vertices)}")
    attribute = mesh.color_attributes.get("impulse") or mesh.color_attributes.new("impulse", "FLOAT_COLOR", "POINT")
    flat = []
    for c in colours:
        flat += [_linear(c[0]), _linear(c[1]), _linear(c[2]), 1.0]
    attribute.data.foreach_set("color", flat)
    mesh.color_attributes.active_color = attribute
    return attribute


class ImpulseSettings(bpy.types.PropertyGroup):
    source: StringProperty(name="Scene", default="drift",
                           description="A built-in scene (drift, clouds, marble ...) or a TOML file")
    overrides: StringProperty(name="Overrides", default="",
                              description="key=value; key=value: scene keys set as --set does")
    width: IntProperty(name="Width", default=0, min=0, max=32768,
                       description="Pixels across (0: the scene's own size); the same view, as --size")
    height: IntProperty(name="Height", default=0, min=0, max=32768)
    image: PointerProperty(name="Image", type=bpy.types.Image)
    follow: BoolProperty(name="Follow the timeline", default=False,
                         description="Fill the Image with the current frame whenever it changes")


class IMPULSE_OT_fill_image(bpy.types.Operator):
    """Render a frame of the impulse scene into the Image"""

    bl_idname = "impulse.fill_image"
    bl_label = "Fill Image"
    frame: IntProperty(name="Frame", default=-1, description="The frame (-1: the current frame)")

    def execute(self, context):
        frame = self.frame if self.frame >= 0 else context.scene.frame_current
        try:
            image = fill(context.scene.impulse, frame)
        except Exception as e:  # impulse.Error carries the CLI's one line
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, f"{image.name}: frame {frame}")
        return {"FINISHED"}


class IMPULSE_OT_import_volume(bpy.types.Operator):
    """Render frames of a volume scene to OpenVDB with the impulse tool and import them as a Volume object"""

    bl_idname = "impulse.import_volume"
    bl_label = "Import Volume"
    first: IntProperty(name="First frame", default=0, min=0)
    last: IntProperty(name="Last frame", default=0, min=0)

    def execute(self, context):
        if self.last < self.first:
            self.report({"ERROR"}, f"frames {self.first}-{self.last}: expected first <= last")
            return {"CANCELLED"}
        try:
            volume = import_volume(context.scene.impulse, self.first, self.last)
        except Exception as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, f"{volume.name}: frames {self.first}-{self.last}")
        return {"FINISHED"}


class IMPULSE_OT_texture_mesh(bpy.types.Operator):
    """Colour the active mesh's vertices with solid wood or marble (impulse mesh texture)"""

    bl_idname = "impulse.texture_mesh"
    bl_label = "Texture Mesh"
    transform: bpy.props.EnumProperty(name="Transform", items=[("wood", "Wood", ""), ("marble", "Marble", "")])
    seed: IntProperty(name="Seed", default=0, min=0)

    def execute(self, context):
        obj = context.active_object
        if obj is None or obj.type != "MESH":
            self.report({"ERROR"}, "Texture Mesh: the active object is not a mesh")
            return {"CANCELLED"}
        try:
            texture_mesh(obj, self.transform, self.seed)
        except Exception as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, f"{obj.name}: colour attribute \"impulse\" ({self.transform})")
        return {"FINISHED"}


class IMPULSE_PT_panel(bpy.types.Panel):
    bl_label = "impulse"
    bl_space_type = "IMAGE_EDITOR"
    bl_region_type = "UI"
    bl_category = "impulse"

    def draw(self, context):
        settings = context.scene.impulse
        layout = self.layout
        layout.prop(settings, "source")
        layout.prop(settings, "overrides")
        row = layout.row()
        row.prop(settings, "width")
        row.prop(settings, "height")
        layout.prop(settings, "image")
        layout.prop(settings, "follow")
        layout.operator(IMPULSE_OT_fill_image.bl_idname)
        layout.operator(IMPULSE_OT_import_volume.bl_idname)
        layout.operator(IMPULSE_OT_texture_mesh.bl_idname)


class ImpulsePreferences(bpy.types.AddonPreferences):
    bl_idname = __name__
    module_dir: StringProperty(name="impulse module directory", subtype="DIR_PATH",
                               description="Where `import impulse` is found: build/python, or a "
                                           "venv's site-packages (empty: Blender's Python path)")
    tool: StringProperty(name="impulse tool", subtype="FILE_PATH", default="impulse",
                         description="The impulse command (Import Volume runs it)")

    def draw(self, context):
        self.layout.prop(self, "module_dir")
        self.layout.prop(self, "tool")


@bpy.app.handlers.persistent
def _follow_timeline(scene, depsgraph=None):
    settings = scene.impulse
    if settings.follow:
        try:
            fill(settings, scene.frame_current)
        except Exception as e:
            print(f"impulse: {e}")


_classes = (ImpulseSettings, IMPULSE_OT_fill_image, IMPULSE_OT_import_volume, IMPULSE_OT_texture_mesh,
            IMPULSE_PT_panel, ImpulsePreferences)


def register():
    for c in _classes:
        bpy.utils.register_class(c)
    bpy.types.Scene.impulse = PointerProperty(type=ImpulseSettings)
    bpy.app.handlers.frame_change_post.append(_follow_timeline)


def unregister():
    bpy.app.handlers.frame_change_post.remove(_follow_timeline)
    del bpy.types.Scene.impulse
    for c in reversed(_classes):
        bpy.utils.unregister_class(c)
