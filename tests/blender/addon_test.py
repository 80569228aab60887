# Headless test of the Blender add-on (tools/blender/mebake_blender):
#   blender -b --factory-startup --python-exit-code 1 --python addon_test.py -- \
#       ADDON_ZIP MEBAKE SAMPLE_PLY WORK_DIR
# installs the add-on from the zip the build makes, imports the sample, bakes it through
# the add-on's operator and checks that the object now has the light map: a UV map from
# the baked mesh, a material whose image texture is the light map, with finite,
# non-negative values, not all zero. Any failure raises (exit code 1).
import math
import os
import sys

from array import array

import bpy
import mathutils

addon_zip, mebake, sample, work = sys.argv[sys.argv.index("--") + 1:][:4]
os.makedirs(work, exist_ok=True)

bpy.ops.preferences.addon_install(filepath=addon_zip, overwrite=True)
bpy.ops.preferences.addon_enable(module="mebake_blender")
bpy.context.preferences.addons["mebake_blender"].preferences.mebake_path = mebake

# Start from an empty scene with only the sample in it.
bpy.ops.object.select_all(action="SELECT")
bpy.ops.object.delete()
if not hasattr(bpy.ops.import_mesh, "ply"):
    bpy.ops.preferences.addon_enable(module="io_mesh_ply")
bpy.ops.import_mesh.ply(filepath=sample)
obj = bpy.context.selected_objects[0]
obj.location = (1.0, 0.5, 0.0)  # a transform, so world and local space differ
bpy.context.view_layer.objects.active = obj
faces_before = len(obj.data.polygons)
x_before = sum(v.co.x for v in obj.data.vertices) / len(obj.data.vertices)

s = bpy.context.scene.mebake
s.output_dir = os.path.join(work, "bake")
s.order = 1
s.max_bounces = 2
s.lightmap_resolution = 256
result = bpy.ops.mebake.bake()
assert result == {"FINISHED"}, f"the operator returned {result}"

mesh = obj.data
assert "mebake_lightmap" in mesh.uv_layers, f"no light-map UV map: {list(mesh.uv_layers.keys())}"
assert abs(len(mesh.polygons) - faces_before) <= faces_before // 10, \
    f"{len(mesh.polygons)} faces after the bake, {faces_before} before"
uv = array("f", bytes(4 * 2 * len(mesh.loops)))
mesh.uv_layers["mebake_lightmap"].data.foreach_get("uv", uv)
assert all(math.isfinite(x) and 0 <= x <= 1 for x in uv), "UVs outside the atlas"
# The mesh stayed where the object was: mebake's world space went back to local space.
co = array("f", bytes(4 * 3 * len(mesh.vertices)))
mesh.vertices.foreach_get("co", co)
mean_x = sum(co[0::3]) / len(mesh.vertices)
assert abs(mean_x - x_before) < 0.05, f"local x mean {mean_x}, was {x_before}"

mat = mesh.materials[0]
images = [n.image for n in mat.node_tree.nodes if n.type == "TEX_IMAGE" and n.image]
assert images, "the material has no image texture"
image = images[0]
w, h = image.size
assert w > 0 and h > 0, "the light map did not load"
px = array("f", bytes(4 * w * h * image.channels))
image.pixels.foreach_get(px)
nc = image.channels
lum = [max(px[i], px[i + 1], px[i + 2]) for i in range(0, len(px), nc)]
assert all(math.isfinite(v) for v in px), "non-finite light-map values"
assert min(lum) >= 0, "negative light-map values"
assert sum(1 for v in lum if v > 0) > 0.05 * len(lum), "the light map is (nearly) all zero"
# The texels the object's UVs land on are lit.
hits = [lum[min(int(uv[k + 1] * h), h - 1) * w + min(int(uv[k] * w), w - 1)]
        for k in range(0, len(uv), 2)]
lit = sum(1 for v in hits if v > 0) / len(hits)
assert lit > 0.9, f"only {lit:.2f} of the UVs land on lit texels"
print(f"mebake add-on test: {len(mesh.polygons)} faces, light map {w}x{h}, "
      f"max {max(lum):.4g}, {lit:.3f} of the UVs on lit texels: OK")

# What a user sees: a small Cycles render (black world, no lights) shows the object only
# through the light map's emission.
scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 4
scene.cycles.use_denoising = False  # Debian builds Cycles without OpenImageDenoise
scene.render.resolution_x = scene.render.resolution_y = 64
scene.render.resolution_percentage = 100
scene.view_settings.view_transform = "Standard"
world = bpy.data.worlds.new("black")
world.use_nodes = False
world.color = (0, 0, 0)
scene.world = world
cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
scene.collection.objects.link(cam)
scene.camera = cam
xs, ys, zs = [], [], []
for corner in obj.bound_box:
    p = obj.matrix_world @ mathutils.Vector(corner)
    xs.append(p.x)
    ys.append(p.y)
    zs.append(p.z)
size = max(max(xs) - min(xs), max(ys) - min(ys), max(zs) - min(zs))
cam.location = ((min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2, max(zs) + 2 * size)  # looks down -Z
scene.render.filepath = os.path.join(work, "cycles.png")
bpy.ops.render.render(write_still=True)
shot = bpy.data.images.load(scene.render.filepath)
rw, rh = shot.size
rp = array("f", bytes(4 * rw * rh * shot.channels))
shot.pixels.foreach_get(rp)
lit_px = sum(1 for i in range(0, len(rp), shot.channels) if max(rp[i:i + 3]) > 0.02)
assert lit_px > 0.1 * rw * rh, f"the Cycles render shows the object in only {lit_px} pixels"
print(f"mebake add-on test: Cycles render {rw}x{rh}, {lit_px} pixels lit by the light map: OK")
