# The operator, its settings and the panel: export -> `mebake bake` -> apply the light map.
import json
import math
import os
import signal
import subprocess
import tempfile
import threading

from array import array

import bpy

from . import ply

UV_NAME = "mebake_lightmap"


class MebakePreferences(bpy.types.AddonPreferences):
    bl_idname = __package__
    mebake_path: bpy.props.StringProperty(
        name="mebake executable", subtype="FILE_PATH", default="mebake",
        description="Path of the mebake program (or its name on PATH)")

    def draw(self, context):
        self.layout.prop(self, "mebake_path")


class MebakeSettings(bpy.types.PropertyGroup):
    output_dir: bpy.props.StringProperty(
        name="Output", subtype="DIR_PATH", default="//mebake/",
        description="Where the bake goes (// = beside the .blend; a temporary folder when "
                    "the file is not saved)")
    order: bpy.props.IntProperty(name="Order", min=0, max=3, default=2,
                                 description="Wavelet order: 0 constant ... 3 cubic")
    max_bounces: bpy.props.IntProperty(name="Bounces", min=0, max=64, default=16,
                                       description="Shooting batches after the direct pass")
    lightmap_resolution: bpy.props.IntProperty(
        name="Light-map size", min=64, max=16384, default=2048,
        description="Atlas side the texel size aims at")
    ground: bpy.props.BoolProperty(
        name="Ground plane", default=False,
        description="Add a floor under the objects that receives their shadow")
    threads: bpy.props.IntProperty(name="Threads", min=0, max=1024, default=0,
                                   description="Worker threads (0: all cores)")


def _mebake_binary(context):
    prefs = context.preferences.addons[__package__].preferences
    return bpy.path.abspath(prefs.mebake_path) if os.sep in prefs.mebake_path else prefs.mebake_path


def _output_dir(settings):
    if settings.output_dir.startswith("//") and not bpy.data.filepath:
        return tempfile.mkdtemp(prefix="mebake-blender-")
    return os.path.abspath(bpy.path.abspath(settings.output_dir))


def export_objects(objects, depsgraph, path):
    """The objects' evaluated meshes (modifiers applied), in world space, as one PLY."""
    positions, triangles, base = array("f"), array("i"), 0
    for obj in objects:
        evaluated = obj.evaluated_get(depsgraph)
        mesh = evaluated.to_mesh()
        try:
            mesh.transform(obj.matrix_world)
            mesh.calc_loop_triangles()
            co = array("f", bytes(4 * 3 * len(mesh.vertices)))
            mesh.vertices.foreach_get("co", co)
            tris = array("i", bytes(4 * 3 * len(mesh.loop_triangles)))
            mesh.loop_triangles.foreach_get("vertices", tris)
            positions.extend(co)
            triangles.extend(t + base for t in tris)
            base += len(mesh.vertices)
        finally:
            evaluated.to_mesh_clear()
    if not triangles:
        raise RuntimeError("the selected objects have no faces to bake onto")
    ply.write_triangles(path, positions, triangles)


class BakeJob:
    """`mebake bake` then `mebake export --mesh` in a thread; progress from --progress json."""

    def __init__(self, binary, settings, scan, out_dir):
        self.out_dir = out_dir
        self.scene_dir = os.path.join(out_dir, "scene.mebake")
        self.mesh = os.path.join(out_dir, "baked_uv.ply")
        self.lightmap = os.path.join(out_dir, "lightmap.exr")
        bake = [binary, "bake", scan, "-o", out_dir, "--force", "--progress", "json",
                "--order", str(settings.order), "--max-bounces", str(settings.max_bounces),
                "--lightmap-resolution", str(settings.lightmap_resolution),
                "--threads", str(settings.threads),
                # Blender's world is z-up: the default light, camera and ground stand on it.
                "--up", "z"]
        if settings.ground:
            bake.append("--ground")
        export = [binary, "-q", "export", self.scene_dir, "--mesh", self.mesh, "--force"]
        self.commands = [bake, export]
        self.status = "mebake: starting"
        self.fraction = 0.0
        self.log = []  # the last lines that were not progress objects (for errors)
        self.returncode = None
        self.cancelled = False
        self._proc = None
        self._lock = threading.Lock()
        self._thread = None

    def _read(self, stream):
        for raw in stream:
            line = raw.decode("utf-8", "replace").rstrip()
            if line.startswith("{"):
                try:
                    p = json.loads(line)
                except ValueError:
                    continue
                pct = "" if p.get("fraction") is None else f" {100 * p['fraction']:.0f}%"
                eta = "" if p.get("eta") in (None, 0) else f", {p['eta']:.0f} s left"
                detail = f" ({p['detail']})" if p.get("detail") else ""
                self.status = f"mebake: {p['stage']}{detail}{pct}{eta}  (Esc cancels)"
                self.fraction = p.get("fraction") or 0.0
            elif line:
                self.log = (self.log + [line])[-20:]

    def run(self):
        for cmd in self.commands:
            with self._lock:
                if self.cancelled:
                    self.returncode = 130
                    return
                self._proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL,
                                              stderr=subprocess.PIPE)
            self._read(self._proc.stderr)
            rc = self._proc.wait()
            if rc != 0:
                self.returncode = rc
                return
        self.returncode = 0

    def start(self):
        self._thread = threading.Thread(target=self.run, daemon=True)
        self._thread.start()

    def done(self):
        return self.returncode is not None

    def cancel(self):
        # SIGINT: mebake stops at the next batch boundary and keeps its checkpoint.
        with self._lock:
            self.cancelled = True
            if self._proc and self._proc.poll() is None:
                self._proc.send_signal(signal.SIGINT)

    def error(self):
        tail = "\n".join(self.log[-5:])
        return f"mebake failed (exit {self.returncode}): {tail}"


