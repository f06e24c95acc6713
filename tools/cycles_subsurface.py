#!/usr/bin/env python3
"""A glTF scene with subsurface materials (KHR_materials_volume_scatter) in
Blender Cycles (CPU), for the picture beside raylab's.

    VENV/bin/python tools/cycles_subsurface.py MODEL.gltf -o OUT.exr --spp N --threads T \\
        [any other option of ../shared/cycles/render_gltf.py]

(VENV: the CPython 3.13 venv with `bpy` that ../shared/cycles/setup.sh
makes; RAYLAB_RENDER_GLTF overrides where render_gltf.py is.) The file is
rendered by ../shared/cycles/render_gltf.py (Blender's glTF importer, fair
settings), whose material set-up is extended: Blender's importer does not
read KHR_materials_volume_scatter, so every material that has it becomes a
Principled BSDF with Subsurface Weight 1, method Random Walk, Base Color
the multiscatterColor (Cycles inverts the albedo its own way), Subsurface
Anisotropy the scatterAnisotropy, and Subsurface Radius 1 / sigma_t per
channel (sigma_t = -ln(attenuationColor) / attenuationDistance), Subsurface
Scale 1. Measured (docs/media.md): Blender 5.2.3's Random Walk takes the
radius as the mean free path (a 1-mfp slab under a uniform sky: R + T 0.714
in Cycles with radius = mfp, 0.979 with radius = 4 pi mfp, raylab 0.649;
the factor can be changed with RAYLAB_RADIUS_PER_MFP), and its own albedo
inversion makes a half-space of Base Color 0.5 reflect 0.438 (raylab:
0.497, the exact target 0.5). Also: Specular IOR Level 0, Transmission 0 and Metallic 0 (the materials this
is for have no specular layer: specularFactor 0); the importer's volume
absorption is unlinked.
"""
import json
import math
import os
import sys

import cycles_peer

rg = cycles_peer.render_gltf()

if len(sys.argv) < 2 or sys.argv[1].startswith("-"):
    sys.exit(__doc__)
model = sys.argv[1]
if model.endswith(".glb"):
    sys.exit("cycles_subsurface.py: give a .gltf (its JSON is read for the materials)")
with open(model) as f:
    doc = json.load(f)
scattering = {}
for m in doc.get("materials", []):
    ext = m.get("extensions", {})
    if "KHR_materials_volume_scatter" not in ext:
        continue
    vol = ext.get("KHR_materials_volume", {})
    scat = ext["KHR_materials_volume_scatter"]
    dist = vol.get("attenuationDistance", math.inf)
    color = vol.get("attenuationColor", [1.0, 1.0, 1.0])
    sigma = [-math.log(max(c, 1e-12)) / dist for c in color]
    scattering[m.get("name", "")] = (scat.get("multiscatterColor", [0.0] * 3), sigma,
                                     scat.get("scatterAnisotropy", 0.0))
if not scattering:
    sys.exit(f"cycles_subsurface.py: no material of {model} has KHR_materials_volume_scatter")

RADIUS_PER_MFP = float(os.environ.get("RAYLAB_RADIUS_PER_MFP", 1.0))
align = rg.align_materials


def align_with_subsurface(bpy, log):
    align(bpy, log)
    for mat in bpy.data.materials:
        params = scattering.get(mat.name)
        if params is None or mat.node_tree is None:
            continue
        rho, sigma, g = params
        nt = mat.node_tree
        for link in list(nt.links):
            if link.to_node.bl_idname == "ShaderNodeOutputMaterial" and link.to_socket.name == "Volume":
                nt.links.remove(link)
        pn = [n for n in nt.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled"][0]
        pn.subsurface_method = "RANDOM_WALK"
        inputs = {
            "Base Color": (*rho, 1.0),
            "Subsurface Weight": 1.0,
            "Subsurface Radius": [RADIUS_PER_MFP / max(s, 1e-12) for s in sigma],
            "Subsurface Scale": 1.0,
            "Subsurface Anisotropy": g,
            "Specular IOR Level": 0.0,
            "Transmission Weight": 0.0,
            "Metallic": 0.0,
        }
        for name, value in inputs.items():
            sock = pn.inputs[name]
            for link in list(sock.links):
                nt.links.remove(link)
            sock.default_value = value
        log.append(f"{mat.name}: subsurface random walk, radius {inputs['Subsurface Radius']}")


rg.align_materials = align_with_subsurface
rg.main(sys.argv[1:])
