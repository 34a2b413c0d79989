#!/usr/bin/python3
"""Open3D's RaycastingScene distance queries on a mesh file, as a user's first script after
`voxplan fuse` would run them (Open3D 0.16 aborts on a zero-area triangle near a query point).

usage: open3d_distance.py MESH OFFSET
Queries compute_distance and compute_signed_distance at every vertex and at every vertex moved
OFFSET along its normal; prints "points max_distance_at_vertices max_distance_off_surface
max_abs_signed_minus_distance". Exits 3 when open3d cannot be imported."""
import sys

try:
    import numpy as np
    import open3d as o3d
except ImportError:
    sys.exit(3)

legacy = o3d.io.read_triangle_mesh(sys.argv[1])
offset = float(sys.argv[2])
if not legacy.has_vertex_normals():
    legacy.compute_vertex_normals()
vertices = np.asarray(legacy.vertices, dtype=np.float32)
normals = np.asarray(legacy.vertex_normals, dtype=np.float32)
scene = o3d.t.geometry.RaycastingScene()
scene.add_triangles(o3d.t.geometry.TriangleMesh.from_legacy(legacy))
query = o3d.core.Tensor(np.vstack([vertices, vertices + offset * normals]))
distance = scene.compute_distance(query).numpy()
signed = scene.compute_signed_distance(query).numpy()
n = len(vertices)
print(len(distance), distance[:n].max(), distance[n:].max(), np.abs(np.abs(signed) - distance).max())
