"""Renders a scene exported by export_blender_scene with Blender's Cycles on the CPU.

    blender -b --factory-startup -P render_cycles.py -- SCENE_DIR/scene.json OUT.exr \
        --samples N[,N2,...] [--threads 2] [--seed 1] [--blender-defaults 1]

--blender-defaults 1 keeps Blender 3.4's factory light-path settings instead of the unbiased ones
below: indirect clamping at 10, light sampling threshold 0.01, 4 diffuse and 4 glossy bounces,
caustics off (what a user who only sets the sample count renders with).

Writes a linear 32-bit EXR (no view transform, no denoising, no clamping, box pixel filter, fixed
sample count) whose channels are the scene's XYZ-relative-to-E triples rendered channel by channel
(the exporter hands XYZ over as "RGB": Cycles multiplies colours per channel, so no colour space
enters). Prints one line "cycles: samples N threads T render_seconds S cpu_seconds C" for the
timing table (C: CPU time of the whole process during the render, all threads: a fairer cost than
wall time on a shared machine).
Several sample counts render one after the other from the same built scene (each a full Cycles
render: sync, BVH, samples); OUT.exr must then contain "{n}", replaced by the sample count.

Mapping from solo's scene (scene.json):
  * frame: solo's OpenCV camera frame (x right, y down, z forward) becomes Blender's world by
    (x, y, z) -> (x, -y, -z), a rotation; the Blender camera sits at the origin with identity
    rotation (looking down -Z, +Y up).
  * camera: square pixels only; lens / sensor_width = fx / width, principal point through
    shift_x = (width/2 - (cx + 0.5)) / max(w, h), shift_y = ((cy + 0.5) - height/2) / max(w, h)
    (solo's pixel i has its centre at coordinate i).
  * surfaces: Diffuse BSDF (roughness 0 = Lambert) coloured by a face-domain colour attribute,
    flat-shaded with the faces' geometric normals (the exporter drops solo's shading normals:
    README.md, "What is compared");
    emitting faces get an Emission shader (strength 1, colour = radiance from a face attribute,
    so emitted radiance equals solo's) added to the diffuse one, in their own material so that
    Cycles samples only them as mesh lights. Cycles' mesh emission is two-sided like solo's.
  * rectangle lights (headlights): AREA lights of the same size and orientation, invisible to the
    camera, spread 180 degrees (solo's hemisphere), power P = 4 * radiance * area: Blender 3.4
    turns an area light's power into radiance P / (4 area), not P / (pi area). Measured with the
    plane-area scene: P = pi L A gave a mean exactly pi / 4 (0.7852) of solo's.
"""

import json
import math
import os
import sys
import time

from array import array

import bpy
from mathutils import Matrix, Vector


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(argv) < 2:
        raise SystemExit("usage: blender -b -P render_cycles.py -- scene.json out.exr --samples N[,N2...] "
                         "[--threads T] [--seed S]")
    options = {"scene": argv[0], "output": argv[1], "samples": [16], "threads": 2, "seed": 1, "blender-defaults": 0}
    rest = argv[2:]
    for i in range(0, len(rest), 2):
        key = rest[i].lstrip("-")
        if key not in ("samples", "threads", "seed", "blender-defaults") or i + 1 >= len(rest):
            raise SystemExit("render_cycles.py: unknown or incomplete option " + rest[i])
        options[key] = [int(n) for n in rest[i + 1].split(",")] if key == "samples" else int(rest[i + 1])
    if len(options["samples"]) > 1 and "{n}" not in options["output"]:
        raise SystemExit("render_cycles.py: several sample counts need {n} in the output name")
    return options


def to_blender(v):
    return (v[0], -v[1], -v[2])


def attribute_node(nodes, name):
    node = nodes.new("ShaderNodeAttribute")
    node.attribute_type = "GEOMETRY"
    node.attribute_name = name
    return node


