# Type stubs of the hapticfield module, generated from its bindings by scripts/make_stubs.py:
# do not edit. Regenerate after changing python/src (see python/README.md):
#   PYTHONPATH=build/python python3 scripts/make_stubs.py
"""hapticfield: haptic fields (tangible images, stochastic textures, friction, HaTT models, normals from a picture, contact composition, surfaces: height fields, meshes and pictures as reliefs felt through a proxy) built in Python and evaluated in C++, and a servo loop on a simulated or real arm. Units: [m], [m/s], [N], [s], [px]."""
import os
import typing
from typing import (Any, Callable, Dict, Iterable, Iterator, List, Optional, Sequence, Set, SupportsFloat, Tuple,
                    Union, overload)

import numpy
import numpy.typing

# A vector argument of 2 or 3 numbers: pybind11 converts any sequence of that length whose items have
# __float__ (a list, a tuple, numpy scalars) or a 1-D numpy array of floats or integers; another length
# raises TypeError. Results are lists.
_Vec2 = Union[Sequence[SupportsFloat], numpy.typing.NDArray[Union[numpy.floating[Any], numpy.integer[Any]]]]
_Vec3 = Union[Sequence[SupportsFloat], numpy.typing.NDArray[Union[numpy.floating[Any], numpy.integer[Any]]]]

__version__: str
has_mujoco: bool
has_video: bool


class DeformingSurface(Surface):
    """A triangle mesh whose vertices move while loops run (deforming_mesh()): the same triangles, new positions each set_vertices(); each field made on it has its own copy of the tree, refitted (not rebuilt) and swapped in without a lock at its next tick."""
    @property
    def frames(self) -> int: ...
    def set_vertices(self, vertices: numpy.typing.NDArray[Any], normals: Optional[numpy.typing.NDArray[Any]] = None) -> None:
        """New positions N x 3 [m] (one per vertex, finite) and optionally vertex normals N x 3; without them a mesh built with shade_normals and no normals gets new normals from its faces (as a mesh rebuilt on these vertices), otherwise keeps its normals. Refits every field's tree on the calling thread (the GIL released); ValueError for a wrong shape, a value not finite, or normals for a mesh without them."""


class Error(RuntimeError):
    ...


class Field:
    """A haptic field evaluated in C++: force [N] from probe state (position [m], velocity [m/s], normal force [N], surface normal)."""
    def __add__(self, arg0: Field) -> Field: ...
    def __repr__(self) -> str: ...
    @property
    def description(self) -> str: ...
    def force(self, position: _Vec3, velocity: _Vec3 = ..., normal_force: float = 0.0, surface_normal: _Vec3 = ...) -> numpy.typing.NDArray[numpy.float64]:
        """Force [N] (3 numbers) at one probe: position [m], velocity [m/s], normal force [N]."""
    def forces(self, positions: numpy.typing.ArrayLike, velocities: Optional[numpy.typing.ArrayLike] = None, normal_forces: Optional[numpy.typing.ArrayLike] = None, surface_normals: Optional[numpy.typing.ArrayLike] = None, period: float = 0.001, start_time: float = 0.0, out: Optional[numpy.typing.NDArray[Any]] = None) -> numpy.typing.NDArray[numpy.float64]:
        """Forces [N] (N x 3) at N probes: positions N x 3 [m], optional velocities N x 3 [m/s], normal forces N [N] and surface normals N x 3 (unit). The probes are evaluated in order as consecutive ticks period [s] apart, so stateful fields (filters, local spheres) advance. out: an N x 3 float64 array to write into (reused between calls). The GIL is released."""
    def reset(self) -> None:
        """Resets the state of stateful parts (filters, samplers)."""


class FileError(Error, OSError):
    ...


class HapticMedia:
    """An MPEG-I Haptics media (.hjif): perceptions, channels, bands, effects, keyframes. docs/hjif.md lists every field and whether it is rendered, kept or skipped."""
    def __repr__(self) -> str: ...
    @property
    def channels(self) -> List[Any]: ...
    @property
    def duration(self) -> float: ...
    @property
    def notes(self) -> List[str]: ...
    def render(self, rate: float) -> numpy.typing.NDArray[numpy.float64]:
        """every channel at rate [Hz]: a channels x samples float64 array (sample i at i / rate)"""
    @property
    def timescale(self) -> int: ...


class Material:
    """A material over a surface's uv (material(), load_haptic_material()): stiffness [N/m], damping [N s/m], static and dynamic friction, texture gain and a vibration id, each a constant or a picture read bilinearly (ids at the nearest texel). surface_contact(..., material=...) reads it at the touched uv every tick."""
    def __repr__(self) -> str: ...
    @property
    def description(self) -> str: ...
    def sample(self, u: float, v: float) -> Dict[str, Any]:
        """The material at uv (u right, v up) as a dict: stiffness, damping, static_friction, dynamic_friction, texture_gain, vibration."""


class MovingSurface(Surface):
    """A surface that moves while loops run (moving_surface()): each field made on it with surface_contact() takes the newest pose at every tick without a lock, the proxy carried with it (a shape moving into a still probe pushes it out, one moving away leaves it free) and the damping on the velocity relative to the touched surface's."""
    @property
    def moving_pose(self) -> Tuple[Any, ...]: ...
    def set_pose(self, pose: Optional[Pose] = None, velocity: _Vec3 = ..., angular_velocity: _Vec3 = ..., time: float = 0.0) -> None:
        """Where the surface's frame is (a Pose; None: where it was built) at time [s] on the loop's clock (Probe time: run_servo's from 0, forces()'s start_time + i period), moving at velocity [m/s] (of the frame's origin) and angular_velocity [rad/s] (about it), both in the device frame: each field's next tick takes it, extrapolated by the velocities from time for at most 0.1 s. Any thread; ValueError for an invalid pose or a value not finite."""


