"""Volume: integration of an analytic plane, meshing, ray casting, queries, save / load."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import HEIGHT, PLANE_POSE, PLANE_X, WIDTH, K, look_pose, plane_depth

import voxplan

VOXEL = 0.02


def axis_points(T_W_C: np.ndarray, depths: np.ndarray) -> np.ndarray:
    """World points on the optical axis of T_W_C at the given depths."""
    return T_W_C[:3, 3] + np.outer(depths, T_W_C[:3, 2])


def test_tsdf_sign_and_zero_crossing_at_the_plane(plane_volume: voxplan.Volume) -> None:
    axis_depth = (PLANE_X - PLANE_POSE[0, 3]) / PLANE_POSE[0, 2]  # the plane along the axis
    # Along the optical axis through the truncation band: positive in front, negative behind.
    d = np.linspace(axis_depth - 0.06, axis_depth + 0.06, 121)
    # Distance to the plane along the ray, scaled to the normal: the TSDF is along x here.
    tsdf = plane_volume.tsdf(axis_points(PLANE_POSE, d))
    assert np.isfinite(tsdf).all()
    assert (tsdf[d < axis_depth - VOXEL] > 0).all()
    assert (tsdf[d > axis_depth + VOXEL] < 0).all()
    crossing = np.flatnonzero(np.diff(np.sign(tsdf)) != 0)
    assert len(crossing) == 1
    i = crossing[0]
    zero = d[i] + (d[i + 1] - d[i]) * tsdf[i] / (tsdf[i] - tsdf[i + 1])
    assert abs(zero - axis_depth) < VOXEL
    # The stored signed distance is the distance along the camera ray's projection (z), which
    # for this plane is within a few percent of the true distance: compare in metres.
    world = axis_points(PLANE_POSE, d)
    front = d < axis_depth - 0.01
    assert np.allclose(tsdf[front], (PLANE_X - world[front, 0]) / PLANE_POSE[0, 2], atol=0.01)


def test_queries_states_and_gradient(plane_volume: voxplan.Volume) -> None:
    p_front = np.array([[PLANE_X - 0.06, 0.3, 1.0]])
    p_behind = np.array([[PLANE_X + 0.03, 0.3, 1.0]])
    p_far = np.array([[50.0, 50.0, 50.0]])
    states = plane_volume.state(np.vstack([p_front, p_behind, p_far]))
    assert list(states) == [voxplan.FREE, voxplan.OCCUPIED, voxplan.UNOBSERVED]
    g = plane_volume.gradient(np.array([[PLANE_X - 0.02, 0.3, 1.0]]))[0]
    assert np.dot(g / np.linalg.norm(g), [-1, 0, 0]) > 0.95  # points away from the surface
    values = plane_volume.voxel_values(np.vstack([p_front, p_far]))
    assert values["weight"][0] > 0 and np.isnan(values["tsdf"][1]) and values["weight"][1] == 0
    near = plane_volume.interpolate(np.array([[PLANE_X - 0.01, 0.3, 1.0]]))
    assert np.allclose(near["color"][0], (200, 100, 50), atol=1.0)
    assert plane_volume.tsdf([PLANE_X - 0.01, 0.3, 1.0]).shape == (1,)  # one point


def test_mesh_vertices_lie_on_the_plane(plane_volume: voxplan.Volume) -> None:
    mesh = plane_volume.extract_mesh()
    assert mesh.num_triangles > 100
    assert mesh.vertices.dtype == np.float32 and mesh.vertices.shape == (mesh.num_vertices, 3)
    assert mesh.triangles.dtype == np.uint32 and mesh.triangles.max() < mesh.num_vertices
    assert np.abs(mesh.vertices[:, 0] - PLANE_X).max() < VOXEL / 2
    assert (np.abs(mesh.colors.astype(int) - (200, 100, 50)) <= 1).all()
    assert np.allclose(mesh.normals, [-1, 0, 0], atol=0.05)  # toward the camera
    # Views of the mesh's own memory, no copy.
    assert isinstance(mesh.vertices.base, voxplan.Mesh)


def test_raycast_depth_equals_the_plane(plane_volume: voxplan.Volume) -> None:
    images = plane_volume.raycast(K, PLANE_POSE, WIDTH, HEIGHT)
    hit = images.status == voxplan.RAY_HIT
    assert hit.mean() > 0.9
    truth = plane_depth(PLANE_POSE)
    assert np.abs(images.depth[hit] - truth[hit]).max() < VOXEL / 2
    assert (images.depth[~hit] == 0).all()
    # Normals face the camera (-x), but at the edge of what was fused the gradient tilts.
    facing = images.normals[hit] @ np.array([-1.0, 0.0, 0.0])
    assert np.mean(facing > 0.99) > 0.9 and facing.min() > 0.5
    assert np.abs(images.vertices[hit][:, 0] - PLANE_X).max() < VOXEL / 2
    assert (np.abs(images.colors[hit].astype(int) - (200, 100, 50)) <= 1).all()
    # From another pose, 10 cm further back and turned: the plane's depth there.
    other = look_pose(np.array([0.9, 0.2, 1.15]), np.array([1.0, 0.1, -0.05]))
    images = plane_volume.raycast(K, other, WIDTH, HEIGHT, max_depth=3.0)
    hit = images.status == voxplan.RAY_HIT
    truth = plane_depth(other)
    assert hit.mean() > 0.5
    assert np.abs(images.depth[hit] - truth[hit]).max() < VOXEL / 2


def test_save_load_round_trip(plane_volume: voxplan.Volume, tmp_path: Path) -> None:
    plane_volume.save(tmp_path / "a.vpmap")
    loaded = voxplan.Volume.load(tmp_path / "a.vpmap")
    assert loaded.voxel_size == plane_volume.voxel_size and loaded.trunc == plane_volume.trunc
    assert np.array_equal(loaded.block_indices(), plane_volume.block_indices())
    points = np.random.default_rng(1).uniform([1.5, -1, 0], [2.5, 1.5, 2], (2000, 3))
    a, b = plane_volume.voxel_values(points), loaded.voxel_values(points)
    for key in ("tsdf", "weight", "color"):
        assert np.array_equal(a[key], b[key], equal_nan=True)
    loaded.save(tmp_path / "b.vpmap")
    assert (tmp_path / "a.vpmap").read_bytes() == (tmp_path / "b.vpmap").read_bytes()
    # Meshes of both are identical too.
    assert np.array_equal(loaded.extract_mesh().vertices, plane_volume.extract_mesh().vertices)


def test_the_up_axis_is_saved_and_loaded(plane_volume: voxplan.Volume, tmp_path: Path) -> None:
    assert plane_volume.up == "unknown"
    plane_volume.save(tmp_path / "unknown.vpmap")
    assert voxplan.Volume.load(tmp_path / "unknown.vpmap").up == "unknown"
    for given, recorded in (("y", "+y"), ("-z", "-z"), ("+x", "+x")):
        plane_volume.up = given
        assert plane_volume.up == recorded
        plane_volume.save(tmp_path / "up.vpmap")
        loaded = voxplan.Volume.load(tmp_path / "up.vpmap")
        assert loaded.up == recorded
        assert np.array_equal(loaded.block_indices(), plane_volume.block_indices())
    with pytest.raises(ValueError, match="up axis"):
        plane_volume.up = "sideways"
    # The up axis is in the header (offset 28, version 2); the blocks are the same bytes.
    a = (tmp_path / "unknown.vpmap").read_bytes()
    b = (tmp_path / "up.vpmap").read_bytes()
    assert a[8:12] == b[8:12] == (2).to_bytes(4, "little")
    assert a[28:32] == bytes(4) and b[28:32] == (1).to_bytes(4, "little")  # +x
    assert a[32:-8] == b[32:-8]


def test_uint16_depth_with_scale_gives_the_same_map(tmp_path: Path) -> None:
    depth_m = np.round(plane_depth(PLANE_POSE) * 5000) / 5000  # what a 16-bit PNG holds
    raw = np.round(depth_m * 5000).astype(np.uint16)
    a, b = voxplan.Volume(VOXEL, 0.08), voxplan.Volume(VOXEL, 0.08)
    # As the PNG decoder converts: raw * (1 / scale) in double, then float.
    a.integrate((raw * (1.0 / 5000)).astype(np.float32), None, K, PLANE_POSE)
    stats = b.integrate(raw, None, K, PLANE_POSE, depth_scale=5000)
    assert stats["depth_copied"]
    a.save(tmp_path / "a.vpmap")
    b.save(tmp_path / "b.vpmap")
    assert (tmp_path / "a.vpmap").read_bytes() == (tmp_path / "b.vpmap").read_bytes()


def test_contiguous_arrays_are_read_in_place_others_copied(tmp_path: Path) -> None:
    depth = plane_depth(PLANE_POSE)
    rgbx = np.zeros((HEIGHT, WIDTH, 4), np.uint8)
    rgbx[..., 1] = 120
    ref = voxplan.Volume(VOXEL, 0.08)
    stats = ref.integrate(depth, rgbx, K, PLANE_POSE)
    assert not stats["depth_copied"] and not stats["color_copied"]
    packed = rgbx.view(np.uint32)[..., 0]  # (H, W) uint32 RGBX
    assert not voxplan.Volume(VOXEL, 0.08).integrate(depth, packed, K, PLANE_POSE)["color_copied"]

    # A non-contiguous depth (a column slice of a wider image) and an (H, W, 3) colour work by
    # copying, with the same result.
    wide = np.zeros((HEIGHT, 2 * WIDTH), np.float32)
    wide[:, :WIDTH] = depth
    strided = wide[:, :WIDTH]
    assert not strided.flags["C_CONTIGUOUS"]
    other = voxplan.Volume(VOXEL, 0.08)
    stats = other.integrate(strided, np.ascontiguousarray(rgbx[..., :3]), K, PLANE_POSE)
    assert stats["depth_copied"] and stats["color_copied"]
    ref.save(tmp_path / "a.vpmap")
    other.save(tmp_path / "b.vpmap")
    assert (tmp_path / "a.vpmap").read_bytes() == (tmp_path / "b.vpmap").read_bytes()

    # voxplan's own (H, W, 3) colour views (a ray cast's, a frame's) are read in place.
    images = ref.raycast(K, PLANE_POSE, WIDTH, HEIGHT)
    assert images.colors.strides == (4 * WIDTH, 4, 1)
    assert isinstance(images.colors.base, voxplan.RaycastImages)
    stats = voxplan.Volume(VOXEL, 0.08).integrate(images.depth, images.colors, K, PLANE_POSE)
    assert not stats["depth_copied"] and not stats["color_copied"]
    # A foreign array with that layout is not trusted: copied.
    foreign = np.zeros((HEIGHT, WIDTH, 4), np.uint8)[..., :3]
    assert voxplan.Volume(VOXEL, 0.08).integrate(depth, foreign, K, PLANE_POSE)["color_copied"]


def test_parameters_and_repr() -> None:
    v = voxplan.Volume(0.05, 0.2, max_depth=5.0, weighting="depth", kernel="scalar")
    assert (v.max_depth, v.weighting, v.kernel) == (5.0, "depth", "scalar")
    v.max_weight = 10.0
    assert v.max_weight == 10.0 and v.num_blocks == 0
    assert "voxel_size=0.05" in repr(v)
    assert voxplan.get_threads() >= 1