def make_material(name, emitting):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    output = nodes.new("ShaderNodeOutputMaterial")
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Roughness"].default_value = 0.0
    links.new(attribute_node(nodes, "reflectance").outputs["Color"], diffuse.inputs["Color"])
    if emitting:
        emission = nodes.new("ShaderNodeEmission")
        emission.inputs["Strength"].default_value = 1.0
        links.new(attribute_node(nodes, "emission").outputs["Color"], emission.inputs["Color"])
        add = nodes.new("ShaderNodeAddShader")
        links.new(diffuse.outputs["BSDF"], add.inputs[0])
        links.new(emission.outputs["Emission"], add.inputs[1])
        links.new(add.outputs["Shader"], output.inputs["Surface"])
    else:
        links.new(diffuse.outputs["BSDF"], output.inputs["Surface"])
    return material


def read_array(path, typecode):
    values = array(typecode)
    with open(path, "rb") as f:
        values.frombytes(f.read())
    return values


def build_mesh(scene_dir, spec):
    m = spec["mesh"]
    vertices = read_array(os.path.join(scene_dir, m["vertices"]), "f")
    faces = read_array(os.path.join(scene_dir, m["faces"]), "I")
    reflectance = read_array(os.path.join(scene_dir, m["face_reflectance"]), "f")
    emission = read_array(os.path.join(scene_dir, m["face_emission"]), "f")
    n_vertices, n_faces = m["vertex_count"], m["face_count"]
    assert len(vertices) == 3 * n_vertices and len(faces) == 3 * n_faces
    assert len(reflectance) == 3 * n_faces and len(emission) == 3 * n_faces
    # (x, y, z) -> (x, -y, -z); strided slices, since per-element Python loops take minutes on
    # a 1080p depth mesh (millions of faces).
    for axis in (1, 2):
        vertices[axis::3] = array("f", (-c for c in vertices[axis::3]))

    mesh = bpy.data.meshes.new("solo_mesh")
    mesh.vertices.add(n_vertices)
    mesh.vertices.foreach_set("co", vertices)
    mesh.loops.add(3 * n_faces)
    mesh.loops.foreach_set("vertex_index", array("i", faces))
    mesh.polygons.add(n_faces)
    mesh.polygons.foreach_set("loop_start", array("i", range(0, 3 * n_faces, 3)))
    mesh.polygons.foreach_set("loop_total", array("i", [3]) * n_faces)
    mesh.update()
    if len(mesh.polygons) != n_faces:
        raise SystemExit("render_cycles.py: Blender dropped faces of the mesh")

    emitting = array("i", map(lambda x, y, z: 1 if max(x, y, z) > 0 else 0,
                               emission[0::3], emission[1::3], emission[2::3]))
    mesh.polygons.foreach_set("material_index", emitting)
    mesh.polygons.foreach_set("use_smooth", [False] * n_faces)
    for name, values in (("reflectance", reflectance), ("emission", emission)):
        attribute = mesh.attributes.new(name, "FLOAT_COLOR", "FACE")
        rgba = array("f", [1.0]) * (4 * n_faces)
        for channel in range(3):
            rgba[channel::4] = values[channel::3]
        attribute.data.foreach_set("color", rgba)
    mesh.materials.append(make_material("surface", False))
    mesh.materials.append(make_material("emitter", True))
    obj = bpy.data.objects.new("solo_mesh", mesh)
    bpy.context.scene.collection.objects.link(obj)
    return sum(emitting)


def add_rectangle_light(index, light):
    u = Vector(to_blender(light["edge_u"]))
    v = Vector(to_blender(light["edge_v"]))
    n = Vector(to_blender(light["normal"]))
    size_u, size_v = u.length, v.length
    data = bpy.data.lights.new("headlight%d" % index, type="AREA")
    data.shape = "RECTANGLE"
    # A Blender area light emits along its local -Z: local X = v, Y = u gives X x Y = -n.
    data.size, data.size_y = size_v, size_u
    data.spread = min(float(light["spread_rad"]), math.pi)
    power = [4.0 * c * size_u * size_v for c in light["radiance"]]
    data.energy = max(power)
    data.color = tuple(c / max(power) for c in power)
    obj = bpy.data.objects.new("headlight%d" % index, data)
    x, y, z = v / size_v, u / size_u, -n
    c = to_blender(light["centre"])
    obj.matrix_world = Matrix(((x[0], y[0], z[0], c[0]),
                               (x[1], y[1], z[1], c[1]),
                               (x[2], y[2], z[2], c[2]),
                               (0.0, 0.0, 0.0, 1.0)))
    obj.visible_camera = False
    bpy.context.scene.collection.objects.link(obj)