class MujocoScene(Field):
    """A MuJoCo scene felt through the servo loop (mujoco_scene()): a Field, and the simulator behind it. The scene's inspection (body, joint_position, step, ...) waits for no run: it raises RuntimeError while a run_servo loop or a forces() call uses the field."""
    def body(self, name: str) -> Dict[str, Any]:
        """A body's centre of mass position [m], its velocity [m/s] (device frame) and mass [kg] as a dict. ValueError for an unknown body."""
    def clear_fault(self) -> None:
        """Starts the scene again from its initial state after a fault; the force fades back in."""
    @property
    def events(self) -> Dict[str, Any]: ...
    @property
    def fault(self) -> str: ...
    @property
    def fault_message(self) -> str: ...
    def joint_position(self, name: str) -> float:
        """A joint's position (a hinge's angle [rad], a slide's [m]). ValueError for an unknown joint."""
    def load(self, path: object) -> None:
        """Changes the scene (MJCF): the new one fades in. FileError / Error as mujoco_scene; the old scene stays on failure."""
    @property
    def rate(self) -> float: ...
    @property
    def scene_energy(self) -> float: ...
    @property
    def simulated_time(self) -> float: ...
    def step(self, n: int = 1) -> bool:
        """Takes n simulator steps on the calling thread, with the newest handle sample (for forces() evaluations between steps; run_servo steps the scene by itself). False when the simulator is faulted."""
    @property
    def tool_radius(self) -> float: ...


class Pose:
    """Where a shape's own frame goes: world = rotation @ local + translation. Every shape constructor takes pose= (origin= is a pose without rotation)."""
    def __init__(self, rotation: Optional[object] = None, translation: _Vec3 = ...) -> None:
        """rotation: None (none), a 3 x 3 rotation matrix (its columns are the shape's x, y, z axes in the world; orthonormal with det +1 within 1e-6, then made exactly so) or a unit quaternion (w, x, y, z), scalar first (scipy's Rotation.as_quat() is scalar last: use as_matrix()); translation (x, y, z) [m]. ValueError for a reflection, a scale, a non-unit quaternion or anything not finite."""
    def __repr__(self) -> str: ...
    @staticmethod
    def about(axis: _Vec3, degrees: float, translation: _Vec3 = ...) -> Pose:
        """A turn of degrees about axis (right-handed, through the shape's own origin), then translation [m]."""
    @property
    def rotation(self) -> numpy.typing.NDArray[numpy.float64]: ...
    @property
    def translation(self) -> List[float]: ...


class ServoStop:
    """A token that stops run_servo from another thread: pass it as run_servo(..., stop=token) and call token.request() from any thread; the loop stops within a few ms (zero force, slew, disarm) and run_servo returns what it recorded with stop_reason 'requested'. A requested token stays requested, so it also ends any later run it is given before its first tick, until clear()."""
    def __init__(self) -> None: ...
    def clear(self) -> None:
        """Withdraws the request, so that the token can be given to a new run."""
    def request(self) -> None:
        """Asks every run given this token to stop (any thread; returns at once)."""
    @property
    def requested(self) -> bool: ...
    @property
    def running(self) -> bool: ...


class Surface:
    """A shape to touch (a height field, a mesh, a plane or a sphere), built once. surface_contact() makes it a field felt through a proxy; one surface may serve several fields (each proxy keeps its own state)."""
    def __repr__(self) -> str: ...
    @property
    def bounds(self) -> Optional[Tuple[List[float], List[float]]]: ...
    @property
    def description(self) -> str: ...
    @property
    def footprint(self) -> Optional[List[float]]: ...
    @property
    def kind(self) -> str: ...
    @property
    def normals(self) -> object: ...
    @property
    def pose(self) -> Pose: ...
    @property
    def samples(self) -> Optional[List[int]]: ...
    @property
    def triangles(self) -> Optional[int]: ...
    @property
    def warnings(self) -> List[str]: ...


class SurfaceField(Field):
    """A surface felt through a proxy (surface_contact()): a Field (forces, force, reset, run_servo, sums) that also tells, with contacts(), where the proxy is at each probe."""
    def contacts(self, positions: numpy.typing.ArrayLike, velocities: Optional[numpy.typing.ArrayLike] = None, period: float = 0.001, start_time: float = 0.0, paths: bool = False) -> Dict[str, Any]:
        """Evaluates the field at N probes in order as consecutive ticks (like forces()) and returns a dict of arrays: force N x 3 [N] (Fc + parts), contact_force N x 3 [N] (Fc alone), proxy N x 3 [m], normal N x 3 (unit, toward the user; zero when not touching), uv N x 2, depth N [m], primitive N (triangle or grid cell j (width - 1) + i; -1: none) and touching N (bool). paths=True adds path: a list of N arrays, each K x 3 [m], the way the proxy went in that tick (where it started, then the end of each straight piece, the last row where it stays; every piece swept against the shape), so a move that looks like a jump can be checked piece by piece. The GIL is released."""


class VideoField(Field):
    """A video felt as a field: a worker thread decodes and prepares the frames; the servo thread maps its loop time [s] to video time and blends the two frames that bracket it (never waiting, locking or allocating). Use it like any Field (forces, composition, run_servo); the probes' time is the loop time [s]."""
    def cuts(self) -> List[Any]:
        """The scene cuts found so far: a list of (frame, time [s])."""
    @property
    def duration(self) -> float: ...
    def error(self) -> str:
        """The worker's error message if it stopped on one, else ''."""
    @property
    def fps(self) -> float: ...
    @property
    def height(self) -> int: ...
    @property
    def lockstep(self) -> bool: ...
    def pause(self) -> None:
        """Holds the video time where it is."""
    def resume(self) -> None:
        """Lets the video time advance again."""
    def seek(self, t: float) -> None:
        """Jumps to video time t [s] (clamped to the video) at the next tick."""
    def set_rate(self, rate: float) -> None:
        """Video seconds per loop second, in (0, 16]."""
    def statistics(self) -> Dict[str, Any]:
        """Counters: prepared, dropped (preparation lagged), bad (undecodable), published (windows), cuts, stale_ticks (ticks whose window was past its 0.5 s hold: the worker late; the force fades out), ended, video_time_s (the servo thread's latest video time [s])."""
    def stop(self) -> None:
        """Stops the worker thread (the field keeps its last window)."""
    @property
    def width(self) -> int: ...


