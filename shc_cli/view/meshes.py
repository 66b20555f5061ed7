"""Unit meshes the viewer instances (scaled and placed per link, foot or block): vertices ``(V, 3)`` float32 and
faces ``(F, 3)`` uint32, counter-clockwise seen from outside."""

from __future__ import annotations

import numpy as np


def cylinder(segments: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """Radius 1 around +z, from z = 0 to z = 1, with caps."""
    angle = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    ring = np.stack([np.cos(angle), np.sin(angle)], axis=1)
    bottom = np.column_stack([ring, np.zeros(segments)])
    top = np.column_stack([ring, np.ones(segments)])
    vertices = np.vstack([bottom, top, [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0]]])
    faces = []
    centre_bottom, centre_top = 2 * segments, 2 * segments + 1
    for i in range(segments):
        j = (i + 1) % segments
        faces += [(i, j, segments + j), (i, segments + j, segments + i),
                  (centre_bottom, j, i), (centre_top, segments + i, segments + j)]
    return vertices.astype(np.float32), np.array(faces, dtype=np.uint32)


def sphere(rings: int = 8, segments: int = 14) -> tuple[np.ndarray, np.ndarray]:
    """Radius 1 around the origin (a UV sphere)."""
    vertices = [(0.0, 0.0, 1.0)]
    for r in range(1, rings):
        polar = np.pi * r / rings
        for s in range(segments):
            azimuth = 2.0 * np.pi * s / segments
            vertices.append((np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth), np.cos(polar)))
    vertices.append((0.0, 0.0, -1.0))
    south = len(vertices) - 1
    faces = []

    def index(r: int, s: int) -> int:
        return 1 + (r - 1) * segments + s % segments

    for s in range(segments):
        faces.append((0, index(1, s), index(1, s + 1)))
        faces.append((south, index(rings - 1, s + 1), index(rings - 1, s)))
    for r in range(1, rings - 1):
        for s in range(segments):
            a, b, c, d = index(r, s), index(r, s + 1), index(r + 1, s), index(r + 1, s + 1)
            faces += [(a, c, d), (a, d, b)]
    return np.array(vertices, dtype=np.float32), np.array(faces, dtype=np.uint32)


def box() -> tuple[np.ndarray, np.ndarray]:
    """Edge 1 centred on the origin."""
    corners = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)], dtype=np.float32)
    faces = np.array([(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
                      (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)], dtype=np.uint32)
    return corners, faces
