/* The planner plugin boundary: the only header a planner plugin must include (C99 or C++).
 *
 * A planner is a shared library exporting one symbol, vp_planner_entry. The host dlopens it,
 * calls the entry with its ABI version and its function table (vp_host_api), and gets back the
 * plugin's table (vp_planner_api): create / plan / destroy. During plan() the plugin reads the
 * maps through the host table and an opaque vp_world handle, and writes its answer through the
 * same table into an opaque vp_plan_output builder. Nothing but C types crosses; no exception,
 * longjmp or C++ object may cross in either direction.
 *
 * Versioning (Vulkan-loader style negotiation, PostgreSQL-style refusal):
 *   - VP_PLANNER_ABI_VERSION is the major version. Host and plugin refuse each other on any
 *     difference; the host names both versions in its message.
 *   - Every struct handed across singly starts with uint32_t struct_size. The side that fills a
 *     struct reads struct_size first (the size of the other side's buffer), writes at most that
 *     many bytes, and sets struct_size to the bytes it wrote. A reader refuses a struct smaller
 *     than it needs (VP_ERROR_STRUCT_SIZE); fields may only be appended within a major version.
 *   - Records passed in arrays (vp_task, vp_ray, vp_surface_voxel, ...) carry no size: their
 *     layout is fixed for a major version.
 *
 * Growth within a major version (ABI 1.1 onwards):
 *   - New host functions come as extension tables: host->get_extension(name, min_version)
 *     returns a static table whose first fields are vp_extension_header, or NULL when the host
 *     has no such extension at that version. Names are "vp.<area>" with the version apart, e.g.
 *     get_extension(VP_EXT_OBJECTS, 1). A table only grows by appended fields; its version
 *     counts the additions.
 *   - get_extension itself was appended to vp_host_api in 1.1: a plugin that must also load on
 *     1.0 hosts checks VP_HOST_HAS(host, get_extension) first. Plugins built against the 1.0
 *     header never see it and keep working (tests/plugins/planners/abi1_0/ holds that header).
 *   - vp_mode_params and vp_robot gained appended fields in 1.1 (marked); a plugin built against
 *     1.0 sizes them smaller and gets the 1.0 prefix.
 *
 * Memory ownership:
 *   - Pointers the host returns (arrays, strings, rasters) are host-owned, read-only and valid
 *     until the current plan() returns; the plugin copies what it keeps.
 *   - Every output function copies its arguments before returning, so plugin memory never needs
 *     to outlive a call, and no plugin-allocated memory is ever freed by the host or vice versa.
 *   - vp_planner_api.name / .version point to static storage in the plugin.
 *
 * Threading: the host calls one planner instance from one thread at a time; the host functions
 * may only be called from inside create() / plan() on that thread.
 *
 * Units and frames: metres, radians, seconds; world frame Z up, the floor at floor_z_m; yaw from
 * world +x towards +y. The robot base is SE(2) (x, y, theta); its camera sits on a yaw joint
 * (camera_yaw relative to the base) with a pitch joint (positive looks up). */
#ifndef VOXPLAN_PLUGINS_PLANNER_API_H_
#define VOXPLAN_PLUGINS_PLANNER_API_H_

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define VP_PLANNER_ABI_VERSION 1u
/* The minor version: what this header appends to ABI 1 (see "Growth" above). */
#define VP_PLANNER_ABI_MINOR 1u
#define VP_PLANNER_ENTRY_SYMBOL "vp_planner_entry"

#if defined(_WIN32)
#define VP_PLANNER_EXPORT_SYMBOL __declspec(dllexport)
#else
#define VP_PLANNER_EXPORT_SYMBOL __attribute__((visibility("default")))
#endif

