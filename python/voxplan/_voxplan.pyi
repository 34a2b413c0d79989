"""Type stubs of voxplan's extension module (python/src/*.cpp); `voxplan` re-exports it."""

import os
from typing import Any, Callable, Iterator, Sequence

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = str | os.PathLike[str]
ArrayLike = npt.ArrayLike

RAY_UNOBSERVED: int
RAY_HIT: int
RAY_FREE: int
UNOBSERVED: int
FREE: int
OCCUPIED: int

class VoxplanWarning(UserWarning):
    """Warnings of voxplan's readers and pipelines (frames skipped, a suspicious depth scale)."""

def set_threads(threads: int) -> None:
    """Caps the worker threads of every later call (0: all hardware threads)."""

def get_threads() -> int:
    """The worker threads calls may use now."""

def simd_available() -> bool:
    """Whether the AVX2 integration kernel runs on this CPU."""

class Mesh:
    """A triangle mesh; its arrays view the mesh's own memory (no copy)."""

    def __init__(
        self,
        vertices: ArrayLike,
        triangles: ArrayLike,
        colors: ArrayLike | None = None,
        normals: ArrayLike | None = None,
    ) -> None: ...
    @property
    def vertices(self) -> npt.NDArray[np.float32]:
        """(N, 3) vertex positions, metres."""
    @property
    def triangles(self) -> npt.NDArray[np.uint32]:
        """(M, 3) vertex indices, counter-clockwise seen from outside."""
    @property
    def colors(self) -> npt.NDArray[np.uint8] | None:
        """(N, 3) RGB per vertex, or None."""
    @property
    def normals(self) -> npt.NDArray[np.float32] | None:
        """(N, 3) unit normals per vertex, or None."""
    @property
    def num_vertices(self) -> int: ...
    @property
    def num_triangles(self) -> int: ...
    def save(self, path: PathLike) -> None:
        """Writes .ply (binary, coloured), .obj, .glb or .stl by extension."""

class RaycastImages:
    """Per-pixel results of Volume.raycast (views of the images' own memory)."""

    @property
    def depth(self) -> npt.NDArray[np.float32]:
        """(H, W) metres along the optical axis, 0 where no surface was hit."""
    @property
    def vertices(self) -> npt.NDArray[np.float32]:
        """(H, W, 3) world hit points, NaN where no hit."""
    @property
    def normals(self) -> npt.NDArray[np.float32]:
        """(H, W, 3) world unit normals, NaN where no hit."""
    @property
    def colors(self) -> npt.NDArray[np.uint8]:
        """(H, W, 3) RGB (a strided view of RGBX pixels), 0 where no hit."""
    @property
    def status(self) -> npt.NDArray[np.uint8]:
        """(H, W) RAY_UNOBSERVED, RAY_HIT or RAY_FREE."""

class Volume:
    """A sparse TSDF volume (8^3 voxel blocks) and its integration parameters."""

    def __init__(
        self,
        voxel_size: float = 0.01,
        trunc: float = 0.04,
        *,
        min_depth: float = 0.1,
        max_depth: float = 3.0,
        max_weight: float = 64.0,
        weighting: str = "constant",
        kernel: str = "auto",
        integrate_color: bool = True,
        max_memory: int = 0,
    ) -> None: ...
    @property
    def voxel_size(self) -> float: ...
    @property
    def trunc(self) -> float: ...
    @property
    def max_memory(self) -> int: ...
    up: str
    min_depth: float
    max_depth: float
    max_weight: float
    weighting: str
    kernel: str
    integrate_color: bool
    @property
    def num_blocks(self) -> int: ...
    @property
    def num_voxels(self) -> int: ...
    @property
    def memory_bytes(self) -> int: ...
    @property
    def blocks_refused(self) -> int: ...
    def integrate(
        self,
        depth: ArrayLike,
        color: ArrayLike | None,
        K: ArrayLike,
        T_W_C: ArrayLike,
        *,
        depth_scale: float | None = None,
    ) -> dict[str, Any]:
        """Fuses one frame: depth (H, W) float32 metres (or uint16 with depth_scale), color None
        / (H, W, 3|4) uint8 / (H, W) uint32 RGBX, K 3x3 or (fx, fy, cx, cy), T_W_C 4x4
        camera-to-world. Returns the frame's stats (depth_copied, color_copied say whether an
        input had to be converted)."""
    def extract_mesh(self, min_weight: float = 0.5, with_color: bool = True) -> Mesh: ...
    def raycast(
        self,
        K: ArrayLike,
        T_W_C: ArrayLike,
        width: int,
        height: int,
        *,
        min_depth: float = 0.1,
        max_depth: float = 5.0,
        min_weight: float = 0.5,
        stop_at_back_faces: bool = True,
        with_color: bool = True,
        with_normals: bool = True,
    ) -> RaycastImages: ...
    def interpolate(self, points: ArrayLike, min_weight: float = 1e-3) -> dict[str, npt.NDArray[np.float32]]:
        """Trilinear tsdf (N,), weight (N,), color (N, 3); NaN where not observed."""
    def voxel_values(self, points: ArrayLike) -> dict[str, npt.NDArray[np.float32]]:
        """The stored voxel's tsdf, weight, color at each point; NaN where unallocated."""
    def tsdf(self, points: ArrayLike, min_weight: float = 1e-3) -> npt.NDArray[np.float32]:
        """Interpolated signed distance (m) at (N, 3) points; NaN where not observed."""
    def state(
        self, points: ArrayLike, min_weight: float = 0.5, occupied_max_sdf_vox: float = 0.5
    ) -> npt.NDArray[np.uint8]:
        """UNOBSERVED, FREE or OCCUPIED per point."""
    def gradient(self, points: ArrayLike) -> npt.NDArray[np.float32]:
        """(N, 3) TSDF gradient, NaN where undefined."""
    def block_indices(self) -> npt.NDArray[np.int32]:
        """(B, 3) allocated block indices, sorted as in map files."""
    def clear(self) -> None: ...
    def save(self, path: PathLike) -> None:
        """Writes a .vpmap map file (the bytes `voxplan fuse --map` writes)."""
    @staticmethod
    def load(path: PathLike) -> Volume:
        """Reads a .vpmap map file."""