def _lightmap_material(image, name):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    uv = nodes.new("ShaderNodeUVMap")
    uv.uv_map = UV_NAME
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = image
    tex.interpolation = "Linear"
    emit = nodes.new("ShaderNodeEmission")
    # The light map holds radiosity B (W/m^2); what a surface shows is radiance B / pi.
    emit.inputs["Strength"].default_value = 1.0 / math.pi
    out = nodes.new("ShaderNodeOutputMaterial")
    links.new(uv.outputs["UV"], tex.inputs["Vector"])
    links.new(tex.outputs["Color"], emit.inputs["Color"])
    links.new(emit.outputs["Emission"], out.inputs["Surface"])
    for k, node in enumerate((uv, tex, emit, out)):
        node.location = (300 * k - 600, 0)
    return mat


def apply_bake(context, objects, job):
    """The baked mesh with its light-map UVs and the light map onto the object: the one
    selected object, or a new object "mebake" for several (the originals are hidden)."""
    if not os.path.exists(job.lightmap):
        raise RuntimeError(f"{job.lightmap} is missing (an atlas of several pages is not "
                           "supported here yet: lower the light-map size)")
    positions, uv, tris = ply.read_baked_mesh(job.mesh)
    if len(objects) == 1:
        target = objects[0]
    else:
        target = bpy.data.objects.new("mebake", bpy.data.meshes.new("mebake"))
        context.scene.collection.objects.link(target)
        for obj in objects:
            obj.hide_set(True)
            obj.hide_render = True
    nv, nt = len(positions) // 3, len(tris) // 3
    mesh = bpy.data.meshes.new(target.name + "_mebake")
    mesh.vertices.add(nv)
    mesh.vertices.foreach_set("co", positions)
    mesh.loops.add(3 * nt)
    mesh.loops.foreach_set("vertex_index", tris)
    mesh.polygons.add(nt)
    mesh.polygons.foreach_set("loop_start", array("i", range(0, 3 * nt, 3)))
    mesh.polygons.foreach_set("loop_total", array("i", [3]) * nt)
    mesh.update()
    layer = mesh.uv_layers.new(name=UV_NAME)
    corner_uv = array("f", bytes(4 * 2 * len(tris)))
    for k, v in enumerate(tris):
        corner_uv[2 * k] = uv[2 * v]
        corner_uv[2 * k + 1] = uv[2 * v + 1]
    layer.data.foreach_set("uv", corner_uv)
    # mebake works in world space; the object keeps its transform.
    mesh.transform(target.matrix_world.inverted())
    image = bpy.data.images.load(job.lightmap, check_existing=False)
    image.colorspace_settings.name = "Linear"
    mesh.materials.append(_lightmap_material(image, target.name + "_mebake"))
    target.data = mesh
    # The baked mesh already has the modifiers' result in it.
    target.modifiers.clear()
    return target


class MEBAKE_OT_bake(bpy.types.Operator):
    """Bake global illumination onto the selected objects with mebake"""
    bl_idname = "mebake.bake"
    bl_label = "Bake with mebake"
    bl_options = {"REGISTER"}

    _timer = None
    _job = None
    _objects = None

    @classmethod
    def poll(cls, context):
        return any(o.type == "MESH" for o in context.selected_objects)

    def _start(self, context):
        settings = context.scene.mebake
        self._objects = [o for o in context.selected_objects if o.type == "MESH"]
        out_dir = _output_dir(settings)
        os.makedirs(out_dir, exist_ok=True)
        scan = os.path.join(out_dir, "selection.ply")
        export_objects(self._objects, context.evaluated_depsgraph_get(), scan)
        self._job = BakeJob(_mebake_binary(context), settings, scan, out_dir)

    def _finish(self, context):
        job = self._job
        if job.returncode != 0:
            if job.cancelled:
                self.report({"WARNING"}, "mebake: cancelled")
                return {"CANCELLED"}
            self.report({"ERROR"}, job.error())
            return {"CANCELLED"}
        target = apply_bake(context, self._objects, job)
        self.report({"INFO"}, f"mebake: light map applied to {target.name} ({job.out_dir})")
        return {"FINISHED"}

    def execute(self, context):
        try:
            self._start(context)
        except (OSError, RuntimeError) as e:
            self.report({"ERROR"}, f"mebake: {e}")
            return {"CANCELLED"}
        if bpy.app.background:  # no event loop: run to the end here
            self._job.run()
            return self._finish(context)
        self._job.start()
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.25, window=context.window)
        wm.progress_begin(0, 100)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC":
            self._job.cancel()
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        wm = context.window_manager
        context.workspace.status_text_set(self._job.status)
        wm.progress_update(int(100 * self._job.fraction))
        if not self._job.done():
            return {"RUNNING_MODAL"}
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)
        try:
            return self._finish(context)
        except (OSError, RuntimeError, ValueError) as e:
            self.report({"ERROR"}, f"mebake: {e}")
            return {"CANCELLED"}


class MEBAKE_PT_panel(bpy.types.Panel):
    bl_label = "mebake"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"

    def draw(self, context):
        s = context.scene.mebake
        col = self.layout.column()
        for name in ("output_dir", "order", "max_bounces", "lightmap_resolution", "ground",
                     "threads"):
            col.prop(s, name)
        col.operator(MEBAKE_OT_bake.bl_idname, icon="RENDER_STILL")