def _allocating_field() -> Field:
    """For tests only: a zero field that allocates and frees 64 bytes on every evaluation (the allocation proof in python/tests/test_alloc.py shows that it catches such a field)."""

def butterworth(signal: numpy.typing.ArrayLike, order: int = 4, band: str = 'low_pass', f1: float = 100.0, f2: float = 0.0, rate: float = 1000.0) -> numpy.typing.NDArray[numpy.float64]:
    """Filters a 1-D signal sampled at rate [Hz] with the library's Butterworth filter (order 1..8, bilinear transform, -3.01 dB at each edge): band low_pass|high_pass (cutoff f1 [Hz]) or band_pass (f1..f2 [Hz])."""

def clamp(field: Field, limit: float) -> Field:
    """|F| limited to limit [N] keeping the direction; a non-finite force becomes zero."""

def deforming_mesh(vertices: numpy.typing.NDArray[Any], faces: numpy.typing.NDArray[Any], uvs: Optional[numpy.typing.NDArray[Any]] = None, normals: Optional[numpy.typing.NDArray[Any]] = None, shade_normals: bool = True, max_nodes: int = 4096, huge_pages: bool = True) -> DeformingSurface:
    """A DeformingSurface: a triangle mesh from arrays as mesh_surface_from_arrays (vertices N x 3 [m] in the device frame, faces M x 3, optional uvs and normals), whose vertices set_vertices() moves while loops run. A deformation is not rigid: a touching proxy is put back in front of the face it touched; a surface that passes through the HIP within one tick leaves it inside, felt as nothing until it comes out. huge_pages as mesh_surface."""

def depth_map(path: object, pixel_size: float = 0.0001, metres_per_unit: float = 1e-06, blur: float = 0.0, origin: Optional[_Vec3] = None, pose: Optional[Pose] = None, shade_normals: bool = True, max_nodes: int = 4096) -> Surface:
    """A height field from a depth map: a one-channel 16-bit PNG or TIFF, or a 32-bit float TIFF; height = value x metres_per_unit [m] (16-bit in um: 1e-6; float in m: 1.0); pixel_size [m]; blur [px]; origin [m] or pose as for height_field. OpenEXR, 8-bit and colour files, NaN values and missing files raise FileError naming the file."""

def estimate_normal(corners: numpy.typing.ArrayLike, K: numpy.typing.ArrayLike, size: Optional[_Vec2] = None, refine: bool = True) -> Dict[str, Any]:
    """Normal of a rectangular face from its 4 image corners (4 x 2 [px], in order around the face) and the 3 x 3 camera matrix K [px] (Kim & Kwon 2013): the homography H = s K [r1 r2 t], the rotation R and n = R [0 0 1]^T (camera frame, toward the camera). size (W, H) [mm] if known, else the aspect is recovered. Returns a dict: normal, R, t, H, rms_reprojection_px, max_reprojection_px, width, height, aspect_recovered."""

def estimate_plane_normal(plane: numpy.typing.ArrayLike, pixels: numpy.typing.ArrayLike, K: numpy.typing.ArrayLike) -> Dict[str, Any]:
    """Pose and normal of a planar face from N >= 4 correspondences: plane points N x 2 (any unit, e.g. [mm]) and their pixels N x 2 [px]; K the 3 x 3 camera matrix [px]. Returns the same dict as estimate_normal()."""

def fir_low_pass(signal: numpy.typing.ArrayLike, cutoff: float, rate: float = 1000.0) -> numpy.typing.NDArray[numpy.float64]:
    """Filters a 1-D signal sampled at rate [Hz] with a 63-tap Hamming-windowed FIR low-pass at cutoff [Hz] (group delay 31 samples)."""

def force_map(image: object, mask: str = 'prewitt', size: Optional[int] = None, border: str = 'suspend', sigma: float = 0.0, gray: str = 'paper', channels: str = 'rgb', levels: Optional[float] = None) -> Tuple[Any, ...]:
    """The tangible-image force at every pixel centre: (fx, fy), two H x W float32 arrays, normalised (1 = a black/white edge), fy positive downward. image: a path (any format OpenCV reads; 16-bit files are scaled by 255/65535) or a numpy array, H x W gray or H x W x 3 / x 4 colour (alpha ignored). channels='rgb' (default: numpy, PIL, imageio order) or 'bgr' (cv2.imread order) names a colour array's channel order. White level: 255 for uint8 and other integer arrays, 65535 for uint16 (as 16-bit files); a float or bool array needs levels= (its white level: 1.0 for a picture in [0, 1], 255 for [0, 255]) and is refused without it; levels= overrides the white level of any array. Other options as tangible_forces()."""

def friction(coulomb: float = 0.0, viscous: float = 0.0, drag: float = 0.0, smoothing_speed: float = 0.002, scale_with_normal_force: bool = False, surface_normal: _Vec3 = ...) -> Field:
    """Friction Ff = -(c + b |v| + d |v|^2) v/|v| (tangential v on a surface): coulomb c [N] (or mu [-] with scale_with_normal_force), viscous b [N s/m], drag d [N s^2/m^2], smoothed stick below smoothing_speed [m/s]; surface_normal used when the probe has none (zero: 3D friction)."""

def hatt_model(path: str) -> Dict[str, Any]:
    """What a HaTT modelSet file holds: name, mu [-], sample_rate [Hz], ar_order, ma_order, models."""

def hatt_texture(path: str, effective_mass: float = 0.05, surface_normal: _Vec3 = ..., seed: int = 1, velocity_threshold: float = 0.001, friction: bool = True) -> Field:
    """A HaTT data-driven texture (a modelSet XML file of the Penn Haptic Texture Toolkit): AR/ARMA vibration models chosen by tangential speed and |Fc|, run at the model's own sample rate, acceleration [m/s^2] times effective_mass [kg] along surface_normal, plus mu |Fc| friction. Raises FileError for a bad file."""

