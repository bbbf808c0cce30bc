#!/usr/bin/python3
"""Makes gradel's small sample inputs (committed next to this script; re-run to regenerate).

    /usr/bin/python3 samples/make_samples.py [OUTDIR]

Only numpy and the standard library (gzip, struct). Every file is deterministic (fixed seed,
gzip mtime 0), so re-running gives the same bytes.

  torus.obj      a torus (R = 1, r = 0.4, 32 x 16 quads -> 1024 triangles), Wavefront OBJ
  torus.stl      the same torus, binary STL
  pawn.ply       a chess pawn made by turning a profile (48 segments), binary little-endian PLY
  torus.binvox   the torus voxelised analytically at 24 voxels across (a voxelised mesh)
  ct.nrrd        a 40^3 synthetic CT scan, int16 Hounsfield units, gzip encoding: air -1000,
                 a soft-tissue ellipsoid (~40 HU) around a bone-like bent cylinder (~1000 HU),
                 with noise; threshold 300 keeps the bone, -300 keeps the whole limb
  ct.nii.gz      the same scan as NIfTI-1, stored uint16 = HU + 1024 with scl_inter = -1024
  ct.raw         the scan's bone mask, 40^3 uint8 (0 / 1), headerless
  mushroom.vox   a 16 x 16 x 16 MagicaVoxel model (z-up): a stalk and a cap
  phantom.nrrd   a 24 x 12 x 24 label map, uint8, gzip encoding: a block of soft tissue (label 1)
                 holding a stiff ellipsoidal inclusion (label 2) just under its top face, centred
"""
import gzip
import io
import os
import struct
import sys

import numpy as np

OUT = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))


def write(name, data):
    with open(os.path.join(OUT, name), "wb") as f:
        f.write(data)


def gz(data):
    buf = io.BytesIO()
    with gzip.GzipFile(fileobj=buf, mode="wb", mtime=0, compresslevel=9) as f:
        f.write(data)
    return buf.getvalue()


# ---- meshes -------------------------------------------------------------------------------

def torus(R=1.0, r=0.4, nu=32, nv=16):
    """Vertices and outward-facing (counter-clockwise) triangles of a torus around y."""
    verts = []
    for i in range(nu):
        a = 2 * np.pi * i / nu
        for j in range(nv):
            b = 2 * np.pi * j / nv
            verts.append(((R + r * np.cos(b)) * np.cos(a), r * np.sin(b), (R + r * np.cos(b)) * np.sin(a)))
    tris = []
    for i in range(nu):
        for j in range(nv):
            p = i * nv + j
            q = ((i + 1) % nu) * nv + j
            p1 = i * nv + (j + 1) % nv
            q1 = ((i + 1) % nu) * nv + (j + 1) % nv
            tris += [(p, p1, q), (q, p1, q1)]
    v = np.array(verts)
    t = np.array(tris)
    # Orient outward: the signed volume must be positive.
    vol = np.einsum("ij,ij->i", v[t[:, 0]], np.cross(v[t[:, 1]], v[t[:, 2]])).sum() / 6
    if vol < 0:
        t = t[:, [0, 2, 1]]
    return v, t


def lathe(profile, n=48):
    """Revolves (radius, height) points about y; caps the ends with a centre vertex."""
    verts = [(0.0, profile[0][1], 0.0)]
    for k in range(n):
        a = 2 * np.pi * k / n
        for rad, y in profile:
            verts.append((rad * np.cos(a), y, rad * np.sin(a)))
    verts.append((0.0, profile[-1][1], 0.0))
    m = len(profile)
    ring = lambda k, i: 1 + (k % n) * m + i
    tris = []
    top = len(verts) - 1
    for k in range(n):
        tris.append((0, ring(k + 1, 0), ring(k, 0)))
        for i in range(m - 1):
            a, b, c, d = ring(k, i), ring(k + 1, i), ring(k, i + 1), ring(k + 1, i + 1)
            tris += [(a, b, d), (a, d, c)]
        tris.append((top, ring(k, m - 1), ring(k + 1, m - 1)))
    v = np.array(verts)
    t = np.array(tris)
    vol = np.einsum("ij,ij->i", v[t[:, 0]], np.cross(v[t[:, 1]], v[t[:, 2]])).sum() / 6
    if vol < 0:
        t = t[:, [0, 2, 1]]
    return v, t