/* ---- Status codes: every fallible function returns one. ---------------------------------- */
typedef int32_t vp_status;
enum {
  VP_OK = 0,
  VP_ERROR_INVALID_ARGUMENT = 1, /* null pointer, NaN, index out of range, bad config */
  VP_ERROR_ABI_MISMATCH = 2,     /* the other side speaks another VP_PLANNER_ABI_VERSION */
  VP_ERROR_STRUCT_SIZE = 3,      /* a struct is smaller than this side needs */
  VP_ERROR_NOT_AVAILABLE = 4,    /* the world cannot answer this query (e.g. no objects) */
  VP_ERROR_LIMIT = 5,            /* an output grew past the host's limits */
  VP_ERROR_PLUGIN = 6,           /* the plugin failed (its message went to set_error) */
  VP_ERROR_INTERNAL = 7          /* the host failed */
};

/* ---- Opaque handles. ---------------------------------------------------------------------- */
typedef struct vp_world vp_world;             /* host: read-only maps for one plan() call */
typedef struct vp_plan_output vp_plan_output; /* host: output builder for one plan() call */
typedef struct vp_planner vp_planner;         /* plugin: one planner instance */

/* ---- Enumerations (int32_t / uint8_t on the wire). ----------------------------------------- */
enum { VP_VOXEL_UNOBSERVED = 0, VP_VOXEL_FREE = 1, VP_VOXEL_OCCUPIED = 2 };
/* Floor raster cells: frontier = free and 8-adjacent to unknown. */
enum { VP_FLOOR_UNKNOWN = 0, VP_FLOOR_FREE = 1, VP_FLOOR_FRONTIER = 2, VP_FLOOR_OBSTACLE = 3 };
/* Why plan() was called. */
enum {
  VP_EVENT_START = 0,       /* first call of a run */
  VP_EVENT_INTERVAL = 1,    /* the re-planning interval elapsed */
  VP_EVENT_ROBOT_IDLE = 2,  /* event_robot finished its queue (task-flow, Guo 2022) */
  VP_EVENT_TASK_FAILED = 3, /* event_robot could not reach or execute failed_task */
  VP_EVENT_WAKEUP = 4       /* the time the plugin asked for came (vp.schedule request_call) */
};
enum { VP_ROBOT_IDLE = 0, VP_ROBOT_EXECUTING = 1 };
/* Scanning modes (Guo 2022); a robot may have more, see vp_robot.mode_count. */
enum { VP_MODE_EXPLORER = 0, VP_MODE_RECONSTRUCTOR = 1 };
/* What a plan does to a robot's queue. APPEND is the default; REPLACE with no task stops it. */
enum { VP_TASKS_APPEND = 0, VP_TASKS_REPLACE = 1 };
enum { VP_RAY_MAX_RANGE = 0, VP_RAY_SURFACE = 1, VP_RAY_LEFT_MAP = 2 };
enum { VP_LOG_DEBUG = 0, VP_LOG_INFO = 1, VP_LOG_WARNING = 2, VP_LOG_ERROR = 3 };

/* ---- Records in arrays (fixed layout for a major version). --------------------------------- */
typedef struct vp_task {
  float x_m, y_m, theta_rad; /* base view pose, world */
  float camera_yaw_rad;      /* relative to the base */
  float camera_pitch_rad;    /* positive looks up */
  float dwell_s;             /* standing time at the view, >= 0 */
  int32_t mode;              /* VP_MODE_* the robot drives and scans in */
  uint32_t tag;              /* plugin's own id, echoed back in vp_call_info */
} vp_task;

typedef struct vp_ray {
  float origin[3];
  float direction[3]; /* unit length */
  float max_range_m;
} vp_ray;

typedef struct vp_ray_hit {
  float distance_m;   /* to the first occupied voxel, or where the ray stopped */
  float unobserved_m; /* length of unobserved voxels crossed before distance_m */
  int32_t result;     /* VP_RAY_* */
} vp_ray_hit;

typedef struct vp_surface_voxel {
  float position[3];
  float normal[3];   /* outward, unit; zero when unknown */
  float uncertainty; /* 0 (well observed) .. 1 (barely observed) */
  float weight;      /* fused TSDF weight */
  int32_t instance;  /* vp_instance.id it belongs to, -1 for none */
} vp_surface_voxel;

typedef struct vp_instance {
  uint32_t id;
  int32_t class_id;  /* -1 unknown */
  const char* label; /* host-owned, may be "" */
  float bbox_min[3], bbox_max[3];
  float completeness; /* 0..1 share of its surface observed well; < 0 unknown */
} vp_instance;

