"""voxplan from Python: CPU voxel-hashing TSDF fusion over numpy arrays.

The engine is C++ (the extension module ``voxplan._voxplan``); this package re-exports it::

    import voxplan
    dataset = voxplan.open_dataset("../shared/data/rgbd/iclnuim_office_traj0")
    result = voxplan.fuse(dataset, voxel_size=0.01)
    mesh = result.volume.extract_mesh()
    print(mesh.vertices.shape, mesh.triangles.shape)  # numpy arrays

Main names:

- ``Volume``: a TSDF volume; ``integrate(depth, color, K, T_W_C)``, ``extract_mesh()``,
  ``raycast(K, T_W_C, width, height)``, point queries (``tsdf``, ``interpolate``,
  ``voxel_values``, ``state``, ``gradient``), ``save(path)`` / ``Volume.load(path)``.
- ``open_dataset(path)``: the dataset readers (TUM, ICL-NUIM, Redwood, 7-Scenes, 3DMatch,
  Replica, ...) as a ``Dataset``, an iterable of ``Frame`` (depth, color, K, T_W_C, timestamp).
- ``fuse(dataset, ...)``: the pipeline ``voxplan fuse`` runs, same parameters, same bytes.
- ``Mesh``, ``read_mesh``, ``evaluate_mesh``: meshes as arrays, files, accuracy/completeness.
- ``explore(scene, planner, ...)``: an exploration experiment with a planner plugin.

Errors are Python exceptions carrying the library's message: ValueError (bad values, malformed
files), FileNotFoundError, OSError, RuntimeError; TypeError for arrays of the wrong dtype.
"""

from . import _voxplan
from ._voxplan import (
    FREE,
    OCCUPIED,
    RAY_FREE,
    RAY_HIT,
    RAY_UNOBSERVED,
    UNOBSERVED,
    Dataset,
    ExploreResult,
    Frame,
    FrameIterator,
    FuseResult,
    Mesh,
    RaycastImages,
    Volume,
    VoxplanWarning,
    evaluate_mesh,
    explore,
    fuse,
    get_threads,
    open_dataset,
    planner_search_path,
    planners,
    read_mesh,
    set_threads,
    simd_available,
)

__version__: str = _voxplan.__version__

__all__ = [
    "FREE",
    "OCCUPIED",
    "RAY_FREE",
    "RAY_HIT",
    "RAY_UNOBSERVED",
    "UNOBSERVED",
    "Dataset",
    "ExploreResult",
    "Frame",
    "FrameIterator",
    "FuseResult",
    "Mesh",
    "RaycastImages",
    "Volume",
    "VoxplanWarning",
    "evaluate_mesh",
    "explore",
    "fuse",
    "get_threads",
    "open_dataset",
    "planner_search_path",
    "planners",
    "read_mesh",
    "set_threads",
    "simd_available",
]

# Classes and functions say they come from `voxplan`, not from the extension module.
for _name in __all__:
    _obj = globals()[_name]
    if hasattr(_obj, "__module__") and getattr(_obj, "__module__", None) == _voxplan.__name__:
        try:
            _obj.__module__ = __name__
        except (AttributeError, TypeError):
            pass
del _name, _obj
