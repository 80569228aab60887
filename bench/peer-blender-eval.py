"""Blender's baked light map at the points of a `mebake reference` JSON (bench/peer-blender.sh).

Run inside Blender (it reads the EXR):
  blender -b --factory-startup --python-exit-code 1 --python bench/peer-blender-eval.py -- \
      REF.json MESH.ply UV.npy LIGHTMAP.exr ALBEDO OUT.json

Each reference point names its input triangle and the input vertices of its corners
(`face`, `vertex_ids`, `barycentric`). The light-map uv is interpolated from blender_bake.py's
per-corner dump (--dump-uv), the EXR is sampled bilinearly (texel centres at (i + 0.5) / res),
and the DIFFUSE pass (irradiance / pi, docs in ../shared/peers/README.md) becomes
B = albedo * pi * texel. Points whose triangle is not an input triangle with the same
vertices (hole fill, or a repaired triangle) are skipped and counted. The error uses the same
definitions as `mebake compare` (docs/accuracy.md).
"""
import bpy
import json, math, sys
import numpy as np

argv = sys.argv[sys.argv.index("--") + 1:]
ref_path, mesh_path, uv_path, exr_path, albedo, out_path = argv[0], argv[1], argv[2], argv[3], float(argv[4]), argv[5]


def read_faces(path):
    with open(path, "rb") as f:
        header = []
        while True:
            l = f.readline().decode("ascii", "replace").strip()
            header.append(l)
            if l == "end_header":
                break
        nv = nf = 0
        vprops = []
        cur = None
        for l in header:
            t = l.split()
            if t[:2] == ["element", "vertex"]:
                nv, cur = int(t[2]), "v"
            elif t[:2] == ["element", "face"]:
                nf, cur = int(t[2]), "f"
            elif t and t[0] == "property" and cur == "v":
                vprops.append(t[1])
        size = {"float": 4, "float32": 4, "double": 8, "uchar": 1, "uint8": 1, "int": 4, "uint": 4}
        f.read(nv * sum(size[p] for p in vprops))
        dt = np.dtype([("n", "u1"), ("i", "<i4", (3,))])
        arr = np.frombuffer(f.read(dt.itemsize * nf), dtype=dt, count=nf)
        return arr["i"]


faces = read_faces(mesh_path)
uv = np.load(uv_path)
if uv.shape[0] != len(faces):
    sys.exit("peer-blender-eval: Blender kept %d of %d faces; cannot map points" % (uv.shape[0], len(faces)))
img = bpy.data.images.load(exr_path)
w, h = img.size
px = np.empty(w * h * img.channels, np.float32)
img.pixels.foreach_get(px)
px = px.reshape(h, w, img.channels)[:, :, :3]  # row 0 = bottom (v = 0)


def sample(u, v):
    x, y = u * w - 0.5, v * h - 0.5
    x0, y0 = int(math.floor(x)), int(math.floor(y))
    fx, fy = x - x0, y - y0
    acc = np.zeros(3)
    for dy, wy in ((0, 1 - fy), (1, fy)):
        for dx, wx in ((0, 1 - fx), (1, fx)):
            xi, yi = min(max(x0 + dx, 0), w - 1), min(max(y0 + dy, 0), h - 1)
            acc += wx * wy * px[yi, xi]
    return acc


ref = json.load(open(ref_path))
B, R, S = [], [], []
skipped = 0
for p in ref["points"]:
    f = p.get("face")
    if f is None or f >= len(faces):
        skipped += 1
        continue
    corners = list(faces[f])
    ids = p["vertex_ids"]
    if sorted(ids) != sorted(corners):
        skipped += 1
        continue
    t = np.zeros(2)
    for k in range(3):
        t += p["barycentric"][k] * uv[f, corners.index(ids[k])]
    B.append(albedo * math.pi * sample(t[0], t[1]))
    R.append(p["B"])
    S.append(p["B_se"])
B, R, S = np.array(B), np.array(R), np.array(S)
level = math.sqrt((R * R).sum(1).mean())
d = np.sqrt(((B - R) ** 2).sum(1))
rms = math.sqrt((d * d).mean()) / level
noise = math.sqrt((S * S).sum(1).mean()) / level
out = {"points": int(len(R)), "skipped": skipped, "relative_rms": rms,
       "relative_max": float(d.max()) / level, "reference_noise_rms": noise,
       "corrected_rms": math.sqrt(max(0.0, rms * rms - noise * noise)),
       "median_relative": float(np.median(d / np.maximum(np.sqrt((R * R).sum(1)), 1e-3 * level))),
       "mean_bake": float(np.sqrt((B * B).sum(1)).mean()), "mean_reference": float(np.sqrt((R * R).sum(1)).mean())}
json.dump(out, open(out_path, "w"), indent=1)
print("peer-blender-eval:", json.dumps(out))