def read_mesh(path: PathLike, *, scale: float = 1.0, up: str = "z") -> Mesh: ...
def evaluate_mesh(
    reconstruction: Mesh | PathLike,
    ground_truth: Mesh | PathLike,
    *,
    threshold: float = 0.05,
    samples_per_m2: float = 10000.0,
    seed: int = 1,
    gt_up: str = "z",
    gt_scale: float = 1.0,
) -> dict[str, Any]:
    """Accuracy (mean, RMS, median, m) and completeness (0..1) as `voxplan eval mesh`."""

class Frame:
    """One decoded RGB-D frame; depth and color view the decoded images (no copy)."""

    @property
    def index(self) -> int: ...
    @property
    def timestamp(self) -> float: ...
    @property
    def depth(self) -> npt.NDArray[np.float32]:
        """(H, W) metres, 0 = invalid."""
    @property
    def color(self) -> npt.NDArray[np.uint8] | None:
        """(H, W, 3) RGB (a strided view of RGBX pixels), or None."""
    @property
    def T_W_C(self) -> npt.NDArray[np.float64] | None:
        """4x4 camera-to-world, or None."""
    @property
    def K(self) -> npt.NDArray[np.float64]: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def depth_path(self) -> str: ...
    @property
    def color_path(self) -> str: ...
    @property
    def pose_rejected(self) -> str: ...
    @property
    def pose_rejected_why(self) -> str: ...

class FrameIterator(Iterator[Frame]):
    def __iter__(self) -> FrameIterator: ...
    def __next__(self) -> Frame: ...
    def __len__(self) -> int: ...

class Dataset:
    """An RGB-D dataset: len(), [i], iteration over Frame objects."""

    def __len__(self) -> int: ...
    def __getitem__(self, index: int) -> Frame: ...
    def __iter__(self) -> FrameIterator: ...
    def frames(
        self, *, start: int = 0, stride: int = 1, count: int = 0, prefetch: int = 3
    ) -> FrameIterator:
        """Frames start, start + stride, ... (at most count), decoded up to prefetch ahead."""
    @property
    def path(self) -> str: ...
    @property
    def root(self) -> str: ...
    @property
    def format(self) -> str: ...
    @property
    def K(self) -> npt.NDArray[np.float64]: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def depth_scale(self) -> float:
        """Depth units per metre of the raw 16-bit images (not of float depth files)."""
    @property
    def depth_encoding(self) -> str | None:
        """'16-bit PNG', '16-bit TIFF', '32-bit float TIFF', '32-bit float EXR', ...: float
        depth is metres (depth_scale does not apply); None for .sens and .bag datasets."""
    @property
    def has_color(self) -> bool: ...
    @property
    def intrinsics_source(self) -> str: ...
    @property
    def pose_source(self) -> str: ...
    @property
    def up(self) -> str: ...
    @property
    def up_source(self) -> str: ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def input_files(self) -> list[str]: ...

def open_dataset(
    path: PathLike,
    *,
    format: str = "auto",
    intrinsics: Sequence[float] | ArrayLike | None = None,
    depth_scale: float | None = None,
    max_pose_gap: float = 0.1,
) -> Dataset: ...

