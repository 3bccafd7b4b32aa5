#!/bin/sh
# Writes the seed corpora of the fuzz targets into tests/fuzz/corpus/<target>/: a few tiny valid
# files per reader (maps of each pixel type, meshes in each encoding, a manifest, a light record,
# an illuminant table, a config file). Needs python3 and a release solo binary (for EXR, TIFF
# and the light record): tests/fuzz/make_corpus.sh [path/to/solo]
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
solo=${1:-$root/build/release/tools/solo}
corpus=$here/corpus
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
rm -rf "$corpus"
for t in scene_manifest map_png map_exr map_tiff map_npy map_pfm mesh_ply mesh_off mesh_obj mesh_stl \
         light_record illuminant_table night_config; do
  mkdir -p "$corpus/$t"
done

# NPY, PFM and PNG written directly; meshes in every encoding.
python3 - "$corpus" "$work" <<'PY'
import struct, sys, zlib
corpus, work = sys.argv[1], sys.argv[2]
W, H = 4, 3

def npy(path, descr, shape, values, fmt):
    header = "{'descr': '%s', 'fortran_order': False, 'shape': %s, }" % (descr, shape)
    header += " " * (63 - (len(header) + 10) % 64) + "\n"
    with open(path, "wb") as f:
        f.write(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode())
        f.write(struct.pack("<%d%s" % (len(values), fmt), *values))

n = W * H
npy(f"{corpus}/map_npy/depth_f4.npy", "<f4", "(3, 4)", [1.0 + i for i in range(n)], "f")
npy(f"{corpus}/map_npy/depth_f8.npy", "<f8", "(3, 4)", [0.5 * i for i in range(n)], "d")
npy(f"{corpus}/map_npy/labels_u1.npy", "|u1", "(3, 4)", [i % 30 for i in range(n)], "B")
npy(f"{corpus}/map_npy/depth_u2.npy", "<u2", "(3, 4)", [100 * i for i in range(n)], "H")
npy(f"{corpus}/map_npy/labels_i8.npy", "<i8", "(3, 4)", [26000 + i for i in range(n)], "q")
npy(f"{corpus}/map_npy/normals_f4.npy", "<f4", "(3, 4, 3)", [0.0, 0.0, -1.0] * n, "f")
npy(f"{work}/depth.npy", "<f4", "(3, 4)", [1.0 + i for i in range(n)], "f")
npy(f"{work}/normals.npy", "<f4", "(3, 4, 3)", [0.0, 0.6, -0.8] * n, "f")

with open(f"{corpus}/map_pfm/gray.pfm", "wb") as f:
    f.write(b"Pf\n4 3\n-1.0\n" + struct.pack("<12f", *[1.0 + i for i in range(n)]))
with open(f"{corpus}/map_pfm/rgb.pfm", "wb") as f:
    f.write(b"PF\n4 3\n1.0\n" + struct.pack(">36f", *([0.0, 0.0, -1.0] * n)))

def png(path, colour_type, bit_depth, channels, interlace=0):
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    sample = bit_depth // 8
    rows = b"".join(b"\0" + bytes((x * 37 + y * 11 + c) % 256 for x in range(W * channels * sample) for c in [0])
                    for y in range(H))
    ihdr = struct.pack(">IIBBBBB", W, H, bit_depth, colour_type, 0, 0, interlace)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))

png(f"{corpus}/map_png/rgb8.png", 2, 8, 3)
png(f"{corpus}/map_png/gray16.png", 0, 16, 1)
png(f"{corpus}/map_png/gray8.png", 0, 8, 1)
png(f"{corpus}/map_png/rgb16.png", 2, 16, 3)
png(f"{corpus}/map_png/rgba8.png", 6, 8, 4)

vertices = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
faces = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
with open(f"{corpus}/mesh_off/tetra.off", "w") as f:
    f.write("OFF\n4 4 0\n" + "".join("%g %g %g\n" % v for v in vertices) + "".join("3 %d %d %d\n" % t for t in faces))
