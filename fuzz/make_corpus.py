#!/usr/bin/python3
"""Writes the fuzz targets' seed corpora, fuzz/corpus/<format>/ (committed; re-run to regenerate):
small valid files of every format and encoding, built with the sample generator's writers.

    /usr/bin/python3 fuzz/make_corpus.py
"""
import os
import struct
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "samples"))
import make_samples as ms  # noqa: E402


def put(fmt, name, data):
    d = os.path.join(HERE, "corpus", fmt)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def main():
    hu = ms.ct_volume(n=8, seed=1)
    put("nrrd", "gzip.nrrd", ms.nrrd_bytes(hu))
    data = np.ascontiguousarray(np.transpose(hu, (2, 1, 0)))
    base = "NRRD0004\ntype: short\ndimension: 3\nsizes: 8 8 8\n"
    put("nrrd", "raw-le.nrrd", (base + "encoding: raw\nendian: little\n\n").encode() + data.astype("<i2").tobytes())
    put("nrrd", "raw-be.nrrd", (base + "encoding: raw\nendian: big\nbyte skip: 2\n\n").encode() + b"xx" + data.astype(">i2").tobytes())
    put("nrrd", "ascii.nrrd", b"NRRD0005\ntype: float\ndimension: 2\nsizes: 3 2\nencoding: ascii\nkinds: domain domain\n\n1 0 2.5\n-1 7 0\n")
    put("nifti", "ct.nii.gz", ms.nifti_bytes(hu))
    nii = ms.gzip.decompress(ms.nifti_bytes(hu))
    put("nifti", "ct.nii", nii)
    h2 = bytearray(540)
    struct.pack_into("<i8sh h8q", h2, 0, 540, b"n+2\0\r\n\032\n", 2, 8, 3, 4, 3, 2, 1, 1, 1, 1)
    struct.pack_into("<q", h2, 168, 544)
    put("nifti", "small.nii2", bytes(h2) + b"\0" * 4 + bytes(range(24)))
    vox = np.zeros((6, 5, 4), bool)
    vox[1:5, 1:4, 1:3] = True
    put("binvox", "box.binvox", ms.binvox_bytes(vox))
    put("vox", "small.vox", ms.vox_bytes([(0, 0, 0, 1), (1, 2, 3, 2), (3, 3, 3, 3)], (4, 4, 4)))
    put("raw", "u8.raw", bytes([4, 3, 2, 1, 0, 0, 0, 0]) + bytes(i % 3 for i in range(24)))
    put("raw", "f32be.raw", bytes([2, 2, 2, 8, 1, 3, 1, 5]) + b"hdr" + np.arange(8, dtype=">f4").tobytes())
    v, t = ms.torus(nu=8, nv=6)
    put("obj", "torus.obj", ms.obj_bytes(v, t))
    put("obj", "quads.obj", b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1 4/1/1\nf -1 -2 -3\n")
    put("stl", "torus.stl", ms.stl_bytes(v, t))
    put("stl", "tetra-ascii.stl", b"solid t\n" + b"".join(
        b"facet normal 0 0 0\nouter loop\n" + b"".join(b"vertex %d %d %d\n" % p for p in tri) + b"endloop\nendfacet\n"
        for tri in [((0, 0, 0), (0, 1, 0), (1, 0, 0)), ((0, 0, 0), (1, 0, 0), (0, 0, 1)),
                    ((0, 0, 0), (0, 0, 1), (0, 1, 0)), ((1, 0, 0), (0, 1, 0), (0, 0, 1))]) + b"endsolid t\n")
    pv, pt = ms.lathe([(0.4, 0.0), (0.3, 0.3), (0.1, 0.6)], n=8)
    put("ply", "pawn-le.ply", ms.ply_bytes(pv, pt))
    put("ply", "tetra-ascii.ply", b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
        b"property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
        b"0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n")
    be = (b"ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\n"
          b"element face 4\nproperty list uchar uint vertex_indices\nend_header\n")
    be += np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], ">f8").tobytes()
    for tri in [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]:
        be += struct.pack(">B3I", 3, *tri)
    put("ply", "tetra-be.ply", be)
    ply_extra()


def ply_extra():
    """Shapes that once cost fuzz_ply seconds per execution (tests/test_io_meshes.cpp, PlySpeed):
    an element of many rows without properties, and one face repeated many times."""
    put("ply", "rowless-element.ply", b"ply\nformat ascii 1.0\nelement junk 65536\nelement vertex 3\nproperty float x\n"
        b"property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        b"0 0 0\n1 0 0\n0 1 1\n3 0 1 2\n")
    rep = (b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
           b"element face 256\nproperty list uchar uchar vertex_indices\nend_header\n")
    rep += np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], "<f4").tobytes()
    tets = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
    rep += b"".join(struct.pack("<4B", 3, *tets[i % 4]) for i in range(256))
    put("ply", "repeated-faces.ply", rep)


if __name__ == "__main__":
    main()