typedef struct vp_path_point {
  float x_m, y_m, theta_rad;
} vp_path_point;

/* Camera pose along a path (Xu 2017): world position and heading, t_s after the path starts.
 * The host aims the camera by yaw and pitch. Along a continuous path (vp.motion) on an arm mount
 * it also moves the camera to `position` (world metres): interpolated in t_s like the angles, at
 * the path's time for the distance driven (each piece's length at its speed, so by arc length: a
 * base slowed by turns does not leave the camera ahead), taken in the base frame of the pose
 * where each piece of motion ends, moved into the arm's workspace and followed at most at the
 * arm's speed; clampings are counted in metrics.json (camera_position_clamped_workspace,
 * _speed). A NaN position means none (the arm stays where it is around that sample); on a head,
 * or along a path that is not continuous, positions are ignored. Other non-finite numbers drop
 * the trajectory. */
typedef struct vp_camera_sample {
  float t_s;
  float position[3];
  float yaw_rad;   /* world yaw of the optical axis */
  float pitch_rad; /* positive looks up */
} vp_camera_sample;

/* ---- Structs filled singly (start with struct_size). --------------------------------------- */
typedef struct vp_call_info {
  uint32_t struct_size;
  int32_t event;        /* VP_EVENT_* */
  int32_t event_robot;  /* robot index the event concerns, -1 for none */
  uint32_t call_index;  /* 0 for the first plan() of a run */
  uint64_t seed;        /* per call; the same seed and world give the same plan */
  double time_budget_s; /* wall time plan() should take at most; <= 0 for none */
  double sim_time_s;    /* simulated time of the run */
  vp_task failed_task;  /* for VP_EVENT_TASK_FAILED */
} vp_call_info;

typedef struct vp_map_info {
  uint32_t struct_size;
  uint32_t reserved;
  uint64_t revision; /* changes whenever the maps change */
  float voxel_size_m;
  float floor_z_m;
  float bounds_min[3], bounds_max[3]; /* where tasks may lie */
} vp_map_info;

/* The 2-D floor raster. Cell (ix, iy), 0 <= ix < width, covers world xy
 * [origin + (ix, iy) * cell_size_m, + cell_size_m); arrays are row-major (iy, then ix). */
typedef struct vp_floor {
  uint32_t struct_size;
  int32_t width, height;
  float cell_size_m;
  float origin_x_m, origin_y_m;
  uint64_t revision;
  const uint8_t* cells;     /* VP_FLOOR_*, width * height */
  const float* clearance_m; /* distance from the cell centre to the nearest obstacle */
} vp_floor;

/* Where a mode's camera sits: at the base centre, on a head at a fixed height with a tilt, or
 * on an arm that sets its height and its offset from the base (Guo 2022's reconstructor). */
enum { VP_MOUNT_BASE = 0, VP_MOUNT_HEAD = 1, VP_MOUNT_ARM = 2 };

/* What a scanning mode changes (Guo 2022): speed and the camera's view. */
typedef struct vp_mode_params {
  uint32_t struct_size;
  float max_speed_mps;
  float max_turn_rate_radps;
  float horizontal_fov_rad, vertical_fov_rad;
  float min_range_m, max_range_m;
  int32_t image_width, image_height;
  float fx, fy, cx, cy; /* pinhole intrinsics of this mode, pixels */
  /* ---- 1.1: the camera's mount and timing. ---- */
  int32_t mount;             /* VP_MOUNT_* */
  float camera_height_min_m; /* optical centre above the floor; min == max: fixed */
  float camera_height_max_m;
  float reach_min_m, reach_max_m;     /* arm: horizontal offset from the base centre */
  float reach_half_angle_rad;         /* arm: offset bearing within +-this of the heading */
  float min_pitch_rad, max_pitch_rad; /* this mode's pitch range, positive looks up */
  float camera_speed_mps;             /* arm: how fast the camera moves on its mount */
  float camera_turn_rate_radps;       /* the slower of the camera's yaw and pitch joints */
  float capture_hz;                   /* frames per second; 0: captured by displacement */
  float switch_s;                     /* time to switch into this mode */
} vp_mode_params;