def setup_camera(spec):
    c = spec["camera"]
    if abs(c["fx"] - c["fy"]) > 1e-6 * c["fx"]:
        raise SystemExit("render_cycles.py: only square pixels (fx == fy)")
    w, h = c["width"], c["height"]
    data = bpy.data.cameras.new("camera")
    data.sensor_fit = "HORIZONTAL"
    data.sensor_width = 36.0
    data.lens = c["fx"] * 36.0 / w
    data.shift_x = (w / 2.0 - (c["cx"] + 0.5)) / max(w, h)
    data.shift_y = ((c["cy"] + 0.5) - h / 2.0) / max(w, h)
    data.clip_start = 0.01
    data.clip_end = 10000.0
    obj = bpy.data.objects.new("camera", data)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.scene.camera = obj
    return w, h


def main():
    setup_start = time.time()
    options = parse_args()
    scene_dir = os.path.dirname(os.path.abspath(options["scene"]))
    with open(options["scene"]) as f:
        spec = json.load(f)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    emitting = build_mesh(scene_dir, spec)
    for i, light in enumerate(spec["rectangle_lights"]):
        add_rectangle_light(i, light)
    w, h = setup_camera(spec)

    world = bpy.data.worlds.new("black")
    world.use_nodes = False
    world.color = (0.0, 0.0, 0.0)
    scene.world = world

    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    cycles.seed = options["seed"]
    if not options["blender-defaults"]:
        bounces = int(spec.get("max_bounces", 12))
        cycles.max_bounces = bounces
        cycles.diffuse_bounces = bounces
        cycles.glossy_bounces = bounces
        cycles.transmission_bounces = bounces
        cycles.transparent_max_bounces = bounces
        cycles.sample_clamp_direct = 0.0
        cycles.sample_clamp_indirect = 0.0
        cycles.light_sampling_threshold = 0.0
        cycles.caustics_reflective = True
        cycles.caustics_refractive = True
    print("cycles light paths: max %d diffuse %d glossy %d, clamp direct %g indirect %g, light threshold %g, "
          "caustics %s" % (cycles.max_bounces, cycles.diffuse_bounces, cycles.glossy_bounces,
                           cycles.sample_clamp_direct, cycles.sample_clamp_indirect,
                           cycles.light_sampling_threshold, cycles.caustics_reflective))
    cycles.pixel_filter_type = "BOX"
    cycles.filter_width = 1.0
    scene.render.threads_mode = "FIXED"
    scene.render.threads = options["threads"]
    scene.render.resolution_x, scene.render.resolution_y = w, h
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.color_mode = "RGB"
    scene.render.image_settings.exr_codec = "ZIP"
    scene.render.use_file_extension = False
    # Several sample counts: keep the synced scene and its BVH between the renders (only the first
    # render's time then includes them).
    scene.render.use_persistent_data = len(options["samples"]) > 1

    print("cycles: scene built in %.1f s (%d faces, %d emitting)" %
          (time.time() - setup_start, spec["mesh"]["face_count"], emitting), flush=True)
    for samples in options["samples"]:
        cycles.samples = samples
        scene.render.filepath = os.path.abspath(options["output"].replace("{n}", str(samples)))
        start, cpu_start = time.time(), time.process_time()
        bpy.ops.render.render(write_still=True)
        seconds, cpu_seconds = time.time() - start, time.process_time() - cpu_start
        print("cycles: samples %d threads %d render_seconds %.3f cpu_seconds %.3f emitting_faces %d" %
              (samples, options["threads"], seconds, cpu_seconds, emitting), flush=True)


main()