def height_field(heights: numpy.typing.NDArray[Any], spacing: Union[float, _Vec2] = 0.0001, origin: Optional[_Vec3] = None, pose: Optional[Pose] = None, shade_normals: bool = True, max_nodes: int = 4096) -> Surface:
    """A height field z = h(x, y) [m] from a 2-D numpy array (float64 or float32 [m]): heights[j, i] is the height at x = i spacing_x, y = j spacing_y (np.meshgrid's 'xy' layout), spacing [m] one number or (spacing_x, spacing_y). Bilinear cells, solid below, felt from above (+z); covers [0, (W - 1) sx] x [0, (H - 1) sy] placed by pose (a Pose) or moved by origin (x, y, z) [m], and nothing beyond. At least 2 x 2 and at most 100 M samples (800 MB as float64, and about as much again for its tree), all finite (ValueError otherwise). A broadcast array (np.broadcast_to, zero strides) or one whose elements overlap in memory is refused before anything is allocated (its size says nothing of the memory a copy takes). shade_normals: blend the corners' normals (force shading); max_nodes: the budget of one query."""

def height_field_from_picture(image: object, pixel_size: float = 0.0001, mm_per_level: float = 0.01, blur: float = 0.0, dark_is_high: bool = False, gray: str = 'paper', channels: str = 'rgb', levels: Optional[float] = None, origin: Optional[_Vec3] = None, pose: Optional[Pose] = None, shade_normals: bool = True, max_nodes: int = 4096) -> Surface:
    """A relief from a picture (see below): height = gray level x mm_per_level [mm] (dark_is_high: 255 - level), after a Gaussian blur of blur [px]; pixel_size [m] between pixel centres; origin [m]: where its bottom-left corner (level 0) goes (or pose: a Pose). The picture's top row is at the largest y (x right, y up), so it reads as it is seen. A missing or undecodable file raises FileError (an OSError).

    image: a path (any format OpenCV reads; 16-bit files are scaled by 255/65535) or a numpy array, H x W gray or H x W x 3 / x 4 colour (alpha ignored). channels='rgb' (default: numpy, PIL, imageio order) or 'bgr' (cv2.imread order) names a colour array's channel order. White level: 255 for uint8 and other integer arrays, 65535 for uint16 (as 16-bit files); a float or bool array needs levels= (its white level: 1.0 for a picture in [0, 1], 255 for [0, 255]) and is refused without it; levels= overrides the white level of any array."""

def hjif_from_run(force: numpy.typing.ArrayLike, contact: Optional[numpy.typing.ArrayLike] = None, vibration: Optional[numpy.typing.ArrayLike] = None, servo_rate: float = 1000.0, vibration_rate: float = 8000.0, full_scale_force: float = 0.0) -> HapticMedia:
    """A recorded run as a HapticMedia: force (N x 3) [N] at servo_rate [Hz] as a Force perception, contact (N) |Fc| [N] as a Pressure perception, vibration (M) at vibration_rate [Hz] as a Vibrotactile perception; full_scale_force [N] (0: the largest recorded) is each force channel's gain."""

def lattice_texture(noise: str = 'gaussian', sigma: float = 1.0, seed: int = 1, grain: _Vec3 = ..., dim: int = 2, interpolation: str = 'linear', octaves: int = 0, h: float = 0.5, gain: float = 1.0, velocity_threshold: float = 0.001, scale_with_normal_force: bool = False, axes: _Vec3 = ...) -> Field:
    """A stochastic texture Ft sampled on a hashed noise lattice (Fritz & Barner 1996): noise gaussian|laplacian|uniform of standard deviation sigma, seed, lattice spacing grain [m] per axis, dim 2 (x, y) or 3, interpolation nearest|linear|cubic. octaves > 0 makes it fBm with self-similarity h (PSD ~ f^-(2h+1)). gain [N per texture unit] (or [N/N] with scale_with_normal_force: Ft proportional to |Fc|), velocity_threshold [m/s] (silent below it), axes: weights along (t1, t2, n) of the surface frame ((1, 1, 0): tangential only)."""

def list_devices() -> List[Tuple[str, bool, str]]:
    """Every arm family the device front door knows, one (family, present, line) tuple each: line says what strings it takes and that an arm is present, or why not (library not built in, no device found, permission denied). Probes only: nothing moves."""

def load_haptic_material(path: object, index: int = 0) -> Material:
    """The Material of haptic material `index` of a glTF file's MPEG_haptic_material extension (stiffness, friction and vibration ids; docs/materials.md lists every field). FileError for a file the reader refuses, ValueError for an index past the last."""

def load_hjif(path: str) -> HapticMedia:
    """Reads a .hjif file. Raises FileError (an OSError) naming the file and the JSON path for a missing file, text that is not JSON, a wrong type or a passed limit (64 MiB, nesting 32, 8,000,000 values, 4,000,000 elements per array, 1 MiB per string)."""

def local_sphere_texture(noise: str = 'gaussian', sigma: float = 1.0, seed: int = 1, radius: float = 0.0005, surface_normal: _Vec3 = ..., gain: float = 1.0, velocity_threshold: float = 0.001, scale_with_normal_force: bool = False, axes: _Vec3 = ...) -> Field:
    """A texture that draws a new noise sample each time the HIP leaves a ball of radius [m] (the local circle on a surface of unit surface_normal). gain [N per texture unit] (or [N/N] with scale_with_normal_force: Ft proportional to |Fc|), velocity_threshold [m/s] (silent below it), axes: weights along (t1, t2, n) of the surface frame ((1, 1, 0): tangential only)."""

