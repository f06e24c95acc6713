"""The Cycles peer, ../shared/cycles/render_gltf.py, as a module for the
tools that extend it (tools/cycles_fog.py, tools/cycles_subsurface.py):
they replace its `align_materials` step and call its `main`.
RAYLAB_RENDER_GLTF overrides where render_gltf.py is."""
import importlib.util
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def render_gltf():
    """render_gltf.py, loaded (its folder gets no __pycache__)."""
    path = os.environ.get("RAYLAB_RENDER_GLTF",
                          os.path.join(HERE, "..", "..", "shared", "cycles", "render_gltf.py"))
    if not os.path.isfile(path):
        sys.exit(f"{path} not found: ../shared (the Cycles peer) must sit beside the project "
                 "folder, or set RAYLAB_RENDER_GLTF")
    sys.dont_write_bytecode = True
    spec = importlib.util.spec_from_file_location("render_gltf", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
