"""Renders a glTF scene with Blender's Cycles, set up to compute what Tessera's `ptnee` computes.

Run by Blender (tools/cycles_compare.py does), not by python3:
    blender -b --factory-startup -noaudio -P tools/cycles_render.py -- SCENE.gltf OUT.exr \
        --spp N [--seed S] [--resolution WxH] [--threads T]
Prints one line `cycles-json {...}` with the render's seconds (the render operator alone: scene
sync, BVH build and sampling; not Blender's start-up or the glTF import).

The scene: glTF import (camera, meshes), every material replaced by what Tessera evaluates for a
rough dielectric-free glTF material with specularFactor 0: a Lambertian BSDF of baseColorFactor,
plus one-sided emission of emissiveFactor x emissiveStrength (KHR_materials_emissive_strength),
both read from the glTF file itself. Cycles: CPU path tracing with next-event estimation and MIS
(its default for emissive meshes), no clamping, no denoising, no adaptive sampling, a 1-pixel box
filter (Tessera's), a black world, bounce limits high enough that Russian roulette ends paths.
Only diffuse and emissive materials are supported: anything else is refused.
"""
import argparse
import json
import sys
import time

import bpy
import numpy

# Debian's Blender 3.4 glTF importer calls numpy.bool, an alias NumPy 1.24 removed; it meant bool.
if "bool" not in numpy.__dict__:
    numpy.bool = bool


def parse():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="cycles_render.py")
    p.add_argument("scene")
    p.add_argument("out")
    p.add_argument("--spp", type=int, required=True)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--resolution", default="256x256")
    p.add_argument("--threads", type=int, default=1)
    return p.parse_args(argv)


def gltf_materials(path):
    with open(path) as f:
        g = json.load(f)
    out = {}
    for m in g.get("materials", []):
        pbr = m.get("pbrMetallicRoughness", {})
        ext = m.get("extensions", {})
        if pbr.get("metallicFactor", 1.0) != 0.0 or ext.get("KHR_materials_specular", {}).get("specularFactor", 1.0) != 0.0:
            sys.exit(f"cycles_render.py: {path}: material '{m.get('name')}' is not pure diffuse "
                     "(metallicFactor and KHR_materials_specular.specularFactor must be 0)")
        strength = ext.get("KHR_materials_emissive_strength", {}).get("emissiveStrength", 1.0)
        out[m["name"]] = (pbr.get("baseColorFactor", [1, 1, 1, 1])[:3], [c * strength for c in m.get("emissiveFactor", [0, 0, 0])],
                          bool(m.get("doubleSided", False)))
    return out


def diffuse_emissive(mat, base, emission, two_sided):
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (*base, 1.0)
    diffuse.inputs["Roughness"].default_value = 0.0  # Lambert, not Oren-Nayar
    shader = diffuse.outputs["BSDF"]
    if any(c > 0 for c in emission):
        em = nt.nodes.new("ShaderNodeEmission")
        em.inputs["Color"].default_value = (*emission, 1.0)
        em.inputs["Strength"].default_value = 1.0
        emitted = em.outputs["Emission"]
        if not two_sided:
            # glTF emission is one-sided unless doubleSided: none from the back face (as Tessera).
            geo = nt.nodes.new("ShaderNodeNewGeometry")
            black = nt.nodes.new("ShaderNodeEmission")
            black.inputs["Strength"].default_value = 0.0
            mix = nt.nodes.new("ShaderNodeMixShader")
            nt.links.new(geo.outputs["Backfacing"], mix.inputs["Fac"])
            nt.links.new(em.outputs["Emission"], mix.inputs[1])
            nt.links.new(black.outputs["Emission"], mix.inputs[2])
            emitted = mix.outputs["Shader"]
        add = nt.nodes.new("ShaderNodeAddShader")
        nt.links.new(shader, add.inputs[0])
        nt.links.new(emitted, add.inputs[1])
        shader = add.outputs["Shader"]
    nt.links.new(shader, out.inputs["Surface"])


def main():
    a = parse()
    w, h = (int(v) for v in a.resolution.lower().split("x"))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=a.scene)
    scene = bpy.context.scene
    mats = gltf_materials(a.scene)
    for mat in bpy.data.materials:
        key = mat.name if mat.name in mats else mat.name.split(".")[0]
        if key not in mats:
            continue
        diffuse_emissive(mat, *mats[key])
    cams = [o for o in scene.objects if o.type == "CAMERA"]
    if not cams:
        sys.exit(f"cycles_render.py: {a.scene}: no camera")
    scene.camera = cams[0]

    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = world

    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = w, h, 100
    r.threads_mode = "FIXED"
    r.threads = a.threads
    r.use_persistent_data = False
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_depth = "32"
    r.image_settings.exr_codec = "ZIP"
    r.filepath = a.out
    r.use_file_extension = False
    c = scene.cycles
    c.device = "CPU"
    c.samples = a.spp
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.seed = a.seed
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0
    c.max_bounces = c.diffuse_bounces = 1024
    c.glossy_bounces = c.transmission_bounces = c.transparent_max_bounces = c.volume_bounces = 1024
    c.caustics_reflective = c.caustics_refractive = True
    c.filter_type = "BOX"
    c.filter_width = 1.0
    c.pixel_filter_type = "BOX"
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0

    t0 = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    seconds = time.perf_counter() - t0
    print("cycles-json " + json.dumps({"spp": a.spp, "seed": a.seed, "seconds": seconds, "threads": a.threads,
                                         "sampling_pattern": str(getattr(c, "sampling_pattern", "?")),
                                         "blender": bpy.app.version_string, "out": a.out}), flush=True)


main()