typedef struct vp_robot {
  uint32_t struct_size;
  uint32_t id;
  float x_m, y_m, theta_rad;
  float camera_yaw_rad, camera_pitch_rad;
  int32_t mode;          /* current VP_MODE_* */
  int32_t status;        /* VP_ROBOT_* */
  uint32_t queued_tasks; /* see get_robot_queue */
  uint32_t mode_count;   /* valid modes are 0 .. mode_count-1 */
  float radius_m;        /* round footprint */
  float camera_height_m; /* optical centre above the floor */
  float min_pitch_rad, max_pitch_rad;
  float camera_yaw_rate_radps, camera_pitch_rate_radps;
  /* ---- 1.1: what the robot has done so far in this run. ---- */
  float distance_m; /* driven by the base */
  float busy_s;     /* with a task in its queue */
  float idle_s;     /* with none */
} vp_robot;

/* The first fields of every extension table (see get_extension). */
typedef struct vp_extension_header {
  uint32_t struct_size; /* bytes of the whole table */
  uint32_t version;     /* >= the min_version asked for */
} vp_extension_header;

/* ---- The host's table: queries (valid during plan) and the output builder. ---------------- */
typedef struct vp_host_api {
  uint32_t struct_size;
  uint32_t abi_version;

  /* Call context. */
  vp_status (*get_call_info)(const vp_world* w, vp_call_info* out);
  double (*elapsed_s)(const vp_world* w); /* wall time since plan() was entered */
  void (*log)(const vp_world* w, int32_t level, const char* message);

  /* 3-D map. Out-of-map points are unobserved. Batches are the fast path. */
  vp_status (*get_map_info)(const vp_world* w, vp_map_info* out);
  vp_status (*voxel_states)(const vp_world* w, const float* points_xyz, uint64_t count,
                            uint8_t* out_states);
  vp_status (*raycast)(const vp_world* w, const vp_ray* rays, uint64_t count, vp_ray_hit* out_hits);
  /* Centres of free voxels next to unobserved ones. */
  vp_status (*get_frontier_voxels)(const vp_world* w, const float** out_xyz, uint64_t* out_count);
  vp_status (*get_surface_voxels)(const vp_world* w, const vp_surface_voxel** out,
                                  uint64_t* out_count);

  /* Floor raster and distances over it. A cell is traversable when it is free (or frontier) and
   * its clearance is at least min_clearance_m. Unreachable distances are +INFINITY. */
  vp_status (*get_floor)(const vp_world* w, vp_floor* out);
  /* Geodesic distance from source_xy to every cell (width * height floats). */
  vp_status (*geodesic_field)(const vp_world* w, const float source_xy[2], float min_clearance_m,
                              const float** out_field);
  /* Row-major count x count geodesic distances between the points. */
  vp_status (*distance_matrix)(const vp_world* w, const float* points_xy, uint32_t count,
                               float min_clearance_m, const float** out_matrix);
  /* Shortest traversable polyline (xy pairs) from -> to; VP_ERROR_NOT_AVAILABLE if none. */
  vp_status (*shortest_path)(const vp_world* w, const float from_xy[2], const float to_xy[2],
                             float min_clearance_m, const float** out_xy, uint32_t* out_count);

  /* Object instances (may be empty). */
  vp_status (*get_instances)(const vp_world* w, const vp_instance** out, uint32_t* out_count);

  /* Robots, indexed 0 .. robot_count-1 (index, not id, is what outputs refer to). */
  uint32_t (*robot_count)(const vp_world* w);
  vp_status (*get_robot)(const vp_world* w, uint32_t robot, vp_robot* out);
  vp_status (*get_robot_mode)(const vp_world* w, uint32_t robot, uint32_t mode,
                              vp_mode_params* out);
  /* Tasks queued and not yet finished, the current one first. */
  vp_status (*get_robot_queue)(const vp_world* w, uint32_t robot, const vp_task** out,
                               uint32_t* out_count);

  /* Output builder; each call copies its arguments. The host validates everything after plan()
   * returns and rejects (and logs) bad tasks one by one, keeping the rest. */
  vp_status (*set_task_policy)(vp_plan_output* o, uint32_t robot, int32_t policy);
  vp_status (*add_task)(vp_plan_output* o, uint32_t robot, const vp_task* task);
  /* Optional dense path for the robot through its new tasks, replacing any earlier one. A path
   * without tasks is followed on its own (field-guided motion, Xu 2017); the camera trajectory
   * then says where the camera looks along it. */
  vp_status (*set_path)(vp_plan_output* o, uint32_t robot, const vp_path_point* points,
                        uint32_t count);
  vp_status (*set_camera_trajectory)(vp_plan_output* o, uint32_t robot,
                                     const vp_camera_sample* samples, uint32_t count);
  /* Exploration finished: nothing left worth a task. */
  vp_status (*set_done)(vp_plan_output* o, int32_t done);
  /* Named numbers for logs and plots: "<stage>_ms", iterations, energies. */
  vp_status (*add_diagnostic)(vp_plan_output* o, const char* name, double value);
  /* Debug drawings for the viewer, grouped into named layers; rgba = 0xRRGGBBAA. */
  vp_status (*add_debug_points)(vp_plan_output* o, const char* layer, const float* xyz,
                                uint32_t count, uint32_t rgba);
  vp_status (*add_debug_polyline)(vp_plan_output* o, const char* layer, const float* xyz,
                                  uint32_t count, uint32_t rgba);
  vp_status (*add_debug_label)(vp_plan_output* o, const char* layer, const float xyz[3],
                               const char* text, uint32_t rgba);
  /* Why plan() is about to return an error. */
  vp_status (*set_error)(vp_plan_output* o, const char* message);

  /* ---- 1.1. ---- */
  /* The named extension table at min_version or later, or NULL (see "Growth" above). May be
   * called from create() and plan(); the table is static and valid while the plugin is loaded. */
  const vp_extension_header* (*get_extension)(const char* name, uint32_t min_version);
} vp_host_api;