class FuseResult:
    """The fused volume and `voxplan fuse`'s counts and timings."""

    @property
    def volume(self) -> Volume: ...
    @property
    def frames(self) -> int: ...
    @property
    def frames_selected(self) -> int: ...
    @property
    def frames_skipped(self) -> int: ...
    @property
    def frames_lost(self) -> int: ...
    @property
    def blocks_refused(self) -> int: ...
    @property
    def loop_s(self) -> float: ...
    @property
    def fps(self) -> float: ...
    @property
    def frame_indices(self) -> npt.NDArray[np.int64]: ...
    @property
    def timestamps(self) -> npt.NDArray[np.float64]: ...
    @property
    def poses(self) -> npt.NDArray[np.float64]: ...
    @property
    def depth_paths(self) -> list[str]: ...
    @property
    def color_paths(self) -> list[str]: ...
    @property
    def load_ms(self) -> npt.NDArray[np.float64]: ...
    @property
    def integrate_ms(self) -> npt.NDArray[np.float64]: ...
    @property
    def frame_ms(self) -> npt.NDArray[np.float64]: ...
    @property
    def track_ms(self) -> npt.NDArray[np.float64]: ...
    @property
    def warnings(self) -> list[str]: ...
    def stats(self) -> dict[str, Any]: ...
    def write(
        self,
        *,
        mesh: PathLike | None = None,
        map: PathLike | None = None,
        trajectory: PathLike | None = None,
        frame_list: PathLike | None = None,
        mesh_min_weight: float = 0.5,
    ) -> Mesh | None: ...

def fuse(
    dataset: Dataset | PathLike,
    *,
    voxel_size: float = 0.01,
    trunc: float = 0.04,
    min_depth: float = 0.1,
    max_depth: float = 3.0,
    frames: int = 0,
    start: int = 0,
    stride: int = 1,
    weighting: str = "constant",
    kernel: str = "auto",
    max_weight: float = 64.0,
    max_memory: int | None = None,
    on_memory_limit: str = "drop",
    track: bool = False,
    photometric_weight: float = 0.0,
    threads: int | None = None,
    progress: Callable[[int, int], object] | None = None,
) -> FuseResult: ...

class ExploreResult:
    @property
    def metrics(self) -> dict[str, Any]: ...
    @property
    def summary(self) -> dict[str, Any]: ...
    @property
    def mesh(self) -> Mesh: ...
    @property
    def volume(self) -> Volume | None: ...
    @property
    def recon_volume(self) -> Volume | None: ...
    @property
    def out_dir(self) -> str | None: ...
    @property
    def terminated(self) -> str: ...
    @property
    def done_reason(self) -> str: ...
    @property
    def world_name(self) -> str: ...
    @property
    def planner(self) -> str: ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def planner_fault(self) -> str | None: ...

def explore(
    scene: str,
    planner: str,
    *,
    planner_config: dict[str, Any] | str | None = None,
    robots: int = 3,
    seed: int = 1,
    max_time: float = 1800.0,
    out_dir: PathLike | None = None,
    starts: Sequence[tuple[float, float]] | None = None,
    voxel_size: float = 0.05,
    recon_voxel_size: float | None = None,
    width: int = 320,
    height: int = 240,
    noise: bool = True,
    labels: bool = True,
    detector_noise: bool = True,
    color: bool = True,
    poses: str = "truth",
    profile: str | None = None,
    planning_interval: float = 15.0,
    plan_budget: float = 1.0,
    eval_samples: float = 100.0,
    threads: int | None = None,
    max_memory: int | None = None,
    progress: Callable[[dict[str, Any]], object] | None = None,
    robot_config: PathLike | None = None,
    fov_deg: float | None = None,
    max_range: float | None = None,
    clear_beyond_range: bool = True,
    odometry_noise: tuple[float, float] | None = None,
    planner_picture: bool = False,
    planner_hard_limit: float = 10.0,
    planner_hard_limit_min: float = 2.0,
    capture_hz: float | None = None,
    fuse_step: float = 0.25,
    fuse_step_deg: float = 15.0,
    progress_interval: float = 30.0,
    up: str = "z",
    scale: float = 1.0,
    floor_z: float | str = 0.0,
) -> ExploreResult:
    """One exploration experiment, as `voxplan explore` runs it; every CLI option is a keyword.

    robot_config: a robot JSON file over the profile's robot (explore/robot_config.h);
    fov_deg (strictly between 1 and 179), max_range (metres, above 0.1 and at most 100),
    capture_hz (0 to 60; 0: frames by displacement): the explorer camera, None keeping the
    profile's, the file's or the built-in robot's (90 degrees, 5 m, 0);
    clear_beyond_range: depth past max_range clears the free space before it;
    odometry_noise: (per metre, per radian), each in [0, 1], for poses='tracked';
    planner_picture: also write planner.png; planner_hard_limit (>= 1, times plan_budget) and
    planner_hard_limit_min (seconds > 0): past the larger a plan call is given up
    ('planner_hung'); fuse_step (m), fuse_step_deg, progress_interval (s), planning_interval,
    plan_budget, eval_samples: in [1e-06, 1e+06]; scene files: up 'z' or 'y', scale to metres,
    floor_z the floor height to move to 0 (within +-100 m, or 'auto'). Out of bounds: ValueError
    naming the argument.
    """

def planners() -> list[str]:
    """Planner plugins explore finds by name."""

def planner_search_path() -> list[str]:
    """The folders explore looks for planners in, in order."""