with open(f"{corpus}/mesh_obj/tetra.obj", "w") as f:
    f.write("".join("v %g %g %g\n" % v for v in vertices) + "".join("f %d %d %d\n" % tuple(i + 1 for i in t) for t in faces))
with open(f"{corpus}/mesh_ply/ascii.ply", "w") as f:
    f.write("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
            + "".join("%g %g %g\n" % v for v in vertices) + "".join("3 %d %d %d\n" % t for t in faces))
with open(f"{corpus}/mesh_ply/binary.ply", "wb") as f:
    f.write(b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
            b"property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n")
    for v in vertices: f.write(struct.pack("<3f", *v))
    for t in faces: f.write(struct.pack("<B3i", 3, *t))
def normal(t):
    return (0.0, 0.0, 0.0)
with open(f"{corpus}/mesh_stl/ascii.stl", "w") as f:
    f.write("solid tetra\n")
    for t in faces:
        f.write(" facet normal 0 0 0\n  outer loop\n" + "".join("   vertex %g %g %g\n" % vertices[i] for i in t)
                + "  endloop\n endfacet\n")
    f.write("endsolid tetra\n")
with open(f"{corpus}/mesh_stl/binary.stl", "wb") as f:
    f.write(b"binary tetra".ljust(80, b" ") + struct.pack("<I", len(faces)))
    for t in faces:
        f.write(struct.pack("<3f", *normal(t)))
        for i in t: f.write(struct.pack("<3f", *vertices[i]))
        f.write(b"\0\0")

with open(f"{corpus}/illuminant_table/table.csv", "w") as f:
    f.write('category,x,y,source\nstreet_light_LT,0.53278,0.41517,"HPS"\nvehicle_light,0.4476,0.4074,"A"\n')
with open(f"{corpus}/night_config/config.toml", "w") as f:
    f.write('[night]\npreset = "draft"\nseed = 7\nmin-spp = 2\nmax-spp = 8\nrelative-error = 0.1\n'
            'refine = false\n16bit = true\noutput = "n.png"\nlights = "l.json"\nsensor-white = [1.0, 2.0, 3.0]\n')
with open(f"{corpus}/night_config/config.ini", "w") as f:
    f.write("[night]\nglare-threshold=0.5\nno-refine=true\n")
PY

# EXR and TIFF through solo's own writers; a synthetic scene's manifest and light record.
"$solo" convert depth "$work/depth.npy" "$corpus/map_exr/depth.exr" > /dev/null
"$solo" convert normals "$work/normals.npy" "$corpus/map_exr/normals.exr" > /dev/null
"$solo" convert depth "$work/depth.npy" "$corpus/map_tiff/depth.tif" > /dev/null
"$solo" convert normals "$work/normals.npy" "$corpus/map_tiff/normals.tif" > /dev/null
"$solo" synth -o "$work/scene" --size 32x18 --seed 1 > /dev/null
cp "$work/scene/scene.json" "$corpus/scene_manifest/synth.json"
cp "$work/scene/gt/scene.json" "$corpus/scene_manifest/ground_truth.json"
printf '{"image": "day.png", "depth": "d.npy", "depth_scale": 0.01}\n' > "$corpus/scene_manifest/minimal.json"
"$solo" lights "$work/scene/scene.json" -o "$work/lights.json" > /dev/null
# The first lights, groups and draws only: a seed of a few KB mutates faster.
python3 - "$work/lights.json" "$corpus/light_record/lights.json" <<'PY'
import json, sys
record = json.load(open(sys.argv[1]))
record.pop("units", None)
record["scene"] = "scene/scene.json"  # paths relative: the corpus holds no machine's paths
record["illuminant_table"] = "data/illuminants/night_illuminants.csv"
record["groups"] = record["groups"][:2]
ids = {group["id"] for group in record["groups"]}
record["lights"] = [light for light in record["lights"] if light["group"] in ids]
record["draws"] = [draw for draw in record["draws"] if draw["group"] in ids]
json.dump(record, open(sys.argv[2], "w"), indent=1)
PY
"$solo" lights "$work/scene/scene.json" --from "$corpus/light_record/lights.json" -o "$work/check.json" > /dev/null
ls -R "$corpus" | head -60
