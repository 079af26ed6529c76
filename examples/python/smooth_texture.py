"""Smooths a texture given as numpy arrays, without opening the atlas's seams.

    python3 examples/python/smooth_texture.py [--out smoothed.png] [--size 256]

Everything is made in numpy: a cylinder cut open along one seam, its UV layout, and a striped
texture with noise. texgrad.filter smooths it on the surface (beta 0), so the stripes stay
continuous across the seam where a 2-D image blur would not see the other side.
"""

import argparse

import numpy as np

import texgrad


def cylinder(segments=32, rings=8):
    """An open cylinder (radius 1/(2 pi), height 1) whose UV chart is cut along x = 0."""
    vertices, uvs, faces, uv_faces = [], [], [], []
    for r in range(rings + 1):
        for s in range(segments + 1):
            angle = 2 * np.pi * s / segments
            if s < segments:  # the seam column reuses the first vertex of the ring
                vertices.append([np.cos(angle) / (2 * np.pi), np.sin(angle) / (2 * np.pi),
                                 r / rings])
            uvs.append([0.05 + 0.9 * s / segments, 0.05 + 0.9 * r / rings])
    for r in range(rings):
        for s in range(segments):
            v = [r * segments + s, r * segments + (s + 1) % segments,
                 (r + 1) * segments + (s + 1) % segments, (r + 1) * segments + s]
            t = [r * (segments + 1) + s, r * (segments + 1) + s + 1,
                 (r + 1) * (segments + 1) + s + 1, (r + 1) * (segments + 1) + s]
            faces += [[v[0], v[1], v[2]], [v[0], v[2], v[3]]]
            uv_faces += [[t[0], t[1], t[2]], [t[0], t[2], t[3]]]
    return texgrad.Mesh(np.array(vertices), np.array(faces), np.array(uvs), np.array(uv_faces))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="smoothed.png")
    parser.add_argument("--size", type=int, default=256)
    args = parser.parse_args()

    mesh = cylinder()
    rng = np.random.default_rng(7)
    columns = np.linspace(0, 1, args.size)
    stripes = 0.5 + 0.4 * np.sin(6 * np.pi * columns)[None, :, None]
    texture = np.clip(stripes + 0.2 * rng.standard_normal((args.size, args.size, 3)), 0, 1)
    texture = (texture * 255).astype(np.uint8)

    smoothed = texgrad.filter(mesh, texture, beta=0.0, alpha=1e3)
    assert smoothed.dtype == np.uint8 and smoothed.shape == texture.shape
    domain = texgrad.TexelDomain(mesh, args.size, args.size)
    active = domain.texel_class > 0
    before = texture[active].astype(float).std()
    after = smoothed[active].astype(float).std()
    texgrad.write_image(args.out, smoothed)
    print(f"wrote {args.out}: {domain.unknowns} texels, texel std {before:.1f} -> {after:.1f}")


if __name__ == "__main__":
    main()