def material(stiffness: Union[float, numpy.typing.ArrayLike] = 1500.0, damping: Union[float, numpy.typing.ArrayLike] = 0.0, static_friction: Union[float, numpy.typing.ArrayLike] = 0.0, dynamic_friction: Optional[Union[float, numpy.typing.ArrayLike]] = None, texture_gain: Union[float, numpy.typing.ArrayLike] = 1.0, vibration: Union[int, numpy.typing.ArrayLike] = 0, clamp: bool = False) -> Material:
    """A Material: each property a number or an H x W array over uv [0, 1]^2 (row 0 the picture's top, v = 1; bilinear between texel centres), repeated outside (clamp=True: edges extended). stiffness [N/m] > 0, damping [N s/m], friction and texture_gain >= 0 everywhere (ValueError otherwise); dynamic_friction defaults to static_friction; vibration: an id or an H x W integer array of ids for the vibration tap."""

def mesh_surface(path: object, scale: float = 1.0, origin: Optional[_Vec3] = None, pose: Optional[Pose] = None, shade_normals: bool = True, max_nodes: int = 4096, max_triangles: int = 20000000, huge_pages: bool = True) -> Surface:
    """A triangle mesh from a file (.stl, .obj, .gltf, .glb by extension); scale: the file's unit in metres (0.001 for millimetres; glTF is in metres), then placed by pose (a Pose) or moved by origin [m]. shade_normals (default, as in feel_shape, servo_demo and the viewer): force shading with the file's vertex normals, or normals computed from the faces where it has none; False: face normals (flat facets). Each triangle is felt from the side its normal points to. A mesh with no triangle of any area raises FileError. A missing, malformed or oversized file raises FileError naming it; Surface.warnings lists what was accepted but may surprise. huge_pages (default): the mesh's tree and arrays on 2 MB pages where the kernel allows (a hand's first pass over a part of a large mesh is faster); False: the system's own pages. The forces are the same either way."""

def mesh_surface_from_arrays(vertices: numpy.typing.NDArray[Any], faces: numpy.typing.NDArray[Any], uvs: Optional[numpy.typing.NDArray[Any]] = None, normals: Optional[numpy.typing.NDArray[Any]] = None, pose: Optional[Pose] = None, origin: Optional[_Vec3] = None, shade_normals: bool = True, max_nodes: int = 4096, max_triangles: int = 20000000, huge_pages: bool = True) -> Surface:
    """A triangle mesh from numpy arrays: vertices N x 3 [m] (real), faces M x 3 vertex indices from 0 (integer dtype; each triangle felt from the side its counter-clockwise winding faces), optional uvs N x 2 and normals N x 3 (per vertex; normalised). Placed by pose (a Pose) or origin [m]. shade_normals as mesh_surface: the given normals, else normals from the faces; False: face normals. At most max_triangles faces (default and limit 20 M) and 3 x max_triangles vertices. ValueError naming the array and row for a wrong shape or dtype, an index out of range, a value not finite, a zero normal, no face, or faces that all have zero area; a broadcast (zero-stride) or overlapping array is refused before anything is allocated. huge_pages as mesh_surface."""

def moving_surface(surface: Surface, pose: Optional[Pose] = None, velocity: _Vec3 = ..., angular_velocity: _Vec3 = ..., time: float = 0.0) -> MovingSurface:
    """A MovingSurface: surface (placed by its own pose within the moving frame) moved by pose (a Pose; None: the identity) at velocity [m/s] and angular_velocity [rad/s] from time [s] on the loop's clock; set_pose() moves it while loops run."""

def mujoco_scene(path: object, rate: float = 500.0, mode: str = 'local_model', stiffness: float = 1000.0, damping: Optional[float] = None, static_friction: float = 0.0, dynamic_friction: float = 0.0, coupling_stiffness: float = 200.0, coupling_damping: Optional[float] = None, tool_body: str = 'tool', scene_origin: _Vec3 = ..., detect_distance: float = 0.01, stall_time: float = 0.05, fade_time: float = 0.2) -> MujocoScene:
    """A MuJoCo scene (an MJCF file with a tool: a free body named tool_body with a sphere geom, the tool's radius) felt as a field (a MujocoScene): the simulator steps at rate [Hz] (10..10000) on a thread of its own, never on the servo loop's. In run_servo on the virtual clock (the default for the simulated arm) it steps in lockstep with the loop's time (step j at j / rate, the loop waiting for it), so a run is the same on any machine; on the wall clock it steps in real time. mode: local_model (default: the touched surfaces as planes rendered at the loop's rate,  stiffness [N/m] and damping [N s/m] on them, Coulomb friction 0 <= dynamic_friction <= static_friction on each: a proxy on the plane sticks in the static cone, slides in the dynamic one) or virtual_coupling (a spring-damper coupling_stiffness [N/m], coupling_damping [N s/m] to the simulated tool). A damping left None is the least Adams & Hannaford's bound allows, T K / 2 at T = 1 / rate (the coupling's at least 2 N s/m); a smaller one is a ValueError. Device frame (y up) to MuJoCo's z up: (x, y, z) -> (x, -z, y), plus scene_origin [m] (scene frame). detect_distance [m]: contacts published within it; stall_time [s]: no step for this long gives zero force; fade_time [s]: the force fades in after a change or a fault. A missing file or MJCF MuJoCo refuses raises FileError, a scene without a usable tool Error."""

def noise(kind: str = 'gaussian', sigma: float = 1.0, seed: int = 1, n: int = 1000) -> numpy.typing.NDArray[numpy.float64]:
    """n x 3 samples of the library's repeatable noise (gaussian|laplacian|uniform, standard deviation sigma) at lattice points (i, 0, 0), i = 0..n-1: a pure function of (seed, point)."""