/* ---- Extensions (get_extension). ------------------------------------------------------------ */

/* "vp.objects" version 1: per-object reads for object-centred planners (Guo 2022). */
#define VP_EXT_OBJECTS "vp.objects"
typedef struct vp_objects_ext {
  vp_extension_header header;
  /* The surface voxels of one instance (those get_surface_voxels gives with .instance == id), in
   * the same order; host-owned like them. An id with no voxels gives count 0. */
  vp_status (*get_instance_surface)(const vp_world* w, uint32_t id, const vp_surface_voxel** out,
                                    uint64_t* out_count);
} vp_objects_ext;

/* "vp.task" version 1: where the camera is at a task (Guo 2022's reconstruction views are 3-D
 * camera poses, T = (x, y, z, theta, phi)). The host validates each against the task's mode:
 * a camera height or offset only on an arm mount and inside its workspace (vp_mode_params'
 * camera_height_*, reach_*), the camera not in occupied or unknown space, the sweep within the
 * mode's pitch range. At the view the robot turns its base, moves the arm, aims (at look_at_W
 * when look_at, else the task's camera yaw and pitch), dwells, then steps the pitch through the
 * sweep with a frame at each step. */
#define VP_EXT_TASK "vp.task"
typedef struct vp_task_ext {
  uint32_t struct_size;
  float camera_height_m;    /* optical centre above the floor; NAN: the mount's rest height */
  float camera_offset_m[2]; /* base frame (forward, left) from the base centre; NAN: rest */
  int32_t look_at;          /* 1: aim at look_at_W while driving to and standing at the task */
  float look_at_W[3];
  float sweep_pitch_min_rad, sweep_pitch_max_rad; /* a tilt sweep after the dwell (the head's */
  float sweep_pitch_step_rad;                     /* "up and down", G L97); step 0: none */
  int32_t object_id; /* the vp_instance the view is for, -1 none (logged, not interpreted) */
} vp_task_ext;

