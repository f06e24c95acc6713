#!/usr/bin/env python3
"""scenes/cloud/cloud.xml in Blender Cycles (CPU): the same `.vdb` cloud, sun,
sky and camera, for timing raylab against Cycles on a volume.

    VENV/bin/python tools/cycles_cloud.py scenes/cloud/cloud.vdb -o OUT.exr \\
        --spp N --threads T [--width 320 --height 180] [--seed S] [--density 60]

(VENV: the CPython 3.13 venv with `bpy` that ../shared/cycles/setup.sh
makes.) The scene follows cloud.xml: the grid's values times `--density`
are the extinction per unit length (Principled Volume: Density; Color is
the albedo, 0.97, with Absorption Color black: Cycles absorbs
`(1 - Color)(1 - Absorption Color)` times the density, so a white
Absorption Color would absorb nothing and make the extinction Color times
the density), Henyey-Greenstein
g = 0.5, a delta sun of irradiance (6, 5.6, 5) along (-0.6, -0.45, -0.66), a
sky of radiance (0.25, 0.35, 0.55), a pinhole camera of 40 degrees
horizontal field of view. Mitsuba's y-up world becomes Blender's z-up one as
the glTF importer turns it (+90 degrees about x). Cycles is set as
../shared/cycles/render_gltf.py sets it for fair timing (no clamping, no
light threshold, no guiding, no adaptive sampling, no denoising), with its
unbiased volume tracking (volume_biased off) and 64 bounces. One JSON line
with the render's seconds ends the output.
"""
import argparse
import json
import math
import sys
import time

import numpy as np

ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("vdb")
ap.add_argument("-o", "--output", required=True)
ap.add_argument("--spp", type=int, required=True)
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--width", type=int, default=320)
ap.add_argument("--height", type=int, default=180)
ap.add_argument("--seed", type=int, default=0)
ap.add_argument("--density", type=float, default=60.0)
a = ap.parse_args()

import bpy  # noqa: E402
from mathutils import Matrix, Vector  # noqa: E402

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
Y_UP_TO_Z_UP = Matrix.Rotation(math.radians(90), 4, "X")


def z_up(v):
    return Y_UP_TO_Z_UP @ Vector(v)


# The cloud, placed by the file's own transform, turned to z up.
bpy.ops.object.volume_import(filepath=a.vdb, align="WORLD", location=(0, 0, 0))
cloud = bpy.context.object
cloud.matrix_world = Y_UP_TO_Z_UP @ cloud.matrix_world
mat = bpy.data.materials.new("cloud")
mat.use_nodes = True
nt = mat.node_tree
nt.nodes.clear()
out = nt.nodes.new("ShaderNodeOutputMaterial")
vol = nt.nodes.new("ShaderNodeVolumePrincipled")
vol.inputs["Color"].default_value = (0.97, 0.97, 0.97, 1.0)
vol.inputs["Density"].default_value = a.density
vol.inputs["Anisotropy"].default_value = 0.5
vol.inputs["Absorption Color"].default_value = (0.0, 0.0, 0.0, 1.0)
nt.links.new(vol.outputs["Volume"], out.inputs["Volume"])
cloud.data.materials.append(mat)

# Sky and sun.
world = bpy.data.worlds.new("sky")
world.use_nodes = True
bg = world.node_tree.nodes["Background"]
bg.inputs["Color"].default_value = (0.25, 0.35, 0.55, 1.0)
bg.inputs["Strength"].default_value = 1.0
scene.world = world
sun = bpy.data.lights.new("sun", "SUN")
sun.energy = 6.0
sun.color = (1.0, 5.6 / 6.0, 5.0 / 6.0)
sun.angle = 0.0
sun_obj = bpy.data.objects.new("sun", sun)
scene.collection.objects.link(sun_obj)
d = z_up((-0.6, -0.45, -0.66)).normalized()
# A sun shines along its local -z.
sun_obj.rotation_euler = d.to_track_quat("-Z", "Y").to_euler()

# Camera: lookat origin (0.4, 0.25, 3.6), target 0, up +y (Mitsuba).
cam = bpy.data.cameras.new("camera")
cam.sensor_fit = "HORIZONTAL"
cam.angle = math.radians(40.0)
cam.clip_start = 1e-3
cam.clip_end = 1e4
cam_obj = bpy.data.objects.new("camera", cam)
scene.collection.objects.link(cam_obj)
origin = z_up((0.4, 0.25, 3.6))
cam_obj.location = origin
cam_obj.rotation_euler = (Vector((0, 0, 0)) - origin).to_track_quat("-Z", "Y").to_euler()
scene.camera = cam_obj

r = scene.render
r.engine = "CYCLES"
r.resolution_x, r.resolution_y, r.resolution_percentage = a.width, a.height, 100
r.threads_mode = "FIXED"
r.threads = a.threads
r.use_persistent_data = False
r.film_transparent = False
r.dither_intensity = 0.0
r.use_compositing = False
r.use_sequencer = False
cy = scene.cycles
cy.device = "CPU"
cy.samples = a.spp
cy.use_adaptive_sampling = False
cy.seed = a.seed
cy.use_denoising = False
cy.use_light_tree = True
cy.light_sampling_threshold = 0.0
cy.use_guiding = False
cy.volume_biased = False
for k in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
          "volume_bounces", "transparent_max_bounces"):
    setattr(cy, k, 64)
cy.sample_clamp_direct = 0.0
cy.sample_clamp_indirect = 0.0
cy.blur_glossy = 0.0
cy.pixel_filter_type = "BOX"
cy.filter_width = 1.0
vs = scene.view_settings
vs.view_transform = "Standard"
vs.look = "None"
r.image_settings.file_format = "OPEN_EXR"
r.image_settings.color_depth = "32"
r.image_settings.exr_codec = "ZIP"
r.filepath = a.output

t0 = time.perf_counter()
bpy.ops.render.render(write_still=True)
seconds = time.perf_counter() - t0
print(json.dumps({"seconds": seconds, "spp": a.spp, "output": a.output}))