def normal_field(width: int, height: int, faces: Sequence[Tuple[numpy.typing.ArrayLike, _Vec3]], mode: str = 'along_motion', max_force: float = 0.6, speed_threshold: float = 0.005, shading_cell_px: float = 0.0, px_per_mm: Optional[float] = None) -> Field:
    """Normals from a picture as a field (Kim & Kwon 2013): faces a list of (polygon K x 2 [px], unit normal (camera frame, n_z <= 0)); F = max_force (n . m) m along the HIP's motion m (mode along_motion) or max_force (n_x, n_y) (gradient). max_force [N], speed_threshold [m/s], shading_cell_px [px] (0: flat faces); picture centred at px_per_mm [px/mm] (default 6.4)."""

def on_surface(field: Field, scale: Union[float, _Vec2] = 1.0, offset: Union[float, _Vec2] = 0.0) -> Field:
    """A field laid on the touched surface by uv (a part of surface_contact()): evaluated at the flat position offset + scale * uv [m] (scale [m per uv unit] and offset [m], each one number or a pair), with the velocity in the tangent frame; its force comes back along the surface's tangent, bitangent and normal. A tangible image, a texture, friction or a normals field so pushes along a curved surface. No force without a tangent frame. The field is shared, not copied."""

def picture_relief(image: object, mm_per_level: float = 0.01, width_m: float = 0.1, blur: float = 0.0, dark_is_high: bool = False, stiffness: float = 1500.0, damping: float = 0.0, static_friction: float = 0.0, dynamic_friction: float = 0.0, texture_gain: float = 1.0, mask: str = 'prewitt', size: Optional[int] = None, border: str = 'suspend', sigma: float = 0.0, gray: str = 'paper', channels: str = 'rgb', levels: Optional[float] = None, radius: float = 0.0) -> SurfaceField:
    """A picture felt as a relief in one line (see below): its gray levels are heights (level x mm_per_level [mm], dark_is_high: 255 - level; blur [px] on the heights only) under the proxy (stiffness [N/m], damping [N s/m], static/dynamic friction), and its tangible-image forces (texture_gain [N] at a black/white edge; 0: the relief alone; mask, size, border, sigma as tangible_field) are laid on the relief in its tangent plane. The picture spans width_m [m] from the first to the last pixel centre, its bottom-left pixel at the origin, x right, y up the picture, z toward the user. radius: the tool's radius [m] in [0, 0.05] (0: a point; > 0 a ball, resting radius above the relief whose cells are two flat triangles each for it). Returns a SurfaceField.

    image: a path (any format OpenCV reads; 16-bit files are scaled by 255/65535) or a numpy array, H x W gray or H x W x 3 / x 4 colour (alpha ignored). channels='rgb' (default: numpy, PIL, imageio order) or 'bgr' (cv2.imread order) names a colour array's channel order. White level: 255 for uint8 and other integer arrays, 65535 for uint16 (as 16-bit files); a float or bool array needs levels= (its white level: 1.0 for a picture in [0, 1], 255 for [0, 255]) and is refused without it; levels= overrides the white level of any array."""

def plane_contact(parts: Sequence[Field] = ..., point: _Vec3 = ..., normal: _Vec3 = ..., stiffness: float = 1500.0, damping: float = 0.0) -> Field:
    """F = Fc + parts: a penalty plane through point [m] with unit normal (toward the user), stiffness [N/m] and damping [N s/m] gives Fc; while touching, the parts see |Fc| [N] and the plane's normal of the same tick."""

def plane_surface(point: _Vec3 = ..., normal: _Vec3 = ..., size: float = 0.01, pose: Optional[Pose] = None) -> Surface:
    """The solid half-space behind a plane through point [m] with unit normal (toward the user), both in the frame that pose (a Pose; default none) places; uv are metres along the plane; size [m]: the length its tolerances scale with."""

def relief_map(image: object, pixel_size: float = 0.0001, mm_per_level: float = 0.01, blur: float = 0.0, dark_is_high: bool = False, gray: str = 'paper', channels: str = 'rgb', levels: Optional[float] = None) -> Tuple[Any, ...]:
    """The relief of a picture as arrays, as height_field_from_picture() builds it: (heights, normals), H x W heights [m] (gray level x mm_per_level [mm], dark_is_high: 255 - level, after a Gaussian blur of blur [px]) and H x W x 3 unit normals (central differences over pixel_size [m], one-sided at the border; x right, y up the picture, z toward the user), row 0 the picture's top row. A missing or undecodable file, or one under 2 x 2 px, raises FileError.

    image: a path (any format OpenCV reads; 16-bit files are scaled by 255/65535) or a numpy array, H x W gray or H x W x 3 / x 4 colour (alpha ignored). channels='rgb' (default: numpy, PIL, imageio order) or 'bgr' (cv2.imread order) names a colour array's channel order. White level: 255 for uint8 and other integer arrays, 65535 for uint16 (as 16-bit files); a float or bool array needs levels= (its white level: 1.0 for a picture in [0, 1], 255 for [0, 255]) and is refused without it; levels= overrides the white level of any array."""

def render_hjif(path: str, rate: float = 8000.0) -> numpy.typing.NDArray[numpy.float64]:
    """Renders every channel of a .hjif file at rate [Hz]: a channels x samples float64 array, channels in file order (as hjif_render's WAV)."""

