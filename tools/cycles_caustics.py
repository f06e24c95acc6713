#!/usr/bin/env python3
"""A glTF scene in Blender Cycles (CPU) with Cycles' own tools for caustics
turned on: path guiding and manifold next-event estimation (MNEE), for the
caustic scenes of tools/compare_cycles.py (issue 45).

    VENV/bin/python tools/cycles_caustics.py MODEL.gltf [--guiding] [--mnee] -o OUT.exr \\
        --spp N --threads T [any other option of ../shared/cycles/render_gltf.py]

(VENV: the CPython 3.13 venv with `bpy` that ../shared/cycles/setup.sh
makes; RAYLAB_RENDER_GLTF overrides where render_gltf.py is.) The file is
rendered by ../shared/cycles/render_gltf.py (Blender's glTF importer, fair
settings: clamping off, light threshold 0, reflective and refractive
caustics on, punctual lights of radius 0), which turns path guiding off;
after its set-up this script changes only:

  --guiding  scene.cycles.use_guiding, use_surface_guiding and
             use_volume_guiding on, with Blender's defaults for the rest
             (guiding_training_samples 128, PARALLAX_AWARE_VMM,
             deterministic guiding): Cycles trains its guiding field during
             the first 128 samples of the render itself, so the training is
             counted in the render time (and at 16 or 64 spp every sample is
             a training sample).
  --mnee     manifold next-event estimation: every light gets
             light.cycles.is_caustics_light, every mesh object with a
             transmitting material (a Principled BSDF whose Transmission
             Weight is above 0: the glass and the water) gets
             object.cycles.is_caustics_caster, and every other mesh object
             object.cycles.is_caustics_receiver. (Cycles' MNEE finds
             refractive caustics only, through at most two smooth
             interfaces, cast on a receiver's diffuse surface: it does
             nothing for a mirror or a metal.)

Without either option this is render_gltf.py unchanged. Blender 5.2.3's API
names, checked: scene.cycles.use_guiding, use_surface_guiding,
use_volume_guiding, guiding_training_samples; object.cycles.
is_caustics_caster / is_caustics_receiver; light.cycles.is_caustics_light.
The notes of the JSON line say what was set.
"""
import sys

import cycles_peer

rg = cycles_peer.render_gltf()

argv = list(sys.argv[1:])
if not argv or argv[0].startswith("-") and argv[0] not in ("--guiding", "--mnee"):
    sys.exit(__doc__)
guiding = "--guiding" in argv
mnee = "--mnee" in argv
argv = [x for x in argv if x not in ("--guiding", "--mnee")]

align = rg.align_materials


def transmits(ob):
    for slot in ob.material_slots:
        mat = slot.material
        if not (mat and mat.node_tree):
            continue
        for pn in rg.principled_nodes(mat):
            t = pn.inputs["Transmission Weight"]
            if t.is_linked or t.default_value > 0.0:
                return True
    return False


def align_with_caustics(bpy, log):
    align(bpy, log)
    scene = bpy.context.scene
    cy = scene.cycles
    if guiding:
        cy.use_guiding = True
        cy.use_surface_guiding = True
        cy.use_volume_guiding = True
        log.append(f"guiding: on (surface, volume; {cy.guiding_training_samples} training "
                   f"samples, {cy.guiding_distribution_type}, deterministic "
                   f"{cy.use_deterministic_guiding})")
    if mnee:
        casters, receivers = [], []
        for ob in scene.objects:
            if ob.type != "MESH":
                continue
            if transmits(ob):
                ob.cycles.is_caustics_caster = True
                casters.append(ob.name)
            else:
                ob.cycles.is_caustics_receiver = True
                receivers.append(ob.name)
        lights = []
        for light in bpy.data.lights:
            light.cycles.is_caustics_light = True
            lights.append(light.name)
        if not casters:
            sys.exit("cycles_caustics.py: --mnee but no mesh has a transmitting material")
        log.append(f"mnee: casters {casters}, receivers {receivers}, lights {lights}")


rg.align_materials = align_with_caustics
rg.main(argv)
