# Types of raypack's compiled module (python/module.cpp), for type checkers and editors. Every
# public name, method and property of the module is here with its parameters and defaults as
# bound; tests/python/test_stubs.py compares the two, so a binding added without its stub fails.

import math
import os
from typing import Any, Literal, TypedDict, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

__version__: str

_Path = str | os.PathLike[str]
_Vec3 = tuple[float, float, float] | list[float] | NDArray[Any]


class _Hits(TypedDict, total=False):
    """Closest hits, each of the rays' leading shape (...): a miss has prim_id 0xffffffff, t inf."""
    t: NDArray[np.float32]
    prim_id: NDArray[np.uint32]
    u: NDArray[np.float32]
    v: NDArray[np.float32]
    instance_id: NDArray[np.uint32]
    geometry_id: NDArray[np.uint32]  # not in read_hits' dict: a hit file has no scene
    ng: NDArray[np.float32]  # (..., 3); left out with normals=False


class _Rays(TypedDict):
    """Rays as the ray functions return them and intersect(**rays) takes them."""
    origins: NDArray[np.float32]
    directions: NDArray[np.float32]
    tnear: NDArray[np.float32]
    tfar: NDArray[np.float32]


class _TileRays(_Rays):
    """primary_rays(..., order='tiles'): flat, in the renderer's order, with each ray's pixel."""
    pixel: NDArray[np.uint32]


class _Aovs(TypedDict):
    """render(..., aovs=True): the image and the primary hit through each pixel centre."""
    rgb: NDArray[np.float32]  # (H, W, 3)
    depth: NDArray[np.float32]  # (H, W), inf on a miss
    normal: NDArray[np.float32]  # (H, W, 3)
    shading_normal: NDArray[np.float32]  # (H, W, 3)
    uv: NDArray[np.float32]  # (H, W, 2)
    prim_id: NDArray[np.uint32]  # (H, W)
    instance_id: NDArray[np.uint32]  # (H, W)
    geometry_id: NDArray[np.uint32]  # (H, W)


class _ClosestPoints(TypedDict):
    """Backend.closest_points: each of the points' leading shape (...); nothing found: prim_id 0xffffffff."""
    points: NDArray[np.float32]  # (..., 3), NaN where nothing is found
    distance: NDArray[np.float32]  # inf where nothing is found
    prim_id: NDArray[np.uint32]
    geometry_id: NDArray[np.uint32]
    instance_id: NDArray[np.uint32]
    uv: NDArray[np.float32]  # (..., 2)


class _AllHits(TypedDict):
    """Backend.all_hits: flat arrays, sorted by ray then t."""
    ray: NDArray[np.int64]  # the ray's index in C order over the leading shape
    t: NDArray[np.float32]
    prim_id: NDArray[np.uint32]
    geometry_id: NDArray[np.uint32]
    instance_id: NDArray[np.uint32]
    u: NDArray[np.float32]
    v: NDArray[np.float32]


class _UpdateReport(TypedDict):
    seconds: float
    refits: int
    rebuilds: int
    top: bool


class _BackendEntry(TypedDict):
    name: str
    description: str
    variants: list[str]
    coherent_methods: list[str]
    incoherent_methods: list[str]
    facts: dict[str, str]
    available: bool
    unavailable_reason: str


class Error(ValueError):
    """A failure the user can act on, with the one-line message of the raypack command."""


class Scene:
    """A scene: triangle meshes, instances, analytic primitives, materials, lights and a camera."""

    def __init__(self) -> None: ...
    # Geometries, numbered 0, 1, ... in the order they are added: each add_* returns its id.
    def add_triangles(self, vertices: ArrayLike, triangles: ArrayLike, *, copy: bool = True) -> int: ...
    def add_sphere(self, center: ArrayLike, radius: float) -> int: ...
    def add_plane(self, normal: ArrayLike, d: float) -> int: ...
    def add_polygon(self, vertices: ArrayLike) -> int: ...
    def add_quadric(self, coefficients: ArrayLike, clip_min: ArrayLike, clip_max: ArrayLike, *,
                    center: ArrayLike = (0.0, 0.0, 0.0)) -> int: ...
    @property
    def geometry_count(self) -> int: ...
    def set_mask(self, geometry: int, mask: int) -> None: ...
    def mask(self, geometry: int) -> int: ...
    @staticmethod
    def from_arrays(vertices: ArrayLike, indices: ArrayLike, *, spheres: ArrayLike | None = None,
                    planes: ArrayLike | None = None) -> Scene: ...
    @property
    def name(self) -> str: ...
    @property
    def prim_count(self) -> int: ...
    @property
    def triangle_count(self) -> int: ...
    @property
    def mesh_count(self) -> int: ...
    @property
    def instance_count(self) -> int: ...
    @property
    def version(self) -> int: ...
    @property
    def bounds(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]: ...
    def vertices(self, mesh: int) -> NDArray[np.float32]: ...
    def set_vertices(self, mesh: int, vertices: ArrayLike) -> None: ...
    def vertices_changed(self, mesh: int) -> None: ...
    def transform(self, instance: int) -> NDArray[np.float32]: ...
    def set_transform(self, instance: int, matrix: ArrayLike) -> None: ...
    def __repr__(self) -> str: ...