def run_servo(field: Field, seconds: float = 1.0, rate: float = 1000.0, device: str = 'sim', hand: str = 'raster', hand_centre: _Vec3 = ..., hand_size: float = 0.06, hand_speed: float = 0.06, realtime: str = 'off', confirm_hardware: bool = False, clock: Optional[str] = None, stop: Optional[ServoStop] = None, anticipate: bool = True) -> Dict[str, Any]:
    """Runs the 1 kHz servo loop (absolute deadlines, the safety chain) on a field for seconds [s] at rate [Hz] and returns a dict: statistics (rate, periods [s], deadlines, safety events, peak force [N], look_aheads and look_aheads_late: ticks anticipated, and run past their deadline), trace (one row a tick: t [s], position N x 3 [m], force N x 3 [N] as that tick commanded after the safety chain, homed and armed N booleans: the tick's device state, False before homing / arming), period_histogram (counts per histogram_bin_s), stop_reason, final_force (the last force written to the arm [N], the stop's zero after a stop), and loop_allocations / loop_frees (malloc / free calls on this thread while the loop ran, when an allocation counter is preloaded as in python/tests/test_alloc.py; None otherwise). device: any string the device front door opens (list_devices() names them and says which are present): sim, woody:GEN[:PRESET]:sim and inverse3:sim are simulated arms, held by a scripted hand (raster|circle|hold around hand_centre [m], hand_size [m], hand_speed [m/s]); hid[:VID:PID], serial:PATH, woody:GEN[:PRESET][:PATH] and inverse3:PATH are real arms (they need confirm_hardware=True). clock virtual (the default for a simulated arm): the loop runs on simulated time as fast as the CPU allows, with the same ticks, safety chain and trace as in real time, so a run renders the same forces on any machine (its timing statistics are nominal: every period exact, compute time 0); wall (the default for a real arm, the only choice there): real time, for timing studies and live interaction. realtime off|best_effort|enforce (SCHED_FIFO; wall clock only). The loop runs on a thread of its own, evaluating the field in C++, never taking the GIL; the calling thread waits with the GIL released. stop: a ServoStop token another thread can request() to end the run (stop_reason 'requested'). Ctrl-C (any exception a signal handler raises) stops the loop within a few ms with zero force and is then raised, the result attached as its `result` attribute (stop_reason 'interrupted'): `except KeyboardInterrupt as e: run = e.result`. anticipate (default True): before each deadline a shape's proxy runs the coming tick on a copy, on the last position moved one period by its velocity, so that the part of the mesh it reads is in cache when the tick runs (LoopConfig::anticipate); the forces are the same without it, only the tick's time differs."""

def save_haptic_material(base: object, out: object, stiffness: Optional[Tuple[numpy.typing.NDArray[Any], float, float]] = None, friction: Optional[Tuple[numpy.typing.NDArray[Any], float, float]] = None, texture: Optional[Tuple[numpy.typing.NDArray[Any], float]] = None, vibration: Optional[numpy.typing.NDArray[Any]] = None, name: str = '') -> None:
    """Writes the glTF `base` again as `out` (.gltf self-contained, or .glb) with an MPEG_haptic_material for every mesh: stiffness and friction as (levels, low, high) with levels an H x W uint8 or uint16 array (black = low, white = high), texture as (levels, force [N] at a black/white edge), vibration an id array. The extension is in extensionsUsed only: any glTF viewer still opens the model."""

def save_hjif(media: HapticMedia, path: str) -> None:
    """Writes the media as .hjif, laid out as the MPEG reference software writes and reads it."""

def scale(field: Field, factor: float) -> Field:
    """F = factor x field [N]."""

def sphere_contact(parts: Sequence[Field] = ..., centre: _Vec3 = ..., radius: float = 0.02, stiffness: float = 1500.0, damping: float = 0.0) -> Field:
    """F = Fc + parts on a solid penalty sphere: centre [m], radius [m], stiffness [N/m], damping [N s/m]."""

def sphere_surface(centre: _Vec3 = ..., radius: float = 0.02, pose: Optional[Pose] = None) -> Surface:
    """A solid ball: centre [m] (in the frame that pose places; default none), radius [m]. uv: u = longitude / 2 pi + 1/2, v = latitude / pi + 1/2, about the ball's own z axis (turned by pose)."""

def sum(fields: Sequence[Field]) -> Field:
    """F = sum of the fields' forces [N]. The parts are shared, not copied."""

def surface_contact(surface: Surface, parts: Sequence[Field] = ..., stiffness: float = 1500.0, damping: float = 0.0, static_friction: float = 0.0, dynamic_friction: float = 0.0, offset: float = 1e-06, radius: float = 0.0, material: Optional[Material] = None, stick_first: bool = True, tick_node_budget: int = 8192) -> SurfaceField:
    """F = Fc + parts on a surface, felt through a proxy (god-object, Zilles & Salisbury 1995): Fc = max(0, k d - b v.n) n + friction, stiffness k [N/m], damping b [N s/m] on the normal velocity, the friction cone static_friction >= dynamic_friction >= 0; offset: the proxy's lift relative to a primitive's size. radius [m], in [0, 0.05]: the tool's radius; 0 (default) a point, > 0 a ball centred on the HIP, swept against the shape: it rests radius above a face (proxy = the ball's centre, d = radius - the HIP's height) and does not enter a crack narrower than 2 radius. Every surface takes a ball (a height field's cells are two flat triangles each for it). While touching, the parts see |Fc| [N], the normal, and the touched point's uv and tangent frame: lay a field on the surface with on_surface(). material (a Material: material(), load_haptic_material()): the stiffness, damping and friction read at the touched uv every tick instead of the numbers, the parts scaled by its texture gain there. stick_first (default True): with friction, the friction cone is tested first on last tick's planes, so a stuck proxy makes no swept query (False: the full tick, the frictionless proxy found first; the two agree on a flat face and differ a little near the cone's edge on a curved one). tick_node_budget: the most tree nodes all of one tick's queries may visit together; past it the proxy stays where it has got to that tick (0: it never moves, so it never touches). Returns a SurfaceField (contacts() tells where the proxy is)."""

def tangible_field(image: object, mask: str = 'prewitt', size: Optional[int] = None, border: str = 'suspend', sigma: float = 0.0, gain: float = 1.0, px_per_mm: Optional[float] = None, workspace_mm: Optional[float] = None, gray: str = 'paper', channels: str = 'rgb', levels: Optional[float] = None) -> Field:
    """A tangible-image field in the device's x-y plane: the picture centred on the origin at px_per_mm [px/mm] (default 6.4, Kim & Kwon's) or fitted so its longer side spans workspace_mm [mm]; gain [N] at a black/white edge. Device frame x right, y up. image: a path (any format OpenCV reads; 16-bit files are scaled by 255/65535) or a numpy array, H x W gray or H x W x 3 / x 4 colour (alpha ignored). channels='rgb' (default: numpy, PIL, imageio order) or 'bgr' (cv2.imread order) names a colour array's channel order. White level: 255 for uint8 and other integer arrays, 65535 for uint16 (as 16-bit files); a float or bool array needs levels= (its white level: 1.0 for a picture in [0, 1], 255 for [0, 255]) and is refused without it; levels= overrides the white level of any array. Other options as tangible_forces()."""

