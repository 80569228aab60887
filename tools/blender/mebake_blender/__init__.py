# mebake for Blender: bakes global illumination onto the selected objects with the mebake
# command-line tool and shows the result on them (docs/blender.md).
#
# Render properties > mebake: settings and "Bake with mebake". The operator exports the
# selected objects (world space, triangulated, modifiers applied) to a binary PLY, runs
# `mebake bake --progress json` in the background with the progress in the status bar
# (Esc cancels; mebake keeps its checkpoint), then reads the baked mesh with its light-map
# UVs (a PLY that `mebake export` writes, so Blender's glTF importer, which fails on Debian
# 12's numpy, is not needed) and the light map (EXR) back onto the object: the baked mesh
# replaces the object's mesh, with a UV map "mebake_lightmap" and a material that emits
# the baked radiance (image texture -> emission, strength 1/pi).
# Several selected objects are baked as one scene (they shadow each other) and come back
# as one object.

bl_info = {
    "name": "mebake",
    "author": "mebake project",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Render > mebake",
    "description": "Bake global illumination onto scanned meshes with mebake",
    "category": "Render",
}

import bpy

from . import bake

classes = (bake.MebakePreferences, bake.MebakeSettings, bake.MEBAKE_OT_bake,
           bake.MEBAKE_PT_panel)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.mebake = bpy.props.PointerProperty(type=bake.MebakeSettings)


def unregister():
    del bpy.types.Scene.mebake
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