def obj_bytes(v, t):
    lines = ["# gradel sample: torus"] + ["v %.6f %.6f %.6f" % tuple(p) for p in v]
    lines += ["f %d %d %d" % tuple(x + 1 for x in tri) for tri in t]
    return ("\n".join(lines) + "\n").encode()


def stl_bytes(v, t):
    out = bytearray(b"gradel sample: binary STL".ljust(80, b" "))
    out += struct.pack("<I", len(t))
    for tri in t:
        a, b, c = v[tri[0]], v[tri[1]], v[tri[2]]
        nrm = np.cross(b - a, c - a)
        nrm = nrm / (np.linalg.norm(nrm) or 1)
        out += struct.pack("<12fH", *nrm, *a, *b, *c, 0)
    return bytes(out)


def ply_bytes(v, t):
    head = ("ply\nformat binary_little_endian 1.0\ncomment gradel sample: pawn\n"
            "element vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
            "element face %d\nproperty list uchar int vertex_indices\nend_header\n" % (len(v), len(t)))
    out = bytearray(head.encode())
    out += v.astype("<f4").tobytes()
    for tri in t:
        out += struct.pack("<B3i", 3, *tri)
    return bytes(out)


# ---- voxel formats ------------------------------------------------------------------------

def binvox_bytes(vox):
    """vox[x, y, z] boolean; binvox stores x slowest, then z, then y fastest."""
    d, h, w = vox.shape[0], vox.shape[2], vox.shape[1]
    flat = np.transpose(vox, (0, 2, 1)).reshape(-1).astype(np.uint8)
    runs = bytearray()
    i = 0
    while i < len(flat):
        j = i
        while j < len(flat) and flat[j] == flat[i] and j - i < 255:
            j += 1
        runs += bytes((flat[i], j - i))
        i = j
    head = "#binvox 1\ndim %d %d %d\ntranslate -1.4 -0.4 -1.4\nscale 2.8\ndata\n" % (d, h, w)
    return head.encode() + bytes(runs)


def vox_bytes(points, size):
    """points: (x, y, z, colour) tuples in MagicaVoxel's z-up frame."""
    def chunk(cid, content, children=b""):
        return cid + struct.pack("<ii", len(content), len(children)) + content + children
    size_c = chunk(b"SIZE", struct.pack("<3i", *size))
    xyzi = chunk(b"XYZI", struct.pack("<i", len(points)) + b"".join(struct.pack("<4B", *p) for p in points))
    palette = bytearray()
    for k in range(256):
        palette += bytes((200, 60 + k % 100, 40, 255))
    rgba = chunk(b"RGBA", bytes(palette))
    return b"VOX " + struct.pack("<i", 150) + chunk(b"MAIN", b"", size_c + xyzi + rgba)


def ct_volume(n=40, seed=6):
    """Hounsfield units on an n^3 grid, index [x, y, z]."""
    rng = np.random.default_rng(seed)
    c = (np.arange(n) + 0.5) / n * 2 - 1  # -1..1
    x, y, z = np.meshgrid(c, c, c, indexing="ij")
    hu = np.full((n, n, n), -1000.0)
    limb = (x / 0.55) ** 2 + (z / 0.5) ** 2 + (y / 0.9) ** 2 <= 1
    hu[limb] = 40
    # Bone: a cylinder along y bent a little (its axis drifts in x with y), hollow marrow.
    ax = 0.12 * y ** 2
    rr = np.sqrt((x - ax) ** 2 + z ** 2)
    bone = (rr <= 0.24) & (np.abs(y) <= 0.75)
    hu[bone] = 1100
    hu[bone & (rr <= 0.1)] = 300  # marrow, partly above a 300 threshold: the choice matters
    hu += rng.normal(0, 25, hu.shape)
    return np.round(hu).astype(np.int16)


def nrrd_bytes(hu):
    # NRRD's first axis is fastest: write x fastest, i.e. numpy order [z, y, x].
    data = np.ascontiguousarray(np.transpose(hu, (2, 1, 0))).astype("<i2").tobytes()
    n = hu.shape
    head = ("NRRD0004\n# gradel sample: synthetic CT, Hounsfield units\ntype: short\ndimension: 3\n"
            "sizes: %d %d %d\nspacings: 1 1 1\nencoding: gzip\nendian: little\n\n" % n)
    return head.encode() + gz(data)