def tangible_forces(image: object, xy: numpy.typing.ArrayLike, mask: str = 'prewitt', size: Optional[int] = None, border: str = 'suspend', sigma: float = 0.0, gray: str = 'paper', channels: str = 'rgb', levels: Optional[float] = None) -> numpy.typing.NDArray[numpy.float64]:
    """Tangible-image forces (Vasudevan & Manivannan 2008) at N pixel positions. image: a path (any format OpenCV reads; 16-bit files are scaled by 255/65535) or a numpy array, H x W gray or H x W x 3 / x 4 colour (alpha ignored). channels='rgb' (default: numpy, PIL, imageio order) or 'bgr' (cv2.imread order) names a colour array's channel order. White level: 255 for uint8 and other integer arrays, 65535 for uint16 (as 16-bit files); a float or bool array needs levels= (its white level: 1.0 for a picture in [0, 1], 255 for [0, 255]) and is refused without it; levels= overrides the white level of any array. xy N x 2 [px] (x right, y down, integer = pixel centre). Returns N x 2: the normalised force (1 = a black/white edge) before any gain, fy positive downward; the same numbers as `tangible_image --probes`. mask prewitt|sobel|scharr|roberts|gauss|emboss, size [px] (default 17; sobel/scharr 3, roberts 2), border suspend|clamp|reflect|fade, sigma [px] (gauss; 0: size/6), gray paper|bt601 (luma weights)."""

def temporal_texture(noise: str = 'gaussian', sigma: float = 1.0, seed: int = 1, order: int = 4, band: str = 'band_pass', f1: float = 30.0, f2: float = 120.0, rate: float = 1000.0, gain: float = 1.0, velocity_threshold: float = 0.001, scale_with_normal_force: bool = False, axes: _Vec3 = ...) -> Field:
    """A fresh noise sample every tick, filtered per component by a Butterworth filter of order 1..8 (0: unfiltered), band low_pass|high_pass (cutoff f1 [Hz]) or band_pass (f1..f2 [Hz]) designed for the servo rate [Hz]. gain [N per texture unit] (or [N/N] with scale_with_normal_force: Ft proportional to |Fc|), velocity_threshold [m/s] (silent below it), axes: weights along (t1, t2, n) of the surface frame ((1, 1, 0): tangential only)."""

def tick_budget(field: Field, ticks: int = 20000, speed: float = 0.1, radius: float = 0.02, depth: float = 0.002, period: float = 0.001, share: float = 0.25) -> Dict[str, Any]:
    """Does the field fit in a servo tick? Runs it over a scripted path (a circle of radius [m] at speed [m/s], pressed depth [m] into the plane z = 0, ticks period [s] apart) and returns a dict: mean_ns, p50_ns, p99_ns, p999_ns, worst_ns, allocations and allocations_per_tick (None unless the allocation counter is preloaded), exceptions, fits_1khz, fits_10khz (p99 at most share of the period, no allocation, no exception) and summary (the same in words). The GIL is released while it runs."""

def uv_relief(heights: Union[float, numpy.typing.ArrayLike], stiffness: float = 1500.0, metres_per_uv: float = 1.0, clamp: bool = False) -> Field:
    """A relief of small height over a surface's uv, felt by haptic bump mapping (Ho, Basdogan & Srinivasan 1999): heights [m] >= 0, a number or an H x W array over uv as material(); lay it with on_surface() as a part of surface_contact() of the same stiffness [N/m]. While touching it adds k h(uv) along the normal and -(|Fc| + k h) grad h along the surface, grad h in m per m with metres_per_uv [m] the surface's size of one uv unit. ValueError for a negative height or a stiffness or scale not finite and > 0."""

def video_cuts(path: object) -> List[Any]:
    """The scene cuts of a video: a list of (frame, time [s]), frame the first of the new scene, as `tangible_video --cuts` writes them."""

def video_field(path: object, mask: str = 'prewitt', size: Optional[int] = None, border: str = 'suspend', denoise: str = 'temporal', fade: float = 0.1, gain: float = 1.0, rate: float = 1.0, start: float = 0.0, loop: bool = False, px_per_mm: Optional[float] = None, workspace_mm: Optional[float] = None) -> VideoField:
    """A VideoField in the device's x-y plane: the video centred on the origin at px_per_mm [px/mm] (default 6.4) or fitted so its longer side spans workspace_mm [mm]; gain [N] at a black/white edge; playback rate (video s per loop s, (0, 16]), start [s of video time], loop. mask, size, border, denoise, fade as video_forces(). Device frame x right, y up."""

def video_forces(path: object, t: numpy.typing.ArrayLike, xy: numpy.typing.ArrayLike, mask: str = 'prewitt', size: Optional[int] = None, border: str = 'suspend', denoise: str = 'temporal', fade: float = 0.1) -> numpy.typing.NDArray[numpy.float64]:
    """Tangible-video forces offline (the same numbers as `tangible_video --probes`, bit for bit): N video times t [s] (frame k at k / fps; any order: they are evaluated sorted, stable, and returned in the input order) and N x 2 pixel positions xy [px] (x right, y down, integer = pixel centre) -> N x 2 normalised forces (1 = a black/white edge), fy down, blended between frames and faded across scene cuts. path: a video file or an image sequence pattern such as 'frames/%04d.png' (25 frames/s). mask, size [px], border as tangible_forces(); denoise none|temporal|spatial|both; fade [s] across a cut, [0, 10]. The frames are decoded and prepared on the calling thread, the GIL released."""

def zero() -> Field:
    """A field that is always zero."""