typedef struct vp_task_ext_table {
  vp_extension_header header;
  /* add_task with the camera's part; ext may be NULL (the defaults, as add_task). */
  vp_status (*add_task_ext)(vp_plan_output* o, uint32_t robot, const vp_task* task,
                            const vp_task_ext* ext);
  /* The camera parts of get_robot_queue's tasks, in the same order, each ext->struct_size bytes
   * apart (tasks added without one carry the defaults). */
  vp_status (*get_robot_queue_ext)(const vp_world* w, uint32_t robot, const vp_task_ext** out,
                                   uint32_t* out_count);
} vp_task_ext_table;

/* "vp.motion" version 1: paths driven without stopping (Xu 2017's advected paths). A continuous
 * path without tasks is followed point to point with the base turning while it drives (each
 * piece takes the longer of its length at the point's speed and its turn at the mode's turn
 * rate), the camera aiming along the camera trajectory at the same time; it ends at its last
 * point without a final turn, dwell or capture stop, and the next path or task starts from there.
 * Frames are taken at the mode's capture rate while driving. */
#define VP_EXT_MOTION "vp.motion"
#define VP_PATH_CONTINUOUS 1u
typedef struct vp_path_ext {
  uint32_t struct_size;
  uint32_t flags;         /* VP_PATH_* */
  const float* speed_mps; /* per point (count of them), > 0; NULL: the mode's speed. Clamped to
                           * the mode's max_speed_mps. The speed of point i is that of the piece
                           * that ends there. */
} vp_path_ext;

typedef struct vp_motion_ext {
  vp_extension_header header;
  /* set_path with how to drive it; ext may be NULL (as set_path). */
  vp_status (*set_path_ext)(vp_plan_output* o, uint32_t robot, const vp_path_point* points,
                            uint32_t count, const vp_path_ext* ext);
} vp_motion_ext;

/* "vp.schedule" version 1: the plugin picks when it is called next (Xu 2017's sub-steps). */
#define VP_EXT_SCHEDULE "vp.schedule"
typedef struct vp_schedule_ext {
  vp_extension_header header;
  /* A call with event VP_EVENT_WAKEUP at the first loop step at or after t_s (the run clock of
   * vp_call_info.t_s), replacing an earlier request; other events may come first and do not
   * cancel it. Refused (logged, nothing scheduled) unless now < t_s <= now + 600 s. */
  vp_status (*request_call)(vp_plan_output* o, double t_s);
} vp_schedule_ext;

/* Whether a host table has a field: a plugin that also runs on older hosts of its major version
 * tests this before calling an appended function. */
#define VP_HOST_HAS(host, field)                                                          \
  ((host)->struct_size >= (uint32_t)((const char*)&(host)->field - (const char*)(host)) + \
                              (uint32_t)sizeof((host)->field))

/* ---- The plugin's table. ------------------------------------------------------------------- */
typedef struct vp_planner_api {
  uint32_t struct_size;
  uint32_t abi_version; /* the plugin's VP_PLANNER_ABI_VERSION; written even on refusal */
  const char* name;     /* static storage, e.g. "omt" */
  const char* version;  /* static storage, e.g. "1.0.0" */
  /* config_json: the planner's options as a JSON object text ("{}" for defaults). On failure
   * writes a NUL-terminated message of at most error_size bytes into error. */
  vp_status (*create)(const vp_host_api* host, const char* config_json, uint64_t seed,
                      vp_planner** out, char* error, uint32_t error_size);
  vp_status (*plan)(vp_planner* self, const vp_world* world, vp_plan_output* out);
  void (*destroy)(vp_planner* self);
} vp_planner_api;

/* The one exported symbol. The host sets out->struct_size to the size of its buffer before the
 * call. The plugin writes out->abi_version first; if host_abi_version differs from its own it
 * returns VP_ERROR_ABI_MISMATCH, and if host->struct_size is too small VP_ERROR_STRUCT_SIZE;
 * otherwise it fills at most out->struct_size bytes and returns VP_OK. */
typedef vp_status (*vp_planner_entry_fn)(uint32_t host_abi_version, const vp_host_api* host,
                                         vp_planner_api* out);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* VOXPLAN_PLUGINS_PLANNER_API_H_ */