class Backend:
    """A backend built over a scene, safe to call from many threads at once."""

    def __init__(self, name: str, scene: Scene, variant: str = 'default', *, coherent_method: str = '',
                 incoherent_method: str = '', refit_limit: float = 1.25) -> None: ...
    def update(self) -> _UpdateReport: ...
    @property
    def current(self) -> bool: ...
    # Rays: origins and directions (..., 3), or one (..., 6) array of origin and direction with
    # directions left out; tnear and tfar broadcast to the leading shape (...) of every answer.
    # mask: each ray's 32 bits (or one for all), against Scene.mask of each geometry.
    def intersect(self, origins: ArrayLike, directions: ArrayLike | None = None, tnear: ArrayLike = 0.0,
                  tfar: ArrayLike = math.inf, coherent: bool = False, *, mask: ArrayLike | None = None,
                  invalid: str = 'warn', normals: bool = True, threads: int = 0) -> _Hits: ...
    def occluded(self, origins: ArrayLike, directions: ArrayLike | None = None, tnear: ArrayLike = 0.0,
                 tfar: ArrayLike = math.inf, coherent: bool = False, *, mask: ArrayLike | None = None,
                 invalid: str = 'warn', threads: int = 0) -> NDArray[np.bool_]: ...
    # Queries (python/queries.cpp, docs/queries.md). Points: (..., 3), the leading shape of every answer.
    def closest_points(self, points: ArrayLike, *, radius: float = math.inf, threads: int = 0) -> _ClosestPoints: ...
    def distance(self, points: ArrayLike, *, threads: int = 0) -> NDArray[np.float32]: ...
    def signed_distance(self, points: ArrayLike, *, threads: int = 0) -> NDArray[np.float32]: ...
    def inside(self, points: ArrayLike, *, threads: int = 0) -> NDArray[np.bool_]: ...
    def count_intersections(self, origins: ArrayLike, directions: ArrayLike | None = None, tnear: ArrayLike = 0.0,
                            tfar: ArrayLike = math.inf, *, mask: ArrayLike | None = None, invalid: str = 'warn',
                            threads: int = 0) -> NDArray[np.uint32]: ...
    def all_hits(self, origins: ArrayLike, directions: ArrayLike | None = None, tnear: ArrayLike = 0.0,
                 tfar: ArrayLike = math.inf, *, max_per_ray: int = 0, mask: ArrayLike | None = None,
                 invalid: str = 'warn', threads: int = 0) -> _AllHits: ...
    @property
    def name(self) -> str: ...
    @property
    def variant(self) -> str: ...
    @property
    def scene(self) -> Scene: ...
    @property
    def build_seconds(self) -> float: ...
    @property
    def bytes(self) -> int: ...
    @property
    def stats(self) -> dict[str, float]: ...
    def __repr__(self) -> str: ...


def load_scene(path: _Path) -> Scene: ...
def backends() -> list[_BackendEntry]: ...
@overload
def render(scene: Scene, backend: str | Backend = 'embree', variant: str = 'default', *, width: int = 1024,
           height: int = 768, spp: int = 1, sampler: str = 'stratified', seed: int = 0, max_depth: int = 3,
           eye: _Vec3 | None = None, look_at: _Vec3 | None = None, up: _Vec3 | None = None, fov: float | None = None,
           aovs: Literal[False] = False, threads: int = 0) -> NDArray[np.float32]: ...
@overload
def render(scene: Scene, backend: str | Backend = 'embree', variant: str = 'default', *, width: int = 1024,
           height: int = 768, spp: int = 1, sampler: str = 'stratified', seed: int = 0, max_depth: int = 3,
           eye: _Vec3 | None = None, look_at: _Vec3 | None = None, up: _Vec3 | None = None, fov: float | None = None,
           aovs: Literal[True], threads: int = 0) -> _Aovs: ...
def diff(scene: Scene, origins: ArrayLike, directions: ArrayLike, tnear: ArrayLike = 0.0, tfar: ArrayLike = math.inf, *,
         a: str | Backend = 'embree', b: str | Backend = 'simd', variant_a: str = 'default',
         variant_b: str = 'default', coherent: bool = False, reference: bool = True, tie_tolerance: float = 1e-06,
         t_tolerance: float = 0.0001, rays_label: str = 'numpy', threads: int = 0) -> dict[str, Any]: ...
@overload
def primary_rays(scene: Scene, width: int, height: int, *, order: Literal['image'] = 'image') -> _Rays: ...
@overload
def primary_rays(scene: Scene, width: int, height: int, *, order: Literal['tiles']) -> _TileRays: ...
def pinhole_rays(width: int, height: int, eye: _Vec3, look_at: _Vec3, up: _Vec3, fov: float) -> NDArray[np.float32]: ...
def random_rays(scene: Scene, count: int, seed: int = 1) -> _Rays: ...
def write_rays(path: _Path, origins: ArrayLike, directions: ArrayLike, tnear: ArrayLike = 0.0,
               tfar: ArrayLike = math.inf) -> None: ...
def read_rays(path: _Path) -> _Rays: ...
def write_image(path: _Path, image: ArrayLike) -> None: ...
def read_image(path: _Path) -> NDArray[np.float32]: ...
def read_hits(path: _Path) -> _Hits: ...