def nifti_bytes(hu):
    n = hu.shape
    hdr = bytearray(348)
    struct.pack_into("<i", hdr, 0, 348)
    struct.pack_into("<8h", hdr, 40, 3, n[0], n[1], n[2], 1, 1, 1, 1)
    struct.pack_into("<hh", hdr, 70, 512, 16)  # datatype uint16, bitpix
    struct.pack_into("<8f", hdr, 76, 1, 1, 1, 1, 1, 1, 1, 1)  # pixdim
    struct.pack_into("<fff", hdr, 108, 352, 1.0, -1024.0)  # vox_offset, scl_slope, scl_inter
    hdr[344:348] = b"n+1\0"
    stored = (hu.astype(np.int32) + 1024).clip(0, 65535).astype("<u2")
    data = np.ascontiguousarray(np.transpose(stored, (2, 1, 0))).tobytes()
    return gz(bytes(hdr) + b"\0\0\0\0" + data)


def phantom_labels(nx=24, ny=12, nz=24):
    """Labels on an nx x ny x nz grid, index [x, y, z]: 1 tissue, 2 the inclusion."""
    x, y, z = np.meshgrid(np.arange(nx) + 0.5, np.arange(ny) + 0.5, np.arange(nz) + 0.5, indexing="ij")
    labels = np.ones((nx, ny, nz), dtype=np.uint8)
    inside = ((x - nx / 2) / 5.0) ** 2 + ((y - 6.5) / 3.5) ** 2 + ((z - nz / 2) / 5.0) ** 2 <= 1
    labels[inside] = 2
    return labels


def label_nrrd_bytes(labels):
    data = np.ascontiguousarray(np.transpose(labels, (2, 1, 0))).astype("u1").tobytes()
    head = ("NRRD0004\n# gradel sample: label map, 1 soft tissue, 2 stiff inclusion\ntype: uint8\ndimension: 3\n"
            "sizes: %d %d %d\nspacings: 1 1 1\nencoding: gzip\n\n" % labels.shape)
    return head.encode() + gz(data)


def mushroom():
    pts = []
    for x in range(16):
        for y in range(16):
            for z in range(16):
                dx, dy = x - 7.5, y - 7.5
                stalk = dx * dx + dy * dy <= 2.6 ** 2 and z < 9
                cap = 8 <= z < 14 and dx * dx + dy * dy + 2.2 * (z - 8) ** 2 <= 7.6 ** 2
                if stalk or cap:
                    pts.append((x, y, z, 1 if cap else 2))
    return pts


def torus_voxels(n=24):
    # Same torus as torus.obj (R = 1, r = 0.4), in a box of 2.8 x 0.8 x 2.8 scaled to n across.
    c = (np.arange(n) + 0.5) / n * 2.8 - 1.4
    ny = int(round(n * 0.8 / 2.8))
    cy = (np.arange(ny) + 0.5) / ny * 0.8 - 0.4
    x, y, z = np.meshgrid(c, cy, c, indexing="ij")
    return (np.sqrt(x ** 2 + z ** 2) - 1.0) ** 2 + y ** 2 <= 0.4 ** 2


def main():
    os.makedirs(OUT, exist_ok=True)
    v, t = torus()
    write("torus.obj", obj_bytes(v, t))
    write("torus.stl", stl_bytes(v, t))
    profile = [(0.42, 0.0), (0.42, 0.08), (0.3, 0.14), (0.24, 0.2), (0.14, 0.55), (0.2, 0.6),
               (0.12, 0.66), (0.2, 0.76), (0.19, 0.86), (0.12, 0.93), (0.0, 0.95)]
    pv, pt = lathe(profile[:-1])
    write("pawn.ply", ply_bytes(pv, pt))
    write("torus.binvox", binvox_bytes(torus_voxels()))
    hu = ct_volume()
    write("ct.nrrd", nrrd_bytes(hu))
    write("ct.nii.gz", nifti_bytes(hu))
    bone = (hu >= 300).astype(np.uint8)
    write("ct.raw", np.ascontiguousarray(np.transpose(bone, (2, 1, 0))).tobytes())
    write("mushroom.vox", vox_bytes(mushroom(), (16, 16, 16)))
    write("phantom.nrrd", label_nrrd_bytes(phantom_labels()))


if __name__ == "__main__":
    main()
