#!/usr/bin/env python3
"""Builds the fuzz seed corpora in OUT/<target>/ at run time: small cuts of the shared meshes
(../shared/data, never copied into the repository) plus tiny files written here.

Usage: make-seeds.py SHARED_DATA OUT"""
import base64
import os
import struct
import sys
import zlib

KEEP_VERTICES = 60  # a cut keeps this many vertices and the faces that use only them


def write(out, target, name, data):
    os.makedirs(os.path.join(out, target), exist_ok=True)
    with open(os.path.join(out, target, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def cut_obj(text):
    """The first KEEP_VERTICES positions/UVs/normals and the faces whose corners they cover."""
    out, counts = [], {"v": 0, "vt": 0, "vn": 0}
    for line in text.splitlines():
        key = line.split(" ", 1)[0]
        if key in counts:
            counts[key] += 1
            if counts[key] <= KEEP_VERTICES:
                out.append(line)
        elif key == "f":
            indices = [int(i) for c in line.split()[1:] for i in c.split("/") if i]
            if all(0 < i <= KEEP_VERTICES for i in indices):
                out.append(line)
        elif key == "mtllib":
            out.append("mtllib fuzz.mtl")
        else:
            out.append(line)
    return "\n".join(out) + "\n"


def obj_seeds(shared, out):
    for root, _, files in os.walk(shared):
        for name in sorted(files):
            if not name.endswith(".obj"):
                continue
            with open(os.path.join(root, name), errors="replace") as f:
                obj = cut_obj(f.read())
            mtl = ""
            for line in open(os.path.join(root, name), errors="replace"):
                if line.startswith("mtllib"):
                    path = os.path.join(root, line.split(None, 1)[1].strip())
                    if os.path.exists(path):
                        mtl = open(path, errors="replace").read()
                    break
            write(out, "obj", name, obj + ("\n#--mtl--\n" + mtl if mtl else ""))
    write(out, "obj", "quad.obj",
          "mtllib fuzz.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n"
          "vt 0 1\nusemtl m\nf 1/1 2/2 3/3 4/4\nf -1/-1 -2/-2 -3/-3\n#--mtl--\n"
          "newmtl m\nmap_Kd tex.png\nnorm n.png\n")


def cut_ply(data):
    """Binary little-endian triangle-strip PLY (float xyz, uchar/int indices, uchar/float
    texcoord lists) cut to KEEP_VERTICES vertices; returns (binary, ascii) files."""
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    nv = int(next(l for l in header if l.startswith("element vertex")).split()[2])
    nf = int(next(l for l in header if l.startswith("element face")).split()[2])
    pos, faces = end, []
    verts = [struct.unpack_from("<3f", data, pos + 12 * i) for i in range(KEEP_VERTICES)]
    pos += 12 * nv
    for _ in range(nf):
        n = data[pos]
        idx = struct.unpack_from("<%di" % n, data, pos + 1)
        pos += 1 + 4 * n
        m = data[pos]
        uv = struct.unpack_from("<%df" % m, data, pos + 1)
        pos += 1 + 4 * m
        if all(i < KEEP_VERTICES for i in idx):
            faces.append((idx, uv))
    head = [l for l in header if not l.startswith(("element", "property", "end_header", "format"))]
    def header_for(fmt):
        return "\n".join([head[0], "format " + fmt] + head[1:] + [
            "element vertex %d" % len(verts), "property float x", "property float y",
            "property float z", "element face %d" % len(faces),
            "property list uchar int vertex_indices", "property list uchar float texcoord",
            "end_header"]) + "\n"
    binary = header_for("binary_little_endian 1.0").encode()
    binary += b"".join(struct.pack("<3f", *v) for v in verts)
    for idx, uv in faces:
        binary += struct.pack("<B%di" % len(idx), len(idx), *idx)
        binary += struct.pack("<B%df" % len(uv), len(uv), *uv)
    ascii_ = header_for("ascii 1.0") + "".join("%g %g %g\n" % v for v in verts) + "".join(
        "%d %s %d %s\n" % (len(i), " ".join(map(str, i)), len(u), " ".join("%g" % x for x in u))
        for i, u in faces)
    return binary, ascii_.encode()


def ply_seeds(shared, out):
    for root, _, files in os.walk(shared):
        for name in sorted(files):
            if name.endswith(".tsp.ply"):
                binary, ascii_ = cut_ply(open(os.path.join(root, name), "rb").read())
                write(out, "ply", name, binary)
                write(out, "ply", name + ".ascii", ascii_)
    write(out, "ply", "corner_uv.ply",
          "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
          "property float z\nproperty float s\nproperty float t\nelement face 1\n"
          "property list uchar int vertex_indices\nend_header\n0 0 0 0 0\n1 0 0 1 0\n"
          "0 1 0 0 1\n3 0 1 2\n")


def tiny_gltf(glb):
    """One textured triangle: positions, UVs, uint16 indices and a PNG signature as image."""
    png = b"\x89PNG\r\n\x1a\n"
    floats = [0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 1, 1, 0, 0]
    binary = struct.pack("<15f", *floats) + struct.pack("<3H", 0, 1, 2) + b"\0\0" + png
    image = ('{"bufferView":3,"mimeType":"image/png"}' if glb else
             '{"uri":"data:image/png;base64,%s"}' % base64.b64encode(png).decode())
    uri = "" if glb else ',"uri":"data:application/octet-stream;base64,%s"' % (
        base64.b64encode(binary).decode())
    text = ('{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],'
            '"nodes":[{"mesh":0,"children":[1]},{"mesh":0,"matrix":[1,0,0,0,0,1,0,0,0,0,1,0,1,2,3,1]}],'
            '"meshes":[{"primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":1},"indices":2,'
            '"material":0,"mode":4}]}],'
            '"materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}},'
            '"normalTexture":{"index":0}}],"textures":[{"source":0}],"images":[%s],'
            '"buffers":[{"byteLength":%d%s}],'
            '"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},'
            '{"buffer":0,"byteOffset":36,"byteLength":24},{"buffer":0,"byteOffset":60,"byteLength":6},'
            '{"buffer":0,"byteOffset":68,"byteLength":8}],'
            '"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",'
            '"min":[0,0,0],"max":[1,1,0]},{"bufferView":1,"componentType":5126,"count":3,'
            '"type":"VEC2"},{"bufferView":2,"componentType":5123,"count":3,"type":"SCALAR"}]}'
            % (image, len(binary), uri))
    if not glb:
        return text.encode()
    text += " " * (-len(text) % 4)
    chunks = struct.pack("<I", len(text)) + b"JSON" + text.encode()
    chunks += struct.pack("<I", len(binary)) + b"BIN\0" + binary
    return b"glTF" + struct.pack("<II", 2, 12 + len(chunks)) + chunks


def gltf_seeds(shared, out):
    write(out, "gltf", "triangle.gltf", tiny_gltf(False))
    write(out, "glb", "triangle.glb", tiny_gltf(True))
    for root, _, files in os.walk(shared):  # external buffers are missing: exercises the JSON
        for name in sorted(files):
            if name.endswith(".gltf") and os.path.getsize(os.path.join(root, name)) < 64 * 1024:
                write(out, "gltf", name, open(os.path.join(root, name), "rb").read())


def png(width, height, channels, depth):
    """A tiny PNG written by hand (gradient pixels)."""
    kind = {1: 0, 3: 2, 4: 6}[channels]
    bytes_per = channels * depth // 8
    rows = b"".join(b"\0" + bytes((x * 37 + y * 11) % 256 for x in range(width * bytes_per))
                    for y in range(height))
    def chunk(tag, body):
        return struct.pack(">I", len(body)) + tag + body + struct.pack(
            ">I", zlib.crc32(tag + body) & 0xFFFFFFFF)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, depth,
                                                              kind, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def image_seeds(shared, out):
    # First byte: 0 png, 1 jpg, 2 exr, 3 ppm (fuzz_image.cpp).
    write(out, "image", "rgb8.png", b"\0" + png(4, 3, 3, 8))
    write(out, "image", "rgba16.png", b"\0" + png(3, 2, 4, 16))
    write(out, "image", "grey8.png", b"\0" + png(5, 1, 1, 8))
    write(out, "image", "rgb.ppm", b"\3" + b"P6\n2 2\n255\n" + bytes(range(12)))
    for root, _, files in os.walk(shared):
        for name in sorted(files):
            path = os.path.join(root, name)
            kind = {".png": 0, ".jpg": 1, ".jpeg": 1, ".exr": 2}.get(os.path.splitext(name)[1])
            if kind is not None and os.path.getsize(path) < 16 * 1024:
                write(out, "image", name, bytes([kind]) + open(path, "rb").read())


def vector_field_seeds(out):
    # First byte: basis (0 intrinsic: 2 doubles a face, 1 extrinsic: 3); then int32 count.
    for basis, dim in ((0, 2), (1, 3)):
        for count in (1, 3):
            body = struct.pack("<i", count) + struct.pack("<%dd" % (count * dim),
                                                          *[0.25 * i for i in range(count * dim)])
            write(out, "vector_field", "field_%d_%d.vf" % (dim, count), bytes([basis]) + body)


def protocol_seeds(out):
    messages = [
        '{"type":"source","face":1,"bary":[1,0,0],"add":true,"id":3}',
        '{"type":"params","alpha":100,"beta":2,"id":1}',
        '{"type":"brush","face":3,"bary":[0.2,0.3,0.5],"radius":0.05,"strength":1,'
        '"mode":"sharpen"}',
        '{"type":"show","texture":"stitched"}',
        '{"type":"run","action":"start","id":4}',
        '{"type":"save"}',
        '{"type":"probe","points":[{"face":0,"bary":[0.3,0.3,0.4]},{"face":2,"bary":[0,0,1]}]}',
        '{"type":"state","id":9007199254740991}',
    ]
    for i, m in enumerate(messages):
        write(out, "protocol", "message_%d.json" % i, m)


def camera_seeds(out):
    # First byte modulo 3: 0 camera JSON, 1 COLMAP text (cameras.txt, "#--images--", images.txt),
    # 2 OpenMVS .mvs.
    write(out, "cameras", "colmap.txt", b"\1" + (
        "# Camera list\n1 SIMPLE_PINHOLE 640 480 500 320 240\n2 PINHOLE 800 600 700 710 400 300\n"
        "3 SIMPLE_RADIAL 640 480 510 321 239 -0.05\n4 RADIAL 640 480 520 322 238 -0.1 0.02\n"
        "5 OPENCV 1024 768 900 905 512 384 -0.2 0.05 0.001 -0.002\n"
        "\n#--images--\n"
        "# Image list\n1 1 0 0 0 0 0 0 1 a.jpg\n\n"
        "2 0.7071067811865476 0 0.7071067811865476 0 1 2 3 2 sub/b c.jpg\n10.5 20.5 -1 30 40 7\n"
        "3 0.5 0.5 0.5 0.5 0 0 5 3 c.png\n\n4 1 0 0 0 0 0 0 4 d.jpg\n\n"
        "5 1 0 0 0 0 0 0 5 e.jpg\n").encode())
    write(out, "cameras", "cameras.json", b"\0" + (
        '{"cameras": [{"file": "IMG_0001.jpg", "width": 640, "height": 480,'
        ' "K": [[500, 0, 320], [0, 500, 240], [0, 0, 1]],'
        ' "R": [[0, 0, 1], [0, 1, 0], [-1, 0, 0]], "C": [5, 0, 0],'
        ' "distortion": {"model": "opencv", "k1": -0.1, "k2": 0.01, "p1": 0.001, "p2": -0.002}},'
        ' {"file": "b.jpg", "width": 64, "height": 48, "K": [[50, 0, 32], [0, 51, 24], [0, 0, 1]],'
        ' "R": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "t": [0, 0, 5],'
        ' "distortion": {"model": "radial", "k1": 0.1, "k2": -0.01}}]}').encode())
    write(out, "cameras", "scene.mvs", b"\2" + openmvs_scene())


def openmvs_scene():
    """A version-5 OpenMVS archive: one platform, one camera, one pose, two images (one
    uncalibrated), an empty point cloud (libs/MVS/Interface.h layout, little-endian)."""
    def string(s):
        return struct.pack("<Q", len(s)) + s.encode()
    identity = struct.pack("<9d", 1, 0, 0, 0, 1, 0, 0, 0, 1)
    data = b"MVSI" + struct.pack("<II", 5, 0)
    data += struct.pack("<Q", 1) + string("platform000")
    data += struct.pack("<Q", 1) + string("PINHOLE") + string("RGB") + struct.pack("<II", 640, 480)
    data += struct.pack("<9d", 500, 0, 319.5, 0, 500, 239.5, 0, 0, 1) + identity
    data += struct.pack("<3d", 0, 0, 0)
    data += struct.pack("<Q", 1) + struct.pack("<9d", 0, 0, 1, 0, 1, 0, -1, 0, 0)
    data += struct.pack("<3d", 5, 0, 0)
    data += struct.pack("<Q", 2)
    data += string("a.jpg") + string("") + struct.pack("<IIII", 0, 0, 0, 0)
    data += string("b.jpg") + string("") + struct.pack("<IIII", 0, 0, 0xFFFFFFFF, 1)
    return data + struct.pack("<3Q", 0, 0, 0)


def main():
    shared, out = sys.argv[1], sys.argv[2]
    obj_seeds(shared, out)
    ply_seeds(shared, out)
    gltf_seeds(shared, out)
    image_seeds(shared, out)
    vector_field_seeds(out)
    protocol_seeds(out)
    camera_seeds(out)


if __name__ == "__main__":
    main()
