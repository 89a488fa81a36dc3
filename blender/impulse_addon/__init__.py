# SPDX-License-Identifier: Apache-2.0
"""impulse in Blender (docs/blender.md): fill a float Image with frame N of an impulse scene (a
built-in name or a TOML file), rendered by the impulse Python module, optionally following the
timeline (frames rendered on demand and cached); the pixels are the values `impulse render SCENE
--frames N-N -o f.exr` writes, in R, G and B (alpha 1), bit for bit. Keys of the scene get
sliders as `impulse preview --expose` gives them; frames A..B bake to an EXR sequence for the
final render. A volume scene comes in as a Volume object playing its OpenVDB sequence (grid
"density"), porous and deformed meshes as mesh objects, written by the impulse tool."""

bl_info = {
    "name": "impulse procedural textures",
    "author": "the impulse authors",
    "version": (0, 2, 0),
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
from bpy.props import (BoolProperty, CollectionProperty, EnumProperty, FloatProperty, IntProperty,
                       PointerProperty, StringProperty)

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


def _number(value):
    """A Blender float property's value as the text a user typed: the shortest decimal that reads
    back as its single-precision value (Blender's float properties are 32-bit; "0.7" rather than
    0.699999988...), so the tool gets what `--amount 0.7` or `--set key=0.7` would give it."""
    import numpy as np

    return str(np.float32(value))


def _key_text(item):
    """A slider's value as TOML text for --set: a whole number for an integer key, else _number."""
    return str(item.whole) if item.integer else _number(item.value)


def _overrides(settings):
    """The settings' overrides as a list for --set: the Overrides text ("key=value" separated by
    semicolons), then the sliders moved since the keys were read (as the preview applies them:
    after the others, so a slider wins)."""
    sets = [o.strip() for o in settings.overrides.split(";") if o.strip()]
    return sets + [f"{item.key}={_key_text(item)}" for item in settings.keys if item.moved]


def _size(settings):
    """(width, height) when the settings give another size (render --size), else None."""
    return (settings.width, settings.height) if settings.width > 0 and settings.height > 0 else None


def _scene(settings):
    """The impulse scene of the settings, loaded once per (source, overrides, size)."""
    size = _size(settings)
    key = (settings.source, tuple(_overrides(settings)), size)
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


def _run_tool(arguments):
    """Runs the impulse tool (the add-on preference) with `arguments`; raises RuntimeError with
    its one-line error when it fails."""
    prefs = bpy.context.preferences.addons[__name__].preferences
    run = subprocess.run([prefs.tool or "impulse"] + arguments, capture_output=True, text=True)
    if run.returncode != 0:
        lines = run.stderr.strip().splitlines()
        raise RuntimeError(lines[-1] if lines else f"impulse exited with status {run.returncode}")


def _render_frames(settings, first, last, folder, extension, sized=True):
    """`impulse render SOURCE --frames first-last -o folder/STEM_####.extension` with the settings'
    overrides (and size, when `sized`: an image scene's), so the files are the CLI's; returns
    their names in frame order. A failure removes the folder (nothing half-written is left) and
    raises RuntimeError."""
    stem = os.path.splitext(os.path.basename(settings.source))[0]
    command = ["render", settings.source, "-o", os.path.join(folder, f"{stem}_####.{extension}"),
               "--frames", f"{first}-{last}", "-q"]
    if sized and _size(settings):
        command += ["--size", "%dx%d" % _size(settings)]
    for o in _overrides(settings):
        command += ["--set", o]
    try:
        _run_tool(command)
    except RuntimeError:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    return sorted(f for f in os.listdir(folder) if f.endswith("." + extension))


def import_volume(settings, first, last):
    """Writes frames first..last of a volume scene as OpenVDB files with the impulse tool (in a
    new temporary directory) and imports them as one Volume object sequence; returns it. Raises
    RuntimeError with the tool's error line."""
    folder = tempfile.mkdtemp(prefix="impulse_volume_")
    files = _render_frames(settings, first, last, folder, "vdb", sized=False)
    bpy.ops.object.volume_import(filepath=os.path.join(folder, files[0]), directory=folder,
                                 files=[{"name": f} for f in files])
    volume = bpy.context.active_object
    volume.data.frame_start = first  # impulse frame f at Blender frame f, as Fill Image does
    return volume


def _image_users(image_names):
    """The Image Texture nodes (materials, worlds, node groups), compositor Image nodes and Image
    Editors showing one of the images named, with what holds each one's frame settings: the node's
    or editor's ImageUser, or a compositor node itself."""
    users = []
    trees = [m.node_tree for m in bpy.data.materials if m.node_tree]
    trees += [w.node_tree for w in bpy.data.worlds if w.node_tree]
    trees += list(bpy.data.node_groups) + [s.node_tree for s in bpy.data.scenes if s.node_tree]
    for tree in trees:
        for node in tree.nodes:
            image = getattr(node, "image", None)
            if image is not None and image.name in image_names:
                users.append((node, node.image_user if hasattr(node, "image_user") else node))
    for screen in bpy.data.screens:
        for area in screen.areas:
            for space in area.spaces:
                if space.type == "IMAGE_EDITOR" and space.image and space.image.name in image_names:
                    users.append((space, space.image_user))
    return users


def bake_sequence(settings, first, last, directory):
    """Renders frames first..last with the impulse tool as EXR files STEM_####.exr (file number =
    frame) into `directory` (a new temporary one when empty) and loads them as one Image of
    source SEQUENCE; every Image Texture node, compositor Image node and Image Editor that showed
    the settings' Image (or an earlier bake) shows the sequence instead, Blender frame f reading
    file f. Returns the Image. The files are rendered into a hidden folder beside them and moved
    in only when all are written: a failure leaves nothing and raises RuntimeError."""
    directory = bpy.path.abspath(directory) if directory else tempfile.mkdtemp(prefix="impulse_bake_")
    try:
        os.makedirs(directory, exist_ok=True)
        staging = tempfile.mkdtemp(prefix=".impulse_bake_", dir=directory)
    except OSError as e:
        raise RuntimeError(f"{directory}: {e.strerror}: expected a directory the bake can write")
    files = _render_frames(settings, first, last, staging, "exr")
    if len(files) != last - first + 1:
        shutil.rmtree(staging, ignore_errors=True)
        raise RuntimeError(f"impulse render wrote {len(files)} files for frames {first}-{last}")
    for f in files:
        os.replace(os.path.join(staging, f), os.path.join(directory, f))
    os.rmdir(staging)
    image = bpy.data.images.load(os.path.join(directory, files[0]), check_existing=False)
    image.source = "SEQUENCE"
    image.colorspace_settings.name = "Non-Color"  # the field's raw values, as Fill Image
    shown = {i.name for i in (settings.image, settings.baked) if i is not None}
    for holder, user in _image_users(shown | {image.name}):
        holder.image = image
        # Blender reads file (f - frame_start + 1) + frame_offset at frame f (its ImageUser
        # frame rule): start A, offset A - 1 makes frame A read file A, frame A + k file A + k.
        user.frame_start, user.frame_offset, user.frame_duration = first, first - 1, last - first + 1
        if hasattr(user, "use_auto_refresh"):
            user.use_auto_refresh = True  # follow the timeline
    settings.baked = image
    return image


def _write_ply(mesh, path):
    """The mesh's vertices (in Blender's order) and polygons as ASCII PLY."""
    lines = ["ply", "format ascii 1.0", f"element vertex {len(mesh.vertices)}", "property float x",
             "property float y", "property float z", f"element face {len(mesh.polygons)}",
             "property list uchar int vertex_indices", "end_header"]
    lines += ["%.9g %.9g %.9g" % tuple(v.co) for v in mesh.vertices]
    lines += [" ".join([str(len(p.vertices))] + [str(i) for i in p.vertices]) for p in mesh.polygons]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def ply_vertex_columns(path, names):
    """The columns `names` of an ASCII PLY's vertices (as the impulse tool writes them), in the
    file's vertex order: a list of one list of floats per vertex."""
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
    columns = [props.index(c) for c in names]
    rows = (text[at + 1 + i].split() for i in range(count))
    return [[float(row[k]) for k in columns] for row in rows]


def ply_colours(path):
    """The 8-bit red, green, blue of an ASCII PLY's vertices, in their order, as [0, 1] floats."""
    return [[c / 255.0 for c in rgb] for rgb in ply_vertex_columns(path, ("red", "green", "blue"))]


def _linear(c):
    """sRGB-encoded display value to linear (Blender's colour attributes hold linear colour)."""
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def texture_mesh(obj, transform, seed):
    """Colours every vertex of the mesh object with `impulse mesh texture` (solid wood or marble,
    docs/mesh.md) into the colour attribute "impulse": the tool writes vertex i of its input as
    vertex i, so the colours line up with Blender's vertices. Raises RuntimeError with the
    tool's error line."""
    with tempfile.TemporaryDirectory(prefix="impulse_mesh_") as folder:
        source, textured = os.path.join(folder, "in.ply"), os.path.join(folder, "out.ply")
        _write_ply(obj.data, source)
        _run_tool(["mesh", "texture", source, "--transform", transform, "--seed", str(seed), "-o", textured])
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


def _write_obj(mesh, path):
    """The mesh's vertices (in Blender's order) and polygons as OBJ, which the tool reads with its
    own reader: vertex i of the file is vertex i of the mesh (docs/mesh.md "Formats")."""
    with open(path, "w") as f:
        f.writelines("v %.9g %.9g %.9g\n" % tuple(v.co) for v in mesh.vertices)
        f.writelines("f " + " ".join(str(i + 1) for i in p.vertices) + "\n" for p in mesh.polygons)


def _import_ply(path, name):
    """Imports an ASCII PLY with Blender's own importer as a new mesh object named `name` (the
    importer keeps the file's vertex order); returns it."""
    before = set(bpy.data.objects)
    bpy.ops.import_mesh.ply(filepath=path)
    new = [o for o in bpy.data.objects if o not in before]
    if len(new) != 1:
        raise RuntimeError(f"{os.path.basename(path)}: Blender's PLY importer made {len(new)} objects")
    new[0].name = new[0].data.name = name
    bpy.context.view_layer.objects.active = new[0]
    return new[0]


def porous_object(iso, envelope, falloff, size, scale, seed):
    """`impulse mesh porous` (the iso-surface of solid noise times a sphere or box envelope over
    [-1, 1]^3, docs/mesh.md "Porous objects (L89 §5.2)") as a new mesh object; returns it. Raises
    RuntimeError with the tool's error line."""
    with tempfile.TemporaryDirectory(prefix="impulse_mesh_") as folder:
        out = os.path.join(folder, "porous.ply")
        _run_tool(["mesh", "porous", "--iso", _number(iso), "--envelope", envelope, "--falloff",
                   _number(falloff), "--size", str(size), "--scale", _number(scale), "--seed", str(seed),
                   "-o", out])
        return _import_ply(out, f"impulse porous {envelope}")


def deform_mesh(obj, amount, scale, seed, frames=0):
    """A copy of the mesh object displaced by vector solid noise (`impulse mesh deform`,
    docs/mesh.md "Stochastic deformation (L89 §5.3)") as a new object with the same transform:
    vertex i of the new mesh is vertex i of the old one, moved. With `frames` N > 0, the tool's
    N frames through 4-D noise (`--frames N`): the mesh is frame 0 and shape key "frame f" holds
    frame f, weighted 1 at Blender frame f and 0 one frame either side, so the shape plays frame
    f at Blender frame f (linear in between). Raises RuntimeError with the tool's error line, or
    when the vertex count changed (nothing is kept then)."""
    with tempfile.TemporaryDirectory(prefix="impulse_mesh_") as folder:
        source = os.path.join(folder, "in.obj")
        out = os.path.join(folder, "out_####.ply" if frames > 0 else "out.ply")
        _write_obj(obj.data, source)
        _run_tool(["mesh", "deform", source, "--amount", _number(amount), "--scale", _number(scale),
                   "--seed", str(seed), "-o", out] + (["--frames", str(frames)] if frames > 0 else []))
        first = out.replace("####", "0000")
        deformed = _import_ply(first, f"{obj.name} deformed")
        if len(deformed.data.vertices) != len(obj.data.vertices):
            count = len(deformed.data.vertices)
            bpy.data.meshes.remove(deformed.data)  # removes the object with it
            raise RuntimeError(f"impulse mesh deform: {count} vertices came back for {len(obj.data.vertices)}")
        if frames > 0:
            _shape_keys(deformed, [out.replace("####", "%04d" % f) for f in range(frames)])
    deformed.matrix_world = obj.matrix_world
    return deformed


def _shape_keys(obj, files):
    """Shape keys "frame f" (f >= 1) from the positions of files[f] (vertex i of each file is
    vertex i of the mesh), keyed to weight 1 at Blender frame f only."""
    obj.shape_key_add(name="frame 0", from_mix=False)  # the basis: the mesh, frame 0
    for f, path in enumerate(files[1:], start=1):
        key = obj.shape_key_add(name=f"frame {f}", from_mix=False)
        key.data.foreach_set("co", [c for p in ply_vertex_columns(path, ("x", "y", "z")) for c in p])
        for frame, weight in ((f - 1, 0.0), (f, 1.0), (f + 1, 0.0)):
            key.value = weight
            key.keyframe_insert("value", frame=frame)
        for point in obj.data.shape_keys.animation_data.action.fcurves[-1].keyframe_points:
            point.interpolation = "LINEAR"


def refresh_keys(settings):
    """Reads the keys named in Expose (as --expose takes them: `key` or `key=lo:hi`, separated by
    commas) from the scene with the module (scenes/exposed.h, as `impulse preview` does) into the
    settings' sliders; values at the file's, none moved. Raises impulse.Error naming a key the
    scene does not hold as a number (the sliders are emptied)."""
    settings.keys.clear()
    specs = [k.strip() for k in settings.expose.split(",") if k.strip()]
    if not specs:
        return
    for k in _impulse().exposed_keys(settings.source, specs):
        item = settings.keys.add()
        with _Quietly():
            item.key, item.lo, item.hi = k["key"], k["lo"], k["hi"]
            item.step, item.integer = k["step"], k["integer"]
            _show(item, k["value"])


def _read_keys(settings):
    """refresh_keys, its error also kept for the panel to show."""
    settings.keys_error = ""
    try:
        refresh_keys(settings)
    except Exception as e:
        settings.keys_error = str(e)
        raise


def _refresh_on_change(settings, context):
    """Source or Expose changed: the sliders follow; a key the scene lacks shows in the panel
    (an update callback has no report)."""
    try:
        _read_keys(settings)
    except Exception:
        pass


_quiet = []  # non-empty while the add-on itself sets sliders: no operator call then


class _Quietly:
    """Sets sliders without their update calling impulse.set_key."""

    def __enter__(self):
        _quiet.append(1)

    def __exit__(self, *exc):
        _quiet.pop()


def _show(item, value):
    """Puts `value` on the slider (both of its fields) as the value taken, calling nothing."""
    with _Quietly():
        item.value = item.applied = value
        item.whole = int(round(value)) if item.integer else 0


def _slider_moved(item, context):
    """A slider changed in the panel: the value goes through impulse.set_key (its range checked,
    its error the operator's report, the Image re-rendered when following the timeline). An
    integer key's field is `whole`: dragging it gives whole numbers only."""
    if _quiet:
        return
    value = float(item.whole) if item.integer else item.value
    try:
        bpy.ops.impulse.set_key(key=item.key, value=value)
    except RuntimeError as e:  # the report, as Blender raises it where there is no window
        print(f"impulse: {e}")


def set_key(settings, key, value, frame):
    """Sets the slider of `key` to `value` and re-renders `frame` when following the timeline.
    Raises ValueError (one line naming the key, the value and the range) for an unknown key, a
    value outside the slider's range or a fraction for an integer key, and impulse.Error with the
    loader's line for a value the scene refuses; the slider and the Image are left as they were
    then."""
    import math

    item = next((i for i in settings.keys if i.key == key), None)
    if item is None:
        names = ", ".join(i.key for i in settings.keys) or "none (Expose names them)"
        raise ValueError(f'unknown key "{key}": the exposed keys are {names}')
    expected = ""
    if not (math.isfinite(value) and item.lo <= value <= item.hi):
        expected = "a value in"
    elif item.integer and value != round(value):
        expected = "a whole number (the scene writes an integer) in"
    if expected:
        _show(item, item.applied)  # a typed-in value goes back
        raise ValueError(f"{key} = {value:g}: expected {expected} [{item.lo:g}, {item.hi:g}], "
                         "the slider's range")
    before, was_moved = item.applied, item.moved
    _show(item, value)
    item.moved = True
    try:  # a value the scene refuses (a radius of 0) is its loader's error; the slider goes back
        _scene(settings)
        if settings.follow:
            fill(settings, frame)
    except Exception:
        _show(item, before)
        item.moved = was_moved
        raise


class ImpulseKey(bpy.types.PropertyGroup):
    """One exposed key's slider: its value, its range and whether it applies as an override."""

    key: StringProperty(name="Key")
    value: FloatProperty(name="Value", update=_slider_moved, precision=4)
    whole: IntProperty(name="Value", update=_slider_moved)  # the field of an integer key
    applied: FloatProperty()  # the last value taken (a refused one goes back to it)
    lo: FloatProperty()
    hi: FloatProperty()
    step: FloatProperty()
    integer: BoolProperty()
    moved: BoolProperty()  # set since the keys were read: applies as --set


class ImpulseSettings(bpy.types.PropertyGroup):
    source: StringProperty(name="Scene", default="drift", update=_refresh_on_change,
                           description="A built-in scene (drift, clouds, marble ...) or a TOML file")
    expose: StringProperty(name="Expose", default="", update=_refresh_on_change,
                           description="Keys given sliders, as impulse preview --expose: key or "
                                       "key=lo:hi, separated by commas (layer.0.kernel.radius)")
    keys: CollectionProperty(type=ImpulseKey)
    keys_error: StringProperty()
    baked: PointerProperty(name="Baked", type=bpy.types.Image)
    overrides: StringProperty(name="Overrides", default="",
                              description="key=value; key=value: scene keys set as --set does")
    width: IntProperty(name="Width", default=0, min=0, max=32768,
                       description="Pixels across (0: the scene's own size); the same view, as --size")
    height: IntProperty(name="Height", default=0, min=0, max=32768)
    image: PointerProperty(name="Image", type=bpy.types.Image)
    follow: BoolProperty(name="Follow the timeline", default=False,
                         description="Fill the Image with the current frame whenever it changes")


def _reported(operator, work):
    """Runs work(), which returns the INFO line (or ""); an exception (impulse.Error with the
    library's line, RuntimeError with the tool's) is the operator's one-line ERROR report."""
    try:
        info = work()
    except Exception as e:
        operator.report({"ERROR"}, str(e))
        return {"CANCELLED"}
    if info:
        operator.report({"INFO"}, info)
    return {"FINISHED"}


def _frames(first, last):
    """Raises ValueError unless first <= last."""
    if last < first:
        raise ValueError(f"frames {first}-{last}: expected first <= last")


def _active_mesh(context, what):
    """The active object when it is a mesh; else ValueError naming the operator."""
    obj = context.active_object
    if obj is None or obj.type != "MESH":
        raise ValueError(f"{what}: the active object is not a mesh")
    return obj


class IMPULSE_OT_fill_image(bpy.types.Operator):
    """Render a frame of the impulse scene into the Image"""

    bl_idname = "impulse.fill_image"
    bl_label = "Fill Image"
    frame: IntProperty(name="Frame", default=-1, description="The frame (-1: the current frame)")

    def execute(self, context):
        frame = self.frame if self.frame >= 0 else context.scene.frame_current
        return _reported(self, lambda: f"{fill(context.scene.impulse, frame).name}: frame {frame}")


class IMPULSE_OT_import_volume(bpy.types.Operator):
    """Render frames of a volume scene to OpenVDB with the impulse tool and import them as a Volume object"""

    bl_idname = "impulse.import_volume"
    bl_label = "Import Volume"
    first: IntProperty(name="First frame", default=0, min=0)
    last: IntProperty(name="Last frame", default=0, min=0)

    def execute(self, context):
        def work():
            _frames(self.first, self.last)
            volume = import_volume(context.scene.impulse, self.first, self.last)
            return f"{volume.name}: frames {self.first}-{self.last}"
        return _reported(self, work)


class IMPULSE_OT_texture_mesh(bpy.types.Operator):
    """Colour the active mesh's vertices with solid wood or marble (impulse mesh texture)"""

    bl_idname = "impulse.texture_mesh"
    bl_label = "Texture Mesh"
    transform: EnumProperty(name="Transform", items=[("wood", "Wood", ""), ("marble", "Marble", "")])
    seed: IntProperty(name="Seed", default=0, min=0)

    def execute(self, context):
        def work():
            obj = _active_mesh(context, "Texture Mesh")
            texture_mesh(obj, self.transform, self.seed)
            return f"{obj.name}: colour attribute \"impulse\" ({self.transform})"
        return _reported(self, work)


class IMPULSE_OT_set_key(bpy.types.Operator):
    """Set an exposed key's slider (an override, as --set) and re-render when following the timeline"""

    bl_idname = "impulse.set_key"
    bl_label = "Set Key"
    bl_options = {"INTERNAL"}
    key: StringProperty(name="Key")
    value: FloatProperty(name="Value")

    def execute(self, context):
        scene = context.scene
        return _reported(self, lambda: set_key(scene.impulse, self.key, self.value, scene.frame_current))


class IMPULSE_OT_refresh_keys(bpy.types.Operator):
    """Read the exposed keys from the scene again (values back to the file's)"""

    bl_idname = "impulse.refresh_keys"
    bl_label = "Reset Sliders"

    def execute(self, context):
        return _reported(self, lambda: _read_keys(context.scene.impulse))


class IMPULSE_OT_bake_sequence(bpy.types.Operator):
    """Render frames to an EXR sequence with the impulse tool, shown where the Image was (final render)"""

    bl_idname = "impulse.bake_sequence"
    bl_label = "Bake EXR Sequence"
    first: IntProperty(name="First frame", default=0, min=0)
    last: IntProperty(name="Last frame", default=0, min=0)
    directory: StringProperty(name="Directory", subtype="DIR_PATH",
                              description="Where the EXR files go (empty: a new temporary directory)")

    def invoke(self, context, event):
        self.first, self.last = context.scene.frame_start, context.scene.frame_end
        return context.window_manager.invoke_props_dialog(self)

    def execute(self, context):
        def work():
            _frames(self.first, self.last)
            image = bake_sequence(context.scene.impulse, self.first, self.last, self.directory)
            return f"{image.name}: frames {self.first}-{self.last} from {image.filepath}"
        return _reported(self, work)


class IMPULSE_OT_porous_object(bpy.types.Operator):
    """Make a porous object: the iso-surface of solid noise times an envelope (impulse mesh porous)"""

    bl_idname = "impulse.porous_object"
    bl_label = "Porous Object"
    bl_options = {"REGISTER", "UNDO"}
    iso: FloatProperty(name="Iso", default=0.5,
                       description="The iso value in standard deviations of the noise, nonzero")
    envelope: EnumProperty(name="Envelope", items=[("sphere", "Sphere", ""), ("box", "Box", "")])
    falloff: FloatProperty(name="Falloff", default=0.3, min=0.001, max=1.0)
    size: IntProperty(name="Grid", default=64, min=8, max=1024, description="Grid samples across the object")
    scale: FloatProperty(name="Scale", default=0.25,
                         description="Kernel radius of the noise, object units ([-1, 1]^3)")
    seed: IntProperty(name="Seed", default=0, min=0)

    def execute(self, context):
        def work():
            obj = porous_object(self.iso, self.envelope, self.falloff, self.size, self.scale, self.seed)
            return f"{obj.name}: {len(obj.data.polygons)} faces"
        return _reported(self, work)


class IMPULSE_OT_deform_mesh(bpy.types.Operator):
    """Displace a copy of the active mesh by vector solid noise (impulse mesh deform)"""

    bl_idname = "impulse.deform_mesh"
    bl_label = "Deform Mesh"
    bl_options = {"REGISTER", "UNDO"}
    amount: FloatProperty(name="Amount", default=0.1,
                          description="Displacement per standard deviation, mesh units")
    scale: FloatProperty(name="Scale", default=0.5, description="Kernel radius of the noise, mesh units")
    seed: IntProperty(name="Seed", default=0, min=0)
    frames: IntProperty(name="Frames", default=0, min=0, max=100000,
                        description="0: one shape; N: frames 0..N-1 through 4-D noise as shape keys "
                                    "(frame f at Blender frame f)")

    def execute(self, context):
        def work():
            obj = _active_mesh(context, "Deform Mesh")
            deformed = deform_mesh(obj, self.amount, self.scale, self.seed, self.frames)
            return f"{deformed.name}: {len(deformed.data.vertices)} vertices moved"
        return _reported(self, work)


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
        layout.prop(settings, "expose")
        if settings.keys_error:
            layout.label(text=settings.keys_error, icon="ERROR")
        column = layout.column(align=True)
        for item in settings.keys:
            # A number field a key, its range above it: a float property has one range for all
            # its instances, so each key's own range is shown here and checked by impulse.set_key.
            column.label(text=f"{item.key}  [{item.lo:g}, {item.hi:g}]")
            column.prop(item, "whole" if item.integer else "value", text="")
        if len(settings.keys):
            layout.operator(IMPULSE_OT_refresh_keys.bl_idname)
        row = layout.row()
        row.prop(settings, "width")
        row.prop(settings, "height")
        layout.prop(settings, "image")
        layout.prop(settings, "follow")
        layout.operator(IMPULSE_OT_fill_image.bl_idname)
        layout.operator(IMPULSE_OT_bake_sequence.bl_idname)
        if settings.baked:
            layout.label(text=f"Baked: {settings.baked.name}")
        layout.operator(IMPULSE_OT_import_volume.bl_idname)
        layout.separator()
        layout.operator(IMPULSE_OT_texture_mesh.bl_idname)
        layout.operator(IMPULSE_OT_deform_mesh.bl_idname)
        layout.operator(IMPULSE_OT_porous_object.bl_idname)


class ImpulsePreferences(bpy.types.AddonPreferences):
    bl_idname = __name__
    module_dir: StringProperty(name="impulse module directory", subtype="DIR_PATH",
                               description="Where `import impulse` is found: build/python, or a "
                                           "venv's site-packages (empty: Blender's Python path)")
    tool: StringProperty(name="impulse tool", subtype="FILE_PATH", default="impulse",
                         description="The impulse command (Import Volume, Bake, the mesh operators run it)")

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


_classes = (ImpulseKey, ImpulseSettings, IMPULSE_OT_fill_image, IMPULSE_OT_set_key,
            IMPULSE_OT_refresh_keys, IMPULSE_OT_bake_sequence, IMPULSE_OT_import_volume,
            IMPULSE_OT_texture_mesh, IMPULSE_OT_deform_mesh, IMPULSE_OT_porous_object,
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
