# Binary PLY in and out with the standard library only (Debian's Blender has no numpy):
# triangles out to mebake, and back the baked mesh that `mebake export --mesh x.ply` writes
# (float x y z nx ny nz s t per vertex, triangles).
import struct
import sys
from array import array


def _le(a):
    """array `a` in little-endian byte order (PLY's), in place."""
    if sys.byteorder != "little":
        a.byteswap()
    return a


def write_triangles(path, positions, triangles):
    """positions: array('f') of x y z; triangles: array('i') of 3 indices each."""
    nv, nf = len(positions) // 3, len(triangles) // 3
    header = ("ply\nformat binary_little_endian 1.0\ncomment exported by the mebake Blender add-on\n"
              f"element vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n"
              f"element face {nf}\nproperty list uchar int vertex_indices\nend_header\n")
    face = struct.Struct("<B3i")
    faces = bytearray(face.size * nf)
    for k in range(nf):
        face.pack_into(faces, face.size * k, 3, triangles[3 * k], triangles[3 * k + 1],
                       triangles[3 * k + 2])
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(_le(array("f", positions)).tobytes())
        f.write(faces)


_SIZES = {"float": ("f", 4), "float32": ("f", 4), "double": ("d", 8), "float64": ("d", 8),
          "uchar": ("B", 1), "uint8": ("B", 1), "char": ("b", 1), "int8": ("b", 1),
          "ushort": ("H", 2), "uint16": ("H", 2), "short": ("h", 2), "int16": ("h", 2),
          "uint": ("I", 4), "uint32": ("I", 4), "int": ("i", 4), "int32": ("i", 4)}


def read_baked_mesh(path):
    """Returns (positions array('f') x y z..., uv array('f') s t..., triangles array('i'))
    of a binary little-endian PLY whose faces are all triangles (what mebake writes).
    Raises ValueError naming the file."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.find(b"end_header\n")
    if not data.startswith(b"ply\n") or end < 0:
        raise ValueError(f"{path}: not a PLY file")
    lines = data[:end].decode("ascii", "replace").splitlines()
    if "format binary_little_endian 1.0" not in lines:
        raise ValueError(f"{path}: expected a binary little-endian PLY")
    elements, current = [], None
    for line in lines:
        words = line.split()
        if words[:1] == ["element"]:
            current = (words[1], int(words[2]), [])
            elements.append(current)
        elif words[:1] == ["property"] and current is not None:
            current[2].append(words[1:])
    offset = end + len(b"end_header\n")
    positions = uv = tris = None
    for name, count, props in elements:
        if name == "vertex":
            fmt = "<" + "".join(_SIZES[p[0]][0] for p in props)
            names = [p[1] for p in props]
            for needed in ("x", "y", "z", "s", "t"):
                if needed not in names:
                    raise ValueError(f"{path}: the vertices have no '{needed}'")
            rec = struct.Struct(fmt)
            cols = [names.index(c) for c in ("x", "y", "z")]
            uvc = [names.index(c) for c in ("s", "t")]
            positions, uv = array("f"), array("f")
            for v in rec.iter_unpack(data[offset:offset + rec.size * count]):
                positions.extend((v[cols[0]], v[cols[1]], v[cols[2]]))
                uv.extend((v[uvc[0]], v[uvc[1]]))
            offset += rec.size * count
        elif name == "face":
            if len(props) != 1 or props[0][0] != "list":
                raise ValueError(f"{path}: expected one list property per face")
            rec = struct.Struct("<" + _SIZES[props[0][1]][0] + "3" + _SIZES[props[0][2]][0])
            tris = array("i")
            for n, a, b, c in rec.iter_unpack(data[offset:offset + rec.size * count]):
                if n != 3:
                    raise ValueError(f"{path}: only triangles are read")
                tris.extend((a, b, c))
            offset += rec.size * count
        else:
            raise ValueError(f"{path}: unexpected element '{name}'")
    if positions is None or tris is None:
        raise ValueError(f"{path}: no vertices or faces")
    nv = len(positions) // 3
    if tris and (min(tris) < 0 or max(tris) >= nv):
        raise ValueError(f"{path}: a face index is out of range")
    return positions, uv, tris
