#!/usr/bin/env python3
"""A glTF scene in fog in Blender Cycles (CPU), as raylab's `--fog DENSITY`
draws it, for the speed comparison (tools/compare_cycles_fog.py).

    VENV/bin/python tools/cycles_fog.py MODEL.gltf --fog DENSITY -o OUT.exr --spp N --threads T \\
        [any other option of ../shared/cycles/render_gltf.py]

(VENV: the CPython 3.13 venv with `bpy` that ../shared/cycles/setup.sh
makes; RAYLAB_RENDER_GLTF overrides where render_gltf.py is.) The file is
rendered by ../shared/cycles/render_gltf.py (Blender's glTF importer, fair
settings: clamping off, light threshold 0, volume bounces as many as the
others), and after the import a box is added over the bounding box of the
scene's meshes, as raylab's fog fills it: a Volume Scatter shader of
Density DENSITY (extinction per unit, all of it scattering: raylab's
default white fog), Anisotropy 0, no surface. The box is flattened no more
than raylab's: an axis thinner than a thousandth of the box's diagonal is
widened to that.
"""
import os
import sys

import cycles_peer

rg = cycles_peer.render_gltf()

argv = list(sys.argv[1:])
if "--fog" not in argv:
    sys.exit(__doc__)
k = argv.index("--fog")
try:
    density = float(argv[k + 1])
except (IndexError, ValueError):
    sys.exit("cycles_fog.py: --fog needs a density (extinction per scene unit)")
del argv[k:k + 2]
if not density >= 0.0:
    sys.exit(f"cycles_fog.py: fog density {density} must be >= 0")

align = rg.align_materials


def align_with_fog(bpy, log):
    align(bpy, log)
    from mathutils import Vector
    lo = Vector((float("inf"),) * 3)
    hi = Vector((float("-inf"),) * 3)
    for ob in bpy.data.objects:
        if ob.type != "MESH":
            continue
        for corner in ob.bound_box:
            p = ob.matrix_world @ Vector(corner)
            lo = Vector(map(min, lo, p))
            hi = Vector(map(max, hi, p))
    if lo.x > hi.x:
        sys.exit("cycles_fog.py: the scene has no mesh to fill with fog")
    thin = 1e-3 * max((hi - lo).length, 1e-3)
    hi = Vector(max(h, l + thin) for l, h in zip(lo, hi))
    verts = [(x, y, z) for x in (lo.x, hi.x) for y in (lo.y, hi.y) for z in (lo.z, hi.z)]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    mesh = bpy.data.meshes.new("raylab_fog")
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    ob = bpy.data.objects.new("raylab_fog", mesh)
    bpy.context.scene.collection.objects.link(ob)
    mat = bpy.data.materials.new("raylab_fog")
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    scatter = nt.nodes.new("ShaderNodeVolumeScatter")
    scatter.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    scatter.inputs["Density"].default_value = density
    scatter.inputs["Anisotropy"].default_value = 0.0
    nt.links.new(scatter.outputs["Volume"], out.inputs["Volume"])
    try:
        mat.cycles.homogeneous_volume = True
    except AttributeError:
        pass
    mesh.materials.append(mat)
    log.append(f"fog: Volume Scatter density {density} over {tuple(lo)} .. {tuple(hi)}")


rg.align_materials = align_with_fog
rg.main(argv)
